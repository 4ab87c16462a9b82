//! `swr`: CPU software occlusion culling, the family Intel's Masked
//! Software Occlusion Culling (MOC: Hasselgren, Andersson, Akenine-Möller,
//! HPG 2016; O3DE), Godot 4's occlusion culling and Umbra belong to:
//! occluders are rasterised on the CPU into a small depth buffer and boxes
//! tested against it, so culling never waits for the GPU and reads nothing
//! back. A frame (`frame` below, step by step) takes last frame's visible
//! objects as occluders, rasterises them conservatively into the buffer's
//! masked cells (mesh.rs, buffer.rs), builds a pyramid of its farthest
//! depths, walks the hierarchy node by node testing each box in the
//! frustum against it, and draws what is visible; a frame whose buffer
//! rests is `vfc`'s own.
//!
//! Departures from MOC: its coverage is the pixels whose centres its own
//! rasteriser puts inside a triangle; here it is the centres the GPU is
//! sure to draw whatever its sub-pixel placement (mesh.rs), so a pixel
//! counts only clear of an occluder's outline by the adapter's snap
//! (about 1/230 pixel at 800x600 at the 8 sub-pixel bits Vulkan and GL
//! adapters report here, 1/16 at the 4 that Metal and Direct3D 12 are held
//! to, since they report none), which costs the seams between objects. A
//! cell keeps a depth plane besides its depth (the occluders' own, lowered
//! below each other's where several fill it); MOC keeps one depth per
//! tile. A cell may keep more than MOC's one working layer
//! (`swr.layers`), so that where several surfaces meet in it each keeps
//! its own depth over its own pixels; working layers nearer than the
//! reference stay once their masks fill the cell, and a box's test at a
//! cell takes each at the box's pixels in its mask; MOC clears its one,
//! and tests boxes against the reference layer alone. A buffer
//! that hid nothing, or saved less drawing than it cost, rests for a few
//! frames, and longer each time it fails again, or as long as 1.5 % of
//! the frames' time pays for where it costs much of a frame (MOC leaves
//! that to its caller), until the frustum holds several times the
//! triangles it held then (a camera turning from a wall into a room).
//! Occluders are whole visible objects (the clusters of one mesh taken
//! together, so that a mesh cut into clusters is one surface), their
//! triangles taken in the f64 projection (MOC and Godot take authored
//! occluder meshes, rasterised in f32 with SIMD: here it is scalar); which
//! of a mesh's triangles share an edge is found for every mesh that may
//! be an occluder when the mode is prepared, untimed, as an engine finds it when it loads an
//! occluder mesh, not in a frame. Like MOC it
//! shares the work among threads (`swr.threads`), each over a band of the
//! buffer's rows, and so are the box tests, each thread walking subtrees
//! of the hierarchy (walk.rs). `swr.resolution` sets the cells (each of
//! up to 8 × 8 pixel groups), trading the box test's precision against
//! time; `auto` takes finer cells where the occluders cover little of the
//! screen, so they cost no more.

use std::ops::Range;
use std::time::Instant;

mod buffer;
mod mesh;
mod neighbours;
mod walk;

use glam::{DAffine3, DMat3, DMat4, DVec2, DVec3, Vec4Swizzles};
use serde::Serialize;

use crate::auto_or::AutoOr;
use crate::bounds::Aabb;
use crate::camera::{Camera, Containment};
use crate::cull::culler::{Culler, FrameInput, OccluderDepths, PreviousFrame, TraversalStats};
use crate::cull::mode::{Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::cull::traversal::{frustum_cull_subtree, outgrew};
use crate::gpu::{
    BoxMargins, BoxPlanes, DepthMargins, EyeBox, FacingFace, Frame, GpuError, GpuSetup, PixelRays, QueryBox,
    Resolution, SubpixelPrecision, eye_relative_box,
};
use crate::parallel;
use crate::scene::{Object, Scene};
use buffer::{Cells, MAX_LAYERS, OcclusionBuffer};
use mesh::{DrawnPart, NearLimit, Patches, Rasteriser, ScreenMesh, ScreenVertex};
use neighbours::{RunNeighbours, run_indices};
use walk::{Walk, Walkers};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Swr,
    summary: "CPU software occlusion culling: last frame's visible objects rasterised conservatively into a small depth buffer on the CPU, the hierarchy's boxes tested against it (Intel's MOC, Godot, Umbra)",
    chart_colour: [140, 86, 75],
    conservative: true,
    draws_by_time: true,
    params: &[RESOLUTION, LAYERS, TRIANGLES, PIXELS_PER_TRIANGLE, THREADS, RESTS],
    exercised_with: &[("rests", "false")],
    needs: Needs::Nothing,
    carries: Carries::OccludersOnCpu,
    auto: Candidacy::Always,
    check: |params| SwrParams::from_params(params).map(drop),
    build: |_, params| Ok(Box::new(SoftwareOcclusionCulling::new(SwrParams::from_params(params)?))),
};

const RESOLUTION: ParamInfo = ParamInfo {
    key: "resolution",
    default: "auto",
    summary: "cells of the CPU depth buffer, WxH (at most the render size on each side); auto: 400x300 (400x150 where the camera looks level: the scene's upright lines then stay upright on screen, and columns of cells matter more than rows), or 800x600 where the last buffer held a depth over at most a quarter of the screen (the finer buffer then has no more cells to fill)",
};

/// `swr.resolution=auto`'s cells: [`COARSE_CELLS`], or twice as many on
/// each side where the last buffer built held a depth over at most
/// [`FINE_WHERE_HELD`] of the screen, so that the finer buffer has no more
/// cells to fill than the coarser one has in all (each at most the render
/// size). Occluders small on screen (a model seen whole from afar) then
/// get a cell a pixel at 800x600, where two occluders meeting inside a cell
/// of 2 x 2 pixels left it at the farther one's depth, for little more
/// time; occluders over most of the screen keep the coarser buffer. A
/// coarse buffer holds no depth in the cells its occluders' outlines cross
/// (a finer one holds most of their pixels), so it turns finer only at
/// [`FINE_FROM_COARSE`], lest the two take turns frame by frame.
const COARSE_CELLS: Resolution = Resolution {
    width: 400,
    height: 300,
};
const FINE_CELLS: Resolution = Resolution {
    width: 800,
    height: 600,
};
const FINE_WHERE_HELD: f64 = 0.25;
const FINE_FROM_COARSE: f64 = 0.2;

/// `swr.resolution=auto` takes [`LEVEL_CELLS`] for its coarse cells (at
/// 800x600, 2 × 4 pixels each) where no upright line of the scene leans
/// on screen by more than this, in pixels across a pixel down
/// ([`looks_level`]): then an upright edge that crosses a cell moves
/// across it by at most a quarter of the cell's height.
/// A scene that stands on a ground (streets, rooms, machines on a floor),
/// seen by a camera that looks neither up nor down, shows most of its
/// outlines upright (a building's corner, a door's frame, a column), and
/// where they are the buffer's columns of cells matter more than its rows.
/// Measured on the default city's street walk (120 frames, Vulkan, buffers
/// every frame, 4 layers): 400x150 cells cull a share of 0.976 of what
/// `roc` culls against 400x300's 0.984, for a fifth less CPU (`cargo
/// bench --bench swr`, six alternating rounds); on den-haag.obj's orbit,
/// which looks down on its district, the same cells cull 0.843 against
/// 0.972, and this rule keeps them square there. Its fine cells stay a
/// pixel each: their occluders cover little of the screen and cost
/// little, and on bunny.obj's orbit made level, 800x300 culled 0.910
/// against 800x600's 0.920.
const UPRIGHT_LEAN: f64 = 0.25;
const LEVEL_CELLS: Resolution = Resolution {
    width: 400,
    height: 150,
};

const LAYERS: ParamInfo = ParamInfo {
    key: "layers",
    default: "4",
    summary: "depth layers a cell keeps, 1 to 8: a reference every pixel of the cell is drawn at or nearer, and working layers each holding the pixels its occluders cover (MOC's two: a reference and one working layer); more keep more of a cell where several surfaces meet in it",
};

const TRIANGLES: ParamInfo = ParamInfo {
    key: "triangles",
    default: "65536",
    summary: "occluder triangles rasterised a frame at most: last frame's visible objects, largest on screen first",
};

/// An occluder costs its triangles (each projected, joined into patches
/// and rasterised) and can hide at most what lies behind its box on
/// screen: one whose box covers fewer pixels than it has triangles (a car
/// or a chair full of detail, seen through a window) costs more than it
/// can hide. Measured with `--sweep swr.pixels_per_triangle=0,1,3` on the
/// default city and on the models of `../shared/models` along their
/// README's paths (Vulkan, lavapipe, buffers built every frame): on the
/// city, 1 keeps the culled share (0.972 of what `roc` culls; 0.970 with
/// every visible object) for 13 % less CPU a frame, and on den-haag.obj
/// 15 % less (it hides more than `roc` either way: its box test is
/// finer); the engine, the bunny and the teapot keep theirs. 3 culls 6 %
/// less on the bunny (0.914) and a third less on den-haag (0.855).
const PIXELS_PER_TRIANGLE: ParamInfo = ParamInfo {
    key: "pixels_per_triangle",
    default: "1",
    summary: "the least pixels an occluder's box covers on screen per triangle of it: objects of more, smaller triangles cost more than they can hide (0: every visible object, up to the budget)",
};

const THREADS: ParamInfo = ParamInfo {
    key: "threads",
    default: "0",
    summary: "threads rasterising occluders, each over a band of the buffer's rows, then walking the hierarchy, each over its subtrees (0: one per core; at most 64; more than the cores take turns on them)",
};

const RESTS: ParamInfo = ParamInfo {
    key: "rests",
    default: "true",
    summary: "let a buffer that spared less drawing than it cost rest (7 frames, then 15, then 31 while it keeps failing, or as many as 1.5 % of the frames' time pays for its cost, up to 127: a frustum traversal only), until the frustum holds over 4 times the triangles it held then; false builds one every frame",
};

/// The most threads `swr.threads` may ask for (or a frame use): each holds
/// its share of the occluders' patches.
const MAX_THREADS: usize = 64;

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SwrParams {
    pub resolution: AutoOr<Resolution>,
    /// Depth layers a cell keeps (buffer.rs).
    pub layers: u32,
    pub triangles: u64,
    /// The least pixels an occluder's box covers per triangle of it.
    pub pixels_per_triangle: f64,
    /// 0: one per core.
    pub threads: usize,
    /// Whether a buffer that did not pay rests ([`Rest`]).
    pub rests: bool,
}

impl SwrParams {
    pub fn from_params(params: &ModeParams) -> Result<SwrParams, ModeError> {
        let threads = params.get(ModeId::Swr, &THREADS)?;
        if threads > MAX_THREADS {
            return Err(ModeError::bad(
                ModeId::Swr,
                &THREADS,
                format!("{threads}: at most {MAX_THREADS} (0: one per core)"),
            ));
        }
        let layers = params.get(ModeId::Swr, &LAYERS)?;
        if !(1..=MAX_LAYERS).contains(&layers) {
            return Err(ModeError::bad(
                ModeId::Swr,
                &LAYERS,
                format!("{layers}: from 1 to {MAX_LAYERS}"),
            ));
        }
        let pixels_per_triangle: f64 = params.get(ModeId::Swr, &PIXELS_PER_TRIANGLE)?;
        if !(pixels_per_triangle >= 0.0 && pixels_per_triangle.is_finite()) {
            let reason = format!("must be a number at least 0, got {pixels_per_triangle}");
            return Err(ModeError::bad(ModeId::Swr, &PIXELS_PER_TRIANGLE, reason));
        }
        Ok(SwrParams {
            resolution: params.get(ModeId::Swr, &RESOLUTION)?,
            layers,
            triangles: params.get(ModeId::Swr, &TRIANGLES)?,
            pixels_per_triangle,
            threads,
            rests: params.get(ModeId::Swr, &RESTS)?,
        })
    }

    /// The threads asked for: `threads`, or one per core for 0 (at most
    /// [`MAX_THREADS`]). The walk takes as many as the hierarchy gives work
    /// to (walk.rs).
    fn threads_asked(&self) -> usize {
        match self.threads {
            0 => std::thread::available_parallelism()
                .map_or(1, usize::from)
                .min(MAX_THREADS),
            n => n,
        }
    }

    /// The threads a frame may rasterise on: those asked for, and no more
    /// than the triangle budget gives work to.
    fn threads_used(&self) -> usize {
        let worth = 1 + self.triangles / TRIANGLES_PER_THREAD;
        self.threads_asked().min(usize::try_from(worth).unwrap_or(usize::MAX))
    }
}

pub struct SoftwareOcclusionCulling {
    params: SwrParams,
    /// Made for the frame's render size and cells, and again when they
    /// change; `spare` keeps the one `swr.resolution=auto` left, so that
    /// switching back allocates nothing.
    buffer: Option<OcclusionBuffer>,
    spare: Option<OcclusionBuffer>,
    /// The share of the screen where the last buffer built with occluders
    /// held a depth (all of it before the first), by which `auto` chooses
    /// the cells.
    held: f64,
    /// Whether `auto` last chose its finer cells ([`FINE_WHERE_HELD`]).
    fine: bool,
    /// What each thread rasterising occluders works with.
    preparers: Vec<Preparer>,
    rasterisers: Vec<Rasteriser>,
    /// Per run of meshes stored against one origin (at its first mesh),
    /// its triangles' neighbours: made when the mode is prepared for every
    /// run holding an object that may be an occluder, as an engine makes
    /// an occluder mesh's adjacency when it loads the mesh, not in a frame
    /// (without `prepare`, as in a unit test, the first time one of its
    /// objects is an occluder).
    neighbours: RunNeighbours,
    /// The backend's depth margins and the adapter's sub-pixel precision,
    /// known once prepared (GL's margins, the larger, and the coarsest
    /// precision until then).
    depth_margins: DepthMargins,
    subpixel: SubpixelPrecision,
    /// Whether its buffers break the conservative rule on purpose
    /// ([`OcclusionBuffer::careless`]).
    #[cfg(test)]
    careless: bool,
    /// The objects found visible last frame.
    visible: Vec<u32>,
    /// Frames left in which no buffer is built, since the last one did
    /// not pay ([`Rest`]).
    rest: Rest,
    /// Whether the last frame rested (it was `vfc`'s own).
    rested: bool,
    /// Whether the buffer holds a frame's occluders.
    buffer_holds: bool,
    /// Scratch, reused so a frame allocates nothing once warm.
    candidates: Vec<Candidate>,
    /// This frame's occluders, each some of `candidates`.
    units: Vec<OccluderUnit>,
    occluders: Vec<u32>,
    found: Vec<u32>,
    /// Step 4's threads' scratch.
    walkers: Walkers,
    /// Frustum culling's, while the buffer rests.
    stack: Vec<u32>,
}

impl SoftwareOcclusionCulling {
    pub fn new(params: SwrParams) -> Self {
        SoftwareOcclusionCulling {
            params,
            buffer: None,
            spare: None,
            held: 1.0,
            fine: false,
            preparers: Vec::new(),
            rasterisers: Vec::new(),
            neighbours: RunNeighbours::default(),
            depth_margins: DepthMargins::for_backend(wgpu::Backend::Gl),
            subpixel: SubpixelPrecision::COARSEST,
            #[cfg(test)]
            careless: false,
            visible: Vec::new(),
            rest: Rest::default(),
            rested: false,
            buffer_holds: false,
            candidates: Vec::new(),
            units: Vec::new(),
            occluders: Vec::new(),
            found: Vec::new(),
            walkers: Walkers::default(),
            stack: Vec::new(),
        }
    }

    /// Takes `subpixel` as the adapter's, as `prepare` does (for a frame
    /// run without a GPU: benches/swr.rs).
    pub fn assume_subpixel_precision(&mut self, subpixel: SubpixelPrecision) {
        self.subpixel = subpixel;
    }
}

impl SoftwareOcclusionCulling {
    /// Its threads' scratch.
    fn make_scratch(&mut self) {
        let threads = self.params.threads_used();
        self.preparers = (0..threads).map(|_| Preparer::default()).collect();
        self.rasterisers = (0..threads).map(|_| Rasteriser::default()).collect();
        self.walkers = Walkers::new(self.params.threads_asked());
    }

    /// The cells a buffer for render size `size` has: those asked for, or
    /// `auto`'s choice ([`FINE_WHERE_HELD`]; the coarse ones taller where
    /// the camera looks `level`, [`LEVEL_CELLS`]), at most `size` on each
    /// side.
    fn cells_for(&mut self, size: Resolution, level: bool) -> Resolution {
        if let AutoOr::Given(cells) = self.params.resolution {
            return within(cells, size);
        }
        let at_most = match self.fine {
            true => FINE_WHERE_HELD,
            false => FINE_FROM_COARSE,
        };
        self.fine = self.held <= at_most;
        let cells = match (self.fine, level) {
            (true, _) => FINE_CELLS,
            (false, true) => LEVEL_CELLS,
            (false, false) => COARSE_CELLS,
        };
        within(cells, size)
    }

    /// The most bytes its buffers may take at render size `size`: the cells
    /// given, or `auto`'s finest and coarsest together (one of them the
    /// spare).
    fn buffers_need(&self, size: Resolution) -> u64 {
        let bytes = |cells: Resolution| OcclusionBuffer::bytes(within(cells, size), self.params.layers);
        match self.params.resolution {
            AutoOr::Given(cells) => bytes(cells),
            AutoOr::Auto => bytes(FINE_CELLS) + bytes(COARSE_CELLS),
        }
    }

    /// Makes `buffer` one for render size `size` with `cells`: as it is,
    /// the spare, or a new one (the one it replaces becomes the spare). A
    /// spare taken back may hold another frame's occluders
    /// (`buffer_holds`).
    fn use_buffer(&mut self, size: Resolution, cells: Resolution) {
        let fits = |b: &Option<OcclusionBuffer>| b.as_ref().is_some_and(|b| b.target() == size && b.cells() == cells);
        if fits(&self.buffer) {
            return;
        }
        // A spare that does not fit goes before another is made, so that
        // no more than two buffers are ever held (`buffers_need`).
        let spare = self.spare.take();
        let next = match fits(&spare) {
            true => spare,
            false => {
                drop(spare);
                Some(OcclusionBuffer::with_layers(size, cells, self.params.layers))
            }
        };
        self.spare = std::mem::replace(&mut self.buffer, next);
        self.buffer_holds = true;
        #[cfg(test)]
        if let Some(buffer) = &mut self.buffer {
            buffer.careless = self.careless;
        }
    }

    /// Takes the candidates that are clusters of one mesh under one
    /// transform as one occluder each, nearest first (a cell an occluder
    /// has filled turns away the triangles behind it).
    fn group_occluders(&mut self, scene: &Scene) {
        let object = |c: &Candidate| &scene.objects[c.object as usize];
        let run = |c: &Candidate| scene.meshes[object(c).mesh as usize].shares_origin_with.start;
        self.candidates
            .sort_unstable_by_key(|c| (object(c).part, run(c), object(c).mesh, c.object));
        let together = |a: &Candidate, b: &Candidate| {
            (object(a).part, run(a)) == (object(b).part, run(b)) && object(a).transform == object(b).transform
        };
        self.units.clear();
        let mut start = 0;
        for k in 1..=self.candidates.len() {
            if k == self.candidates.len() || !together(&self.candidates[k - 1], &self.candidates[k]) {
                let boxes = self.candidates[start..k].iter().map(|c| c.on_screen.clone());
                self.units.push(OccluderUnit {
                    candidates: start..k,
                    on_screen: boxes.reduce(|a, b| a.zip(b).map(|(a, b)| a.union(&b))).flatten(),
                });
                start = k;
            }
        }
        let first_object = |u: &OccluderUnit| self.candidates[u.candidates.start].object;
        self.units.sort_unstable_by(|a, b| {
            b.nearest()
                .total_cmp(&a.nearest())
                .then(first_object(a).cmp(&first_object(b)))
        });
    }
}

/// When `swr` builds no buffer, and so tests no box (a frustum traversal
/// only): after a buffer that did not pay ([`pays`]), for [`REST_FRAMES`]
/// frames, twice as many and one more each time the next buffer fails
/// again, up to [`LONGEST_REST`]; a buffer that pays brings the rests back
/// to the shortest. Where occlusion never pays, it costs one frame in 32.
/// A buffer that costs much of a frame (with the box tests through it)
/// rests longer: as many frames as [`TRY_BUDGET`] of their time pays for
/// it, up to [`LONGEST_DEAR_REST`] (as `auto` bounds its rechecks of
/// rivals known to be dearer), so that where a buffer costs about a frame
/// (a dense model's, on a light frame) its tries cost not 5 % of the run
/// but 1.5 % (more for one dearer than about 2.6 frames, which the
/// longest rest caps). A rest ends early where the frustum comes to hold
/// several times the triangles it held when the buffer did not pay
/// ([`outgrew`]): a camera that faced a wall, where a buffer hides
/// nothing, turning into a room, where it hides most; the frame that ends
/// the rest takes the objects in its frustum as occluders, as the frame
/// after a resting one does. Walking 120 frames through an office floor
/// of 10 × 10 rooms with doorways (turning at the floor's outer walls,
/// and passing through balls in its way; two runs on each of lavapipe
/// and llvmpipe, alternating with the rule before), `swr` rested in 29–49
/// frames where `roc` hid more than a tenth of the frustum and took
/// 0.76–0.96 of `roc`'s time; with rests ending where the frustum outgrew
/// the failed one, it rested in 24 such frames and took 0.73–0.76 of
/// `roc`'s time (the rests left mostly follow a frame in which a ball the
/// eye then passed filled the view: past it, last frame's visible set,
/// the ball, hides nothing, and the frustum ahead shrinks as the walls
/// come nearer). Leaving occlusion out is always safe.
#[derive(Clone, Copy, Debug)]
struct Rest {
    /// Frames left of the current rest.
    left: u32,
    /// How long the next rest is.
    next: u32,
    /// The triangles in the frustum when the last buffer did not pay.
    failed_with: u64,
}

const REST_FRAMES: u32 = 7;
const LONGEST_REST: u32 = 31;
/// Share of the frames' time that tries of a buffer which keeps failing
/// may cost: `auto.budget`'s default.
const TRY_BUDGET: f64 = 0.015;
/// The longest rest of a dear buffer: the rests' doubling two steps on.
const LONGEST_DEAR_REST: u32 = 127;

impl Default for Rest {
    fn default() -> Rest {
        Rest {
            left: 0,
            next: REST_FRAMES,
            failed_with: 0,
        }
    }
}

impl Rest {
    /// Whether this frame rests; counts it.
    fn take(&mut self) -> bool {
        let resting = self.left > 0;
        self.left = self.left.saturating_sub(1);
        resting
    }

    /// Ends the rest where the frustum, now holding `in_frustum`
    /// triangles, outgrew the one whose buffer did not pay; whether it
    /// did.
    fn ends_where_outgrown(&mut self, in_frustum: u64) -> bool {
        let outgrown = outgrew(in_frustum, self.failed_with);
        if outgrown {
            self.left = 0;
        }
        outgrown
    }

    /// After a frame's buffer that cost `cost` frames (its time, with the
    /// box tests through it, over the previous frame's; 0 where not
    /// known), in a frustum holding `in_frustum` triangles: rests from the
    /// next frame on unless it `paid`.
    fn after(&mut self, paid: bool, cost: f64, in_frustum: u64) {
        if paid {
            self.next = REST_FRAMES;
        } else {
            self.failed_with = in_frustum;
            // A NaN stays one through the clamp, and is 0 frames.
            let paid_for = (cost / TRY_BUDGET).ceil().clamp(0.0, f64::from(LONGEST_DEAR_REST)) as u32;
            self.left = self.next.max(paid_for);
            self.next = (2 * self.next + 1).min(LONGEST_REST);
        }
    }
}

/// Whether a buffer that hid `hidden` triangles, at a cost of `spent_ms`
/// of this frame's CPU time, pays for itself: it hid something and, where
/// the mode's previous frame says what its drawing cost a triangle, the
/// drawing it spared is worth at least that time. The estimate errs
/// towards building buffers: a triangle's share of the drawing holds the
/// frame's fixed costs too, and a hidden node counts all its objects'
/// triangles, even those beyond the frustum.
fn pays(hidden: u64, spent_ms: f64, previous: Option<PreviousFrame>) -> bool {
    match previous {
        _ if hidden == 0 => false,
        Some(p) if p.triangles_drawn > 0 && p.render_ms.is_finite() && p.render_ms > 0.0 => {
            hidden as f64 * p.render_ms / p.triangles_drawn as f64 >= spent_ms
        }
        _ => true,
    }
}

/// An object that may be an occluder this frame.
struct Candidate {
    /// Its box on screen; `None` when the box reaches the near plane (it
    /// may cover all of it).
    on_screen: Option<BoxOnScreen>,
    object: u32,
}

impl Candidate {
    /// The pixels its box covers (all of them for a box reaching the near
    /// plane).
    fn area(&self) -> f64 {
        self.on_screen.as_ref().map_or(f64::INFINITY, |b| b.area)
    }
}

/// One occluder as the buffer takes it: the candidates that are clusters
/// of one mesh placed by one transform, taken together so that the edges
/// they share join their surfaces (scene/model.rs, `shares_origin_with`).
struct OccluderUnit {
    /// Its candidates, among the frame's, in mesh order.
    candidates: Range<usize>,
    /// The rectangle on screen holding their boxes, and the nearest depth
    /// of those; `None` where one box reaches the near plane.
    on_screen: Option<BoxOnScreen>,
}

impl OccluderUnit {
    /// Its nearest depth (the nearest possible for a box reaching the near
    /// plane).
    fn nearest(&self) -> f64 {
        self.on_screen.as_ref().map_or(f64::INFINITY, |b| b.nearest)
    }
}

/// A camera's projection to framebuffer pixels and reverse-Z depth.
struct Projector {
    view_projection: DMat4,
    size: DVec2,
}

impl Projector {
    fn new(camera: &Camera, size: Resolution) -> Projector {
        Projector {
            view_projection: camera.projection() * DMat4::from_mat3(camera.view_rotation()),
            size: DVec2::new(f64::from(size.width), f64::from(size.height)),
        }
    }

    /// The eye-relative point `p` on screen: (x, y) in pixels, z its depth,
    /// and its view depth; `None` nearer than `near` along the view (or
    /// behind the eye).
    fn project(&self, p: DVec3, near: f64) -> Option<(DVec3, f64)> {
        let clip = self.view_projection * p.extend(1.0);
        if clip.w.is_nan() || clip.w < near {
            return None;
        }
        let ndc = clip.xyz() / clip.w;
        let on_screen = DVec3::new(
            (ndc.x * 0.5 + 0.5) * self.size.x,
            (0.5 - ndc.y * 0.5) * self.size.y,
            ndc.z,
        );
        Some((on_screen, clip.w))
    }

    /// The view depth of the eye-relative point `p` (its clip w).
    fn view_depth(&self, p: DVec3) -> f64 {
        (self.view_projection * p.extend(1.0)).w
    }

    /// A tested box on screen; `None` where a corner does not project to
    /// a finite point (then nothing can be said of it: it is visible).
    fn box_on_screen(&self, q: &QueryBox) -> Option<BoxOnScreen> {
        let (min, max) = (q.min.xyz().as_dvec3(), q.max.xyz().as_dvec3());
        // Each corner's clip position is the sum of one of two terms per
        // axis, summed in the order `DMat4 * DVec4` sums them (so the same
        // bits): 6 products instead of 8 × 4.
        let m = &self.view_projection;
        let terms = [
            [m.x_axis * min.x, m.x_axis * max.x],
            [m.y_axis * min.y, m.y_axis * max.y],
            [m.z_axis * min.z, m.z_axis * max.z],
        ];
        let (mut low, mut high, mut nearest) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
        for corner in 0..8 {
            let term = |axis: usize| terms[axis][(corner >> axis) & 1];
            let clip = term(0) + term(1) + term(2) + m.w_axis;
            let ndc = clip.xyz() / clip.w;
            if !ndc.is_finite() {
                return None;
            }
            let pixel = DVec2::new((ndc.x * 0.5 + 0.5) * self.size.x, (0.5 - ndc.y * 0.5) * self.size.y);
            low = low.min(pixel);
            high = high.max(pixel);
            nearest = nearest.max(ndc.z + f64::from(q.min.w));
        }
        let clamp = |v: f64, side: f64| v.floor().clamp(0.0, side - 1.0) as u32;
        let seen = (high.min(self.size) - low.max(DVec2::ZERO)).max(DVec2::ZERO);
        Some(BoxOnScreen {
            first: [clamp(low.x, self.size.x), clamp(low.y, self.size.y)],
            last: [clamp(high.x, self.size.x), clamp(high.y, self.size.y)],
            area: seen.x * seen.y,
            nearest,
        })
    }
}

/// `cells`, at most `size` on each side: a buffer has no more cells than
/// the render has pixels.
fn within(cells: Resolution, size: Resolution) -> Resolution {
    Resolution {
        width: cells.width.min(size.width),
        height: cells.height.min(size.height),
    }
}

/// Refuses buffers of `need` bytes where the system says this process may
/// take only `left` more (unknown: taken as enough), before allocating
/// them ends the process.
fn buffers_fit(need: u64, left: Option<u64>) -> Result<(), GpuError> {
    match left {
        Some(left) if need > left => Err(GpuError::HostMemory {
            what: "swr's CPU depth buffers",
            need: need.div_ceil(1 << 20),
            left: left / (1 << 20),
            hint: "take fewer swr.layers or a coarser swr.resolution",
        }),
        _ => Ok(()),
    }
}

/// Whether every line along `up` (the scene's up) that `camera` sees
/// leans on screen by at most [`UPRIGHT_LEAN`] pixels across a pixel down.
/// In the camera's frame (x right, y up, looking down -z), such a line
/// through a point seen at (px, py) (its x and y over its distance) runs
/// on screen along (ux + px uz, uy + py uz), u being `up` in that frame:
/// its lean is a ratio of two affine functions of (px, py), so over the
/// view, where the second keeps its sign, it is greatest at a corner.
fn looks_level(camera: &Camera, up: DVec3) -> bool {
    let u = camera.view_rotation() * up;
    let half_y = (camera.fov_y / 2.0).tan();
    let half_x = half_y * camera.aspect;
    let corners = [
        [-half_x, -half_y],
        [half_x, -half_y],
        [-half_x, half_y],
        [half_x, half_y],
    ];
    let down = corners.map(|[_, py]| u.y + py * u.z);
    let across = corners.map(|[px, _]| u.x + px * u.z);
    // Upright lines point one way (up or down) on screen everywhere, and
    // lean little at every corner.
    (down.iter().all(|&d| d > 0.0) || down.iter().all(|&d| d < 0.0))
        && across.iter().zip(&down).all(|(a, d)| a.abs() <= UPRIGHT_LEAN * d.abs())
}

/// A tested box on screen.
#[derive(Clone)]
struct BoxOnScreen {
    /// The first and last pixels (x, y) its rectangle touches, clamped to
    /// the target.
    first: [u32; 2],
    last: [u32; 2],
    /// Pixels of the target it covers.
    area: f64,
    /// Its nearest depth, raised.
    nearest: f64,
}

impl BoxOnScreen {
    /// The rectangle holding both (its area that rectangle's), and the
    /// nearer depth.
    fn union(&self, other: &BoxOnScreen) -> BoxOnScreen {
        BoxOnScreen {
            first: [self.first[0].min(other.first[0]), self.first[1].min(other.first[1])],
            last: [self.last[0].max(other.last[0]), self.last[1].max(other.last[1])],
            area: f64::from((self.last[0] - self.first[0] + 1) * (self.last[1] - self.first[1] + 1)),
            nearest: self.nearest.max(other.nearest),
        }
    }
}

/// How a box stands against the buffer.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Hidden,
    Visible,
}

/// What one frame tests boxes with.
struct Tester<'a> {
    buffer: &'a OcclusionBuffer,
    projector: &'a Projector,
    rays: PixelRays,
    camera: &'a Camera,
    view: &'a DMat3,
    /// Those of an exact test ([`BoxMargins::for_exact_tests`]): it is
    /// made in f64.
    margins: BoxMargins,
}

impl Tester<'_> {
    /// `bounds` (in the frustum) against the buffer: by its nearest corner,
    /// and where that is not enough, by where the pixel rays through each
    /// pyramid texel enter it (a box seen obliquely is far nearer at one
    /// end than at the other).
    fn test(&self, bounds: &Aabb) -> Verdict {
        let EyeBox::Testable(q) = eye_relative_box(self.camera, self.view, self.margins, bounds) else {
            return Verdict::Visible;
        };
        let Some(b) = self.projector.box_on_screen(&q) else {
            return Verdict::Visible;
        };
        let planes = BoxPlanes::new(self.camera, &q, &self.rays, self.buffer.target());
        if self.buffer.hides(b.first, b.last, b.nearest, &planes) {
            Verdict::Hidden
        } else {
            Verdict::Visible
        }
    }
}

impl Culler for SoftwareOcclusionCulling {
    fn name(&self) -> &str {
        ModeId::Swr.name()
    }

    /// Its parameters as given (`threads` 0 stays 0: the count it comes to
    /// is the machine's, and `occlu merge` holds one run's parameters equal
    /// on every machine).
    /// As given, but for a `resolution` given: the cells its buffer had,
    /// which are at most the render size on each side (`auto` stays
    /// `auto`: its cells change with the frames).
    fn parameters(&self) -> serde_json::Value {
        let used = SwrParams {
            resolution: match (self.params.resolution, &self.buffer) {
                (AutoOr::Given(_), Some(buffer)) => AutoOr::Given(buffer.cells()),
                (asked, _) => asked,
            },
            ..self.params
        };
        serde_json::json!(used)
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        self.depth_margins = setup.gpu.depth_margins;
        self.subpixel = setup.gpu.subpixel;
        self.make_scratch();
        buffers_fit(self.buffers_need(setup.resolution), crate::scene::memory::available())?;
        let cells = self.cells_for(setup.resolution, false);
        self.use_buffer(setup.resolution, cells);
        // Every object that may be an occluder: one of more triangles than
        // the budget never is.
        let scene = setup.scene;
        let budget = self.params.triangles;
        let may_occlude =
            (0..scene.objects.len() as u32).filter(|&o| u64::from(scene.objects[o as usize].triangles) <= budget);
        self.neighbours.make(scene, may_occlude);
        Ok(())
    }

    /// One frame, on the CPU:
    ///
    /// 1. **Occluders**: last frame's visible objects, largest on screen first,
    ///    each whose triangles still fit `swr.triangles` and whose box covers
    ///    `swr.pixels_per_triangle` pixels per triangle; the clusters of one
    ///    mesh under one transform are one occluder. They are rasterised
    ///    nearest first.
    /// 2. **Rasterise** their triangles, projected in f64, into a buffer of
    ///    `swr.resolution` cells, conservatively. An occluder's triangles that
    ///    turn one way and join along shared edges are one surface (a patch,
    ///    mesh.rs): it marks the pixel groups of a cell the GPU is sure to draw
    ///    it over, with the GPU's snapping and f32 error as margins from its
    ///    outline, and the least depth it may draw there. A cell merges the
    ///    patches' marks (buffer.rs, MOC's working layers) and, once every
    ///    pixel is marked, takes the farthest depth of the nearest marks
    ///    that fill it, with a depth plane below theirs, so a box can be compared with it centre by
    ///    centre. A triangle reaching the near plane keeps its part beyond it
    ///    (clipped, as MOC clips; its cut sides border its patch), so a floor
    ///    or a wall that runs past the eye hides what lies behind it.
    /// 3. **Pyramid** of the buffer's farthest depths.
    /// 4. **Test**: the hierarchy is walked node by node (its subtrees
    ///    shared among the threads, walk.rs); a node in the
    ///    frustum is also tested by its box (grown as every box test, and
    ///    raised by a fragment's error: the test is made in f64,
    ///    `BoxMargins::for_exact_tests`, gpu/conservative.rs). Its screen
    ///    rectangle's pixels, rounded
    ///    outward, are read at the pyramid level where they span at most 8
    ///    texels; at each texel the box must lie behind the texel's farthest
    ///    depth, by its nearest corner or by the planes where pixel rays enter
    ///    it (`BoxPlanes`: a box seen at a slant is far nearer at one end), or
    ///    no ray through the texel's pixel centres may meet it; a texel that
    ///    fails is tried again by its children, down to the cells, where the box
    ///    may also lie behind the cell's plane, or behind a working layer
    ///    or the reference at its pixels in the layer's mask and behind the
    ///    reference at the rest, each part over its own rectangle. A hidden
    ///    node stops its subtree; a box reaching the near plane is visible.
    ///    A leaf's objects are tested one by one.
    /// 5. **Draw** the visible objects (the renderer orders them nearest
    ///    first, as it does every list a mode draws); they are next
    ///    frame's occluder candidates. An occluder found hidden is not
    ///    drawn, and what the buffer vouches for is still drawn: where a
    ///    layer vouches for a depth at a pixel centre, an occluder merged
    ///    into it draws that centre at least that near. If that occluder is
    ///    found hidden, its box (which holds what it draws) lies behind some
    ///    layer at that centre, nearer still, and so another occluder draws
    ///    the centre nearer than the first; depths that only grow along
    ///    finitely many occluders end at one that is drawn. (One hidden
    ///    because no pixel ray meets its box draws no centre at all.)
    ///
    /// A frame whose buffer rests ([`Rest`]) skips steps 1 to 4: it is
    /// `vfc`'s frame, and what it draws is next frame's candidates.
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let (camera, scene, size) = (input.camera, input.scene, input.resolution);
        let mut stats = TraversalStats::default();
        if self.preparers.is_empty() {
            self.make_scratch();
        }
        let frustum = camera.frustum();

        // A resting buffer tests nothing: the frame is frustum culling's,
        // its fully-inside shortcut included, so that it costs what `vfc`
        // costs. (Walked node by node, den-haag's orbit took 0.4–0.5 ms of
        // CPU and 0.3–1.1 ms more of GPU a frame than `vfc`, whose frame
        // there is 10–14 ms.) Unless the frustum has outgrown the one
        // whose buffer did not pay: then the rest ends, and this frame
        // builds a buffer.
        let mut resting = self.rest.take();
        if resting {
            self.found.clear();
            let mut frustum_stats = TraversalStats::default();
            frustum_cull_subtree(
                scene,
                input.hierarchy,
                0,
                &frustum,
                &mut self.stack,
                &mut self.found,
                &mut frustum_stats,
            );
            // One pass over the objects found, which a resting frame
            // draws anyway.
            resting = !self.rest.ends_where_outgrown(scene.triangles_of(&self.found));
            if resting {
                stats = frustum_stats;
            } else {
                // The view turned: last frame's visible objects may be off
                // screen, and a buffer of none hides nothing. This frame's
                // frustum is what a resting frame hands the next one.
                std::mem::swap(&mut self.visible, &mut self.found);
            }
        }
        self.rested = resting;

        // 1. Occluders: last frame's visible objects still on screen,
        // largest first; none while the buffer rests (which keeps its
        // cells: a resting buffer holds nothing to choose them by).
        if !resting || self.buffer.as_ref().is_none_or(|b| b.target() != size) {
            let cells = self.cells_for(size, looks_level(camera, scene.up.axis.vector()));
            self.use_buffer(size, cells);
        }
        // A resting buffer holds nothing (what it shows is what the frame
        // used).
        if let (true, Some(buffer)) = (resting && self.buffer_holds, &mut self.buffer) {
            buffer.cleared_bands(u32::MAX).for_each(drop);
            self.buffer_holds = false;
        }
        if resting {
            ctx.draw(&self.found);
            std::mem::swap(&mut self.visible, &mut self.found);
            return stats;
        }
        let projector = Projector::new(camera, size);
        let margins = BoxMargins::new(self.depth_margins, self.subpixel, camera, size);
        let exact = margins.for_exact_tests();
        let view = camera.view_rotation();
        self.candidates.clear();
        for &o in &self.visible {
            let bounds = &scene.objects[o as usize].bounds;
            if frustum.classify(bounds) == Containment::Outside {
                continue;
            }
            let on_screen = match eye_relative_box(camera, &view, exact, bounds) {
                EyeBox::ReachesNear => None,
                EyeBox::Testable(q) => match projector.box_on_screen(&q) {
                    Some(b) if b.area > 0.0 => Some(b),
                    Some(_) => continue,
                    None => None,
                },
            };
            self.candidates.push(Candidate { on_screen, object: o });
        }
        self.candidates
            .sort_unstable_by(|a, b| b.area().total_cmp(&a.area()).then(a.object.cmp(&b.object)));
        let mut budget = self.params.triangles;
        let pixels_per_triangle = self.params.pixels_per_triangle;
        self.candidates.retain(|c| {
            let triangles = u64::from(scene.objects[c.object as usize].triangles);
            let fits = triangles <= budget && c.area() >= pixels_per_triangle * triangles as f64;
            budget -= if fits { triangles } else { 0 };
            fits
        });
        self.group_occluders(scene);
        self.occluders.clear();
        for unit in &self.units {
            for c in &self.candidates[unit.candidates.clone()] {
                self.occluders.push(c.object);
            }
        }

        stats.occluder_triangles = self.params.triangles - budget;

        // 2-3. Their triangles into the buffer, then the pyramid. Their
        // meshes' neighbours were made when the mode was prepared (here
        // only in a frame run unprepared, as in a unit test). What a buffer
        // costs, against what it spares, is timed from here.
        self.neighbours.make(scene, self.occluders.iter().copied());
        let started = Instant::now();
        let Some(buffer) = &mut self.buffer else {
            unreachable!("made above")
        };
        let rays = PixelRays::new(camera, size);
        let occluders = Occluders {
            units: &self.units,
            candidates: &self.candidates,
            projector: &projector,
            snap: self.subpixel.vertex_error(size),
            fragments: FragmentRule {
                margins,
                view: &view,
                rays: &rays,
                target: size,
            },
            camera,
            scene,
            neighbours: &self.neighbours,
        };
        occluders.rasterise(buffer, &mut self.preparers, &mut self.rasterisers);
        buffer.build_pyramid();
        self.buffer_holds = true;
        if self.params.resolution == AutoOr::Auto && !self.occluders.is_empty() {
            self.held = buffer.held();
        }

        // 4. The hierarchy, in the frustum and not hidden (walk.rs: its
        // subtrees shared over the threads).
        let tester = Tester {
            buffer,
            projector: &projector,
            rays,
            camera,
            view: &view,
            margins: exact,
        };
        let hides = |bounds: &Aabb| tester.test(bounds) == Verdict::Hidden;
        let walk = Walk {
            frustum: &frustum,
            scene,
            hierarchy: input.hierarchy,
            hides: &hides,
        };
        let walked = self.walkers.walk(&walk, &mut self.found);
        let hidden_triangles = walked.hidden_triangles;
        (
            stats.nodes_visited,
            stats.nodes_culled_frustum,
            stats.nodes_culled_occlusion,
        ) = (
            walked.nodes_visited,
            walked.nodes_culled_frustum,
            walked.nodes_culled_occlusion,
        );
        // A buffer of occluders that did not pay rests the next frames (a
        // warm-up frame's time, compiling and filling caches, says nothing).
        if !self.occluders.is_empty() && self.params.rests && !input.warm_up {
            let spent_ms = started.elapsed().as_secs_f64() * 1e3;
            let cost = input.previous.map_or(0.0, |p| spent_ms / p.frame_ms);
            let paid = pays(hidden_triangles, spent_ms, input.previous);
            // What the frustum held: what was found visible and what was
            // hidden (a hidden node's objects counted whole, even where
            // they reach past the frustum, which only makes the rest end
            // later).
            let in_frustum = if paid {
                0
            } else {
                hidden_triangles + scene.triangles_of(&self.found)
            };
            self.rest.after(paid, cost, in_frustum);
        }

        // 5. The visible objects; they are next frame's candidates.
        ctx.draw(&self.found);
        std::mem::swap(&mut self.visible, &mut self.found);
        stats
    }

    /// Also ends a rest: a culler seeded by another (as `auto` seeds the
    /// one it probes) is measured frame by frame, each with its buffer.
    fn seed_visible(&mut self, visible: &[u32]) {
        self.visible.clear();
        self.visible.extend_from_slice(visible);
        self.rest = Rest::default();
    }

    fn occluder_depths(&self) -> Option<OccluderDepths> {
        self.buffer.as_ref().map(OcclusionBuffer::per_pixel)
    }

    fn frustum_only(&self) -> bool {
        self.rested
    }
}

/// What one thread makes of its share of the occluders: each one's
/// vertices on screen and the parts of its mesh drawn (scratch), and its
/// patches, ready to rasterise.
#[derive(Default)]
struct Preparer {
    vertices: Vec<Option<ScreenVertex>>,
    /// Per vertex, its position relative to the eye.
    positions: Vec<DVec3>,
    parts: Vec<DrawnPart>,
    patches: Patches,
    /// The occluders of its share, each as (its index, its patches in
    /// `patches`).
    occluders: Vec<(usize, Range<usize>)>,
}

/// A frame uses one thread more for each this many occluder triangles (a
/// job handed to the pool costs about 12 µs before it starts; a
/// triangle's rasterising, a few hundred nanoseconds).
const TRIANGLES_PER_THREAD: u64 = 4096;

/// Bands of rows a frame's rasterisation is cut into, per thread.
const BANDS_PER_THREAD: u32 = 8;

/// One frame's occluders, and what they are rasterised with.
struct Occluders<'a> {
    units: &'a [OccluderUnit],
    candidates: &'a [Candidate],
    projector: &'a Projector,
    /// How far the GPU's sub-pixel snap may move a vertex
    /// ([`ScreenMesh::snap`]).
    snap: f64,
    fragments: FragmentRule<'a>,
    camera: &'a Camera,
    scene: &'a Scene,
    /// Per run of meshes stored against one origin (at its first mesh),
    /// its triangles' neighbours (made for every occluder's run).
    neighbours: &'a RunNeighbours,
}

/// What the scene's fragment stage keeps of each object this frame
/// (`FragmentLimit`, as the renderer makes it).
struct FragmentRule<'a> {
    margins: BoxMargins,
    view: &'a DMat3,
    rays: &'a PixelRays,
    target: Resolution,
}

impl FragmentRule<'_> {
    /// [`DrawnPart::facing`] for `object`.
    fn facing(&self, camera: &Camera, object: &Object) -> [Option<FacingFace>; 3] {
        FacingFace::of_object(camera, self.view, self.margins, &object.bounds, self.rays, self.target)
    }
}

impl Occluders<'_> {
    /// Rasterises every occluder into `buffer` (cleared first), on as many
    /// threads as there are triangles to share (one per
    /// [`TRIANGLES_PER_THREAD`], at most one per preparer and rasteriser),
    /// in two steps: each thread makes the patches of a share of the
    /// occluders (in order, shared by triangles); then each rasterises
    /// every occluder's patches, in order, into a band of the buffer's rows,
    /// so the cells are those one thread leaves.
    fn rasterise(&self, buffer: &mut OcclusionBuffer, preparers: &mut [Preparer], rasterisers: &mut [Rasteriser]) {
        let triangles = |unit: &OccluderUnit| -> u64 {
            self.candidates[unit.candidates.clone()]
                .iter()
                .map(|c| u64::from(self.scene.objects[c.object as usize].triangles))
                .sum()
        };
        let total: u64 = self.units.iter().map(triangles).sum();
        let rows = buffer.cells().height;
        let threads = (1 + total / TRIANGLES_PER_THREAD)
            .min(preparers.len().min(rasterisers.len()) as u64)
            .min(u64::from(rows))
            .max(1) as usize;
        // Share k ends where the triangles so far first reach (k + 1) /
        // threads of them.
        let mut ends = [0; MAX_THREADS];
        let (mut so_far, mut k) = (0, 0);
        for (i, unit) in self.units.iter().enumerate() {
            so_far += triangles(unit);
            while k + 1 < threads && so_far * threads as u64 >= total * (k as u64 + 1) {
                ends[k] = i + 1;
                k += 1;
            }
        }
        ends[k..threads].fill(self.units.len());
        let shares = preparers[..threads]
            .iter_mut()
            .enumerate()
            .map(|(k, preparer)| (if k == 0 { 0 } else { ends[k - 1] }..ends[k], preparer));
        parallel::each(shares, |(share, preparer)| self.prepare(share, preparer));
        // Rows hold unlike work (sky above, near objects below): each
        // thread takes band after band of a few rows until none is left.
        let preparers = &preparers[..threads];
        let bands = buffer.cleared_bands(rows.div_ceil(BANDS_PER_THREAD * threads as u32));
        let bands = std::sync::Mutex::new(bands);
        parallel::each(rasterisers[..threads].iter_mut(), |rasteriser| {
            // A band is taken under the lock; a thread that panicked holding
            // it ends the frame's scope anyway.
            while let Some(mut cells) = bands.lock().ok().and_then(|mut bands| bands.next()) {
                self.rasterise_band(&mut cells, preparers, rasteriser);
            }
        });
    }

    /// Makes the patches of the occluders `share`.
    fn prepare(&self, share: Range<usize>, preparer: &mut Preparer) {
        preparer.patches.clear();
        preparer.occluders.clear();
        for i in share {
            let which = prepare_occluder(preparer, self, &self.units[i]);
            preparer.occluders.push((i, which));
        }
    }

    fn rasterise_band(&self, cells: &mut Cells, preparers: &[Preparer], rasteriser: &mut Rasteriser) {
        for preparer in preparers {
            for (i, which) in &preparer.occluders {
                // Skipped where the buffer so far hides its boxes: it could
                // add nothing (rasterising nearest first makes this pay).
                let hidden = self.units[*i]
                    .on_screen
                    .as_ref()
                    .is_some_and(|b| cells.behind(b.first, b.last, b.nearest));
                if !hidden {
                    rasteriser.rasterise(cells, &preparer.patches, which.clone());
                }
            }
        }
    }
}

/// The GPU's error in an f32 vertex position, as a fraction of the sizes
/// of what it sums: 8 steps of 2^-24 (rounding the matrix, 4 products and
/// 3 sums take 5, the rest is margin).
const F32_POSITION_ERROR: f64 = 8.0 / (1u32 << 24) as f64;

/// How far from ours the GPU may place a vertex of a mesh within `local`
/// (in its own frame) placed by `transform`, on any view axis. It rounds
/// the model-view to f32 and sums, per view axis, its products with the
/// f32 position and its translation: within a few steps of 2^-24 of the
/// sizes of those terms, at most |model-view| · |local| + |translation|.
fn position_error(camera: &Camera, transform: &DAffine3, local: &Aabb) -> f64 {
    let model_view = camera.model_view(transform);
    let reach = local.min.abs().max(local.max.abs());
    F32_POSITION_ERROR * (model_view.matrix3.abs() * reach + model_view.translation.abs()).max_element()
}

/// Makes the patches of `occluder`'s triangles (placed where the scene has
/// them this frame) in `preparer`; returns which they are.
///
/// Its vertices may land [`position_error`] from ours: that error d moves
/// a vertex at view depth w and x pixels off the view's axis by up to
/// d / w · (f + x) pixels (f the pixels at unit depth), and its depth by
/// d / w of it: its part of its [`ScreenVertex`]'s slack and depth error. Vertices within that
/// error (and 2^-10 of the near distance) of the near plane are not
/// placed: the GPU may clip them. A triangle with such a vertex keeps its
/// part beyond that limit (mesh.rs), so a floor or a wall that reaches
/// past the eye still hides what lies behind it (MOC clips its occluders
/// at the near plane too). Where that part ends, the GPU clips the
/// triangle nearer the eye, at the near plane, with f32 arithmetic on the
/// same line: its crossing's error is taken as twice a vertex's at the
/// near plane's depth (an upper bound of it anywhere between), and its
/// sides' placement on screen bounded where they are on screen.
fn prepare_occluder(preparer: &mut Preparer, occluders: &Occluders, occluder: &OccluderUnit) -> Range<usize> {
    let (camera, scene, projector) = (occluders.camera, occluders.scene, occluders.projector);
    let objects = || {
        occluders.candidates[occluder.candidates.clone()]
            .iter()
            .map(|c| &scene.objects[c.object as usize])
    };
    // An occluder holds one candidate at least.
    let first = &scene.objects[occluders.candidates[occluder.candidates.start].object as usize];
    let local = objects().fold(Aabb::EMPTY, |b, o| b.union(scene.meshes[o.mesh as usize].bounds));
    let position_error = position_error(camera, &first.transform, &local);
    let near = camera.near * (1.0 + 1.0 / 1024.0) + position_error;
    let pixels_at_unit_depth = projector.size.y / (2.0 * (camera.fov_y / 2.0).tan());
    let run = &scene.meshes[first.mesh as usize].shares_origin_with;
    let run_first_triangle = scene.meshes[run.start as usize].first_index / 3;
    preparer.vertices.clear();
    preparer.positions.clear();
    preparer.parts.clear();
    let mut triangle_slot = 0;
    for object in objects() {
        let mesh = &scene.meshes[object.mesh as usize];
        let indices = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
        // A cluster's indices reach a run of vertices of its own; each is
        // projected once.
        let (first_vertex, last_vertex) = indices
            .iter()
            .fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        if first_vertex > last_vertex {
            continue;
        }
        let triangles = mesh.first_index / 3 - run_first_triangle;
        preparer.parts.push(DrawnPart {
            triangles: triangles..triangles + mesh.triangles(),
            first_vertex,
            vertex_slot: preparer.vertices.len() as u32,
            triangle_slot,
            facing: occluders.fragments.facing(camera, object),
        });
        triangle_slot += mesh.triangles();
        for p in &scene.vertices[first_vertex as usize..=last_vertex as usize] {
            let local = DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
            let position = object.transform.transform_point3(local) - camera.eye;
            preparer.positions.push(position);
            preparer
                .vertices
                .push(projector.project(position, near).map(|(at, view_depth)| {
                    // Off the view's axis, an error in view depth moves it too.
                    let off_axis = (at.x - projector.size.x / 2.0)
                        .abs()
                        .max((at.y - projector.size.y / 2.0).abs());
                    ScreenVertex {
                        at,
                        slack: occluders.snap + position_error * (pixels_at_unit_depth + off_axis) / view_depth,
                        depth_error: position_error / view_depth,
                    }
                }));
        }
    }
    // An error d in eye space moves a point at view depth w on screen by up
    // to f / w · d · (1 + |x| / f) on x (alike on y), x its offset from the
    // view's axis: without bound for a crossing far off screen. But a side
    // through it runs on screen from a placed vertex A, and how far the
    // placed line is from ours changes linearly along it: at a point P on
    // screen, s = |AP| / |AC| of the way to the crossing C, the crossing's
    // part is s · f / w · d · (1 + |C| / f), within f / w · d · (1 + 3 r)
    // as |AP| and |A| are at most the screen's span, r its greatest offset
    // from the axis over f.
    let screen_reach = (projector.size.x + projector.size.y) / 2.0 / pixels_at_unit_depth;
    let positions = &preparer.positions;
    let crossing = |placed: usize, clipped: usize| {
        let (p, q) = (positions[placed], positions[clipped]);
        let (wp, wq) = (projector.view_depth(p), projector.view_depth(q));
        let at = p + (q - p) * ((wp - near) / (wp - wq));
        // At the limit, so well beyond the near plane.
        let (at, _) = projector.project(at, camera.near)?;
        let error = 2.0 * position_error / camera.near;
        Some(ScreenVertex {
            at,
            slack: occluders.snap + error * pixels_at_unit_depth * (1.0 + 3.0 * screen_reach),
            depth_error: error,
        })
    };
    let mesh = ScreenMesh {
        vertices: &preparer.vertices,
        parts: &preparer.parts,
        indices: run_indices(scene, run),
        neighbours: occluders.neighbours.of(run),
        closed: scene.parts[first.part as usize].closed,
        near: Some(NearLimit { crossing: &crossing }),
        snap: occluders.snap,
        depth: occluders.fragments.margins.depth(),
    };
    preparer.patches.add(&mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::recording::{Recording, camera_down_z, cubes, cuboids, input, one_object_a_leaf};
    use crate::hierarchy::Hierarchy;

    #[test]
    fn an_object_covering_fewer_pixels_than_it_has_triangles_is_no_occluder() {
        // A cube 3 m ahead covers thousands of pixels; one 1 km off, far
        // aside, covers a few for its 12 triangles (its box on screen, its
        // pixels rounded outward).
        let (scene, hierarchy) = cubes(&[DVec3::new(-0.5, -0.5, -4.0), DVec3::new(-500.0, -0.5, -1000.0)]);
        let camera = camera_down_z();
        let occluder_triangles = |pixels_per_triangle: &str| {
            let given = ModeParams::parse(
                &[format!("swr.pixels_per_triangle={pixels_per_triangle}")],
                &[ModeId::Swr],
            );
            let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&given.unwrap()).unwrap());
            let mut frame_calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
            let stats: Vec<TraversalStats> = (0..2)
                .map(|frame| swr.frame(&mut frame_calls, &input(frame, &camera, &scene, &hierarchy)))
                .collect();
            assert_eq!(frame_calls.drawn().len(), 4, "both cubes drawn in both frames");
            stats[1].occluder_triangles
        };
        assert_eq!(occluder_triangles("1"), 12, "the near cube alone");
        assert_eq!(occluder_triangles("0"), 24, "both cubes");
        for bad in ["-1", "nan", "inf"] {
            assert!(ModeParams::parse(&[format!("swr.pixels_per_triangle={bad}")], &[ModeId::Swr]).is_err());
        }
    }

    #[test]
    fn an_object_behind_an_occluder_is_drawn_until_the_occluder_is_known_even_as_an_occluder() {
        // A cube 2 m ahead hides one 17 m further on, right behind the
        // middle of its face, where the face's two triangles meet (taken
        // apart, they leave the cells along their shared edge empty); a
        // third stands aside.
        let (scene, hierarchy) = cubes(&[
            DVec3::new(-0.5, -0.5, -3.0),
            DVec3::new(-0.5, -0.5, -20.0),
            DVec3::new(8.0, -0.5, -20.0),
        ]);
        let camera = camera_down_z();
        let params = SwrParams::from_params(&ModeParams::default()).unwrap();
        let mut swr = SoftwareOcclusionCulling::new(params);
        let (mut drawn, mut stats) = (Vec::new(), Vec::new());
        for frame in 0..3 {
            let mut frame_calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
            stats.push(swr.frame(&mut frame_calls, &input(frame, &camera, &scene, &hierarchy)));
            let mut objects = frame_calls.drawn();
            objects.sort_unstable();
            drawn.push(objects);
        }
        // Frame 0 knows no occluder: everything in view. Frame 1 takes those
        // as occluders, finds the far cube hidden behind the near one and
        // does not draw it, though it is an occluder; frame 2 leaves it out
        // of the occluders too.
        assert_eq!(drawn, [vec![0, 1, 2], vec![0, 2], vec![0, 2]]);
        assert_eq!(stats[0].occluder_triangles, 0);
        assert_eq!(stats[1].occluder_triangles, 3 * 12, "the three cubes' triangles");
        assert_eq!(stats[2].occluder_triangles, 2 * 12, "the two visible cubes' triangles");
        assert!(stats[1].nodes_culled_occlusion > 0 && stats[2].nodes_culled_occlusion > 0);

        // Told what another culler drew (as auto tells the culler it
        // probes), its first frame has the near cube as occluder already.
        let mut seeded = SoftwareOcclusionCulling::new(params);
        seeded.seed_visible(&[0, 2]);
        let mut frame_calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
        seeded.frame(&mut frame_calls, &input(0, &camera, &scene, &hierarchy));
        let mut objects = frame_calls.drawn();
        objects.sort_unstable();
        assert_eq!(objects, [0, 2]);
    }

    #[test]
    fn a_box_behind_a_distant_wall_by_more_than_both_fragments_errors_is_hidden_on_gl() {
        // On GL (the margins swr takes until it is prepared) depth keeps
        // only absolute precision: 2 steps of 2^-24 of a fragment's error
        // each for the wall and the cube (`DepthMargins::fragment_error`),
        // with the box's growth (1e-4 of its reach: 0.17 step here) 4.2
        // steps. A cube 5 steps behind a wall 1 km ahead (depth near /
        // distance = 1e-4; a step of depth is 2^-24 · distance² / near,
        // 0.6 m, of distance there) is hidden: a GPU box test would need its
        // full raise, 4 steps, and so 6.2, but swr's test is exact.
        let (distance, near) = (1000.0, camera_down_z().near);
        let gap = 5.0 / f64::from(1u32 << 24) * distance * distance / near;
        let (scene, hierarchy) = cuboids(&[
            (
                DVec3::new(-200.0, -200.0, -distance - 1.0),
                DVec3::new(200.0, 200.0, -distance),
            ),
            (
                DVec3::new(-5.0, -5.0, -distance - gap - 10.0),
                DVec3::new(5.0, 5.0, -distance - gap),
            ),
        ]);
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        assert_eq!(swr.depth_margins, DepthMargins::for_backend(wgpu::Backend::Gl));
        let drawn = drawn_over(&mut swr, &scene, &hierarchy, &camera_down_z(), 3);
        assert_eq!(drawn, [vec![0, 1], vec![0], vec![0]]);
    }

    /// The objects `swr` drew (sorted) in each of `frames` frames of `scene`
    /// seen by `camera`.
    fn drawn_over(
        swr: &mut SoftwareOcclusionCulling,
        scene: &Scene,
        hierarchy: &Hierarchy,
        camera: &Camera,
        frames: u32,
    ) -> Vec<Vec<u32>> {
        (0..frames)
            .map(|frame| {
                let mut calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
                swr.frame(&mut calls, &input(frame, camera, scene, hierarchy));
                let mut objects = calls.drawn();
                objects.sort_unstable();
                objects
            })
            .collect()
    }

    /// Asserts that at every pixel centre `swr`'s buffer vouches for no
    /// depth nearer than where the pixel's ray first enters one of `solids`
    /// (the surfaces drawn, by a slab-test ray caster); returns at how many
    /// it vouches for some depth.
    fn assert_vouches_no_nearer_than(swr: &SoftwareOcclusionCulling, camera: &Camera, solids: &[Aabb]) -> u32 {
        use crate::gpu::{entry_depth, pixel_ray};
        let buffer = swr.buffer.as_ref().unwrap();
        let size = Resolution::DEFAULT;
        let mut vouching = 0;
        for py in 0..size.height {
            for px in 0..size.width {
                let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
                let ray = pixel_ray(camera, size, x, y);
                let drawn = solids
                    .iter()
                    .filter_map(|b| entry_depth(camera, b, ray))
                    .fold(0.0, f64::max);
                let vouched = buffer.vouched_at(x, y);
                assert!(
                    vouched <= drawn,
                    "({x}, {y}): the buffer vouches for {vouched}, the surface is at {drawn}"
                );
                vouching += u32::from(vouched > 0.0);
            }
        }
        vouching
    }

    #[test]
    fn a_floor_reaching_past_the_eye_hides_what_lies_under_it_and_vouches_for_no_depth_nearer_than_its_own() {
        // A floor slab under the eye, reaching 60 m on every side (its
        // triangles cross the near plane), and a box buried under it ahead.
        let boxes = [
            (DVec3::new(-60.0, -1.5, -60.0), DVec3::new(60.0, -1.0, 60.0)),
            (DVec3::new(-1.0, -4.0, -12.0), DVec3::new(1.0, -2.5, -10.0)),
        ];
        let (scene, hierarchy) = cuboids(&boxes);
        let camera = camera_down_z();
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        let drawn = drawn_over(&mut swr, &scene, &hierarchy, &camera, 2);
        // The floor's part in front of the near plane is an occluder: the
        // buried box is not drawn once the floor is known.
        assert_eq!(drawn, [vec![0, 1], vec![0]]);
        // At every pixel centre, what the buffer vouches for is no nearer
        // than where the pixel's ray first enters a box (the surface drawn
        // there), and it vouches for the floor's depth nearly everywhere
        // below the horizon.
        let solids = boxes.map(|(min, max)| Aabb::new(min, max));
        let floor_pixels = assert_vouches_no_nearer_than(&swr, &camera, &solids);
        let size = Resolution::DEFAULT;
        assert!(
            floor_pixels > size.width * size.height * 2 / 5,
            "{floor_pixels} pixels hold the floor"
        );
    }

    #[test]
    fn auto_cells_are_a_pixel_each_after_a_buffer_that_held_little_of_the_screen_and_coarse_again_after_one_that_held_much()
     {
        // A floor under the eye and a box 30 m ahead, 12 m up. Looking up
        // at the box, the buffer holds its pixels and a strip of the far
        // floor; looking ahead, the floor holds most of the screen below
        // the horizon. Frame 0 knows no occluder, and each frame's cells
        // follow what the last buffer held; looking ahead, level, the
        // coarse ones are twice as tall as wide.
        let (scene, hierarchy) = cuboids(&[
            (DVec3::new(-60.0, -1.5, -60.0), DVec3::new(60.0, -1.0, 60.0)),
            (DVec3::new(-1.0, 11.0, -31.0), DVec3::new(1.0, 13.0, -29.0)),
        ]);
        let ahead = camera_down_z();
        let up = Camera {
            rotation: glam::DQuat::from_rotation_x(25f64.to_radians()),
            ..ahead
        };
        // Built every frame (a buffer that hid nothing would rest).
        let params = SwrParams {
            rests: false,
            ..SwrParams::from_params(&ModeParams::default()).unwrap()
        };
        let mut swr = SoftwareOcclusionCulling::new(params);
        let frames: Vec<(Resolution, f64)> = [&up, &up, &up, &ahead, &ahead, &ahead]
            .into_iter()
            .map(|camera| {
                drawn_over(&mut swr, &scene, &hierarchy, camera, 1);
                (swr.buffer.as_ref().unwrap().cells(), swr.held)
            })
            .collect();
        let (coarse, fine) = (COARSE_CELLS, FINE_CELLS);
        assert_eq!(
            frames.iter().map(|f| f.0).collect::<Vec<_>>(),
            [coarse, coarse, fine, fine, LEVEL_CELLS, LEVEL_CELLS],
            "{frames:?}"
        );
        assert!(frames[1].1 > 0.0 && frames[1].1 <= FINE_FROM_COARSE, "{frames:?}");
        assert!(frames[3].1 > FINE_WHERE_HELD, "{frames:?}");
        // The fine buffer waits as the spare.
        assert_eq!(swr.spare.as_ref().map(OcclusionBuffer::cells), Some(fine));
    }

    #[test]
    fn buffers_the_machine_cannot_hold_are_refused_before_they_are_allocated() {
        // 8192 × 8192 cells (2^26) of 8 layers: a pyramid of 16/3 bytes a
        // cell, a reference plane of 24, and 7 working layers of 40.
        let params = |items: &[&str]| {
            let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
            SwrParams::from_params(&ModeParams::parse(&items, &[ModeId::Swr]).unwrap()).unwrap()
        };
        let size = Resolution {
            width: 8192,
            height: 8192,
        };
        let huge = SoftwareOcclusionCulling::new(params(&["swr.resolution=8192x8192", "swr.layers=8"]));
        let need = huge.buffers_need(size);
        assert_eq!(need, (1u64 << 26) * 16 / 3 + (1 << 26) * (24 + 7 * 40));
        let error = buffers_fit(need, Some(4 << 30)).unwrap_err();
        assert!(error.is_input_error());
        assert_eq!(
            error.to_string(),
            "swr's CPU depth buffers need about 19798 MiB, and this machine lets occlu take 4096 MiB more: take fewer swr.layers or a coarser swr.resolution"
        );
        assert!(
            buffers_fit(need, None).is_ok(),
            "where the system does not say, allocation decides"
        );
        // auto's two buffers at 800x600 with 4 layers: 68 and 17 MiB.
        let auto = SoftwareOcclusionCulling::new(params(&[]));
        let need = auto.buffers_need(Resolution::DEFAULT);
        assert_eq!(need.div_ceil(1 << 20), 86);
        assert!(buffers_fit(need, Some(4 << 30)).is_ok());
    }

    #[test]
    fn a_camera_looks_level_where_the_scenes_upright_lines_lean_little_anywhere_on_screen() {
        // 60° high at 4:3: the corners lie 0.77 across and 0.58 up or
        // down of the centre, over distance.
        let ahead = camera_down_z();
        let turned = |x: f64, y: f64, z: f64| Camera {
            rotation: glam::DQuat::from_euler(glam::EulerRot::YXZ, y.to_radians(), x.to_radians(), z.to_radians()),
            ..ahead
        };
        assert!(looks_level(&ahead, DVec3::Y));
        assert!(
            looks_level(&ahead, DVec3::NEG_Y),
            "upside down, upright lines stay upright"
        );
        assert!(
            looks_level(&turned(0.0, 70.0, 0.0), DVec3::Y),
            "turned about the up axis"
        );
        // Turned and looking down 12°: 0.19 (taken the wrong way round,
        // camera to world, the turn would tilt it to 0.28).
        assert!(looks_level(&turned(-12.0, 60.0, 0.0), DVec3::Y));
        // Looking 10° down, a line at a corner leans 0.77 sin 10° over
        // cos 10° - 0.58 sin 10°: 0.15; 20° down, 0.35.
        assert!(looks_level(&turned(-10.0, 0.0, 0.0), DVec3::Y));
        assert!(!looks_level(&turned(-20.0, 0.0, 0.0), DVec3::Y));
        assert!(!looks_level(&turned(20.0, 0.0, 0.0), DVec3::Y));
        // Rolled, every upright line leans by the roll's tangent: 0.18 at
        // 10°, 0.36 at 20°.
        assert!(looks_level(&turned(0.0, 0.0, 10.0), DVec3::Y));
        assert!(!looks_level(&turned(0.0, 0.0, 20.0), DVec3::Y));
        // Looking straight down, upright lines meet on screen.
        assert!(!looks_level(&turned(-90.0, 0.0, 0.0), DVec3::Y));
        // A Z-up scene: looking along -z is looking straight down on it,
        // and along +y (pitched up 90°, so the camera's up is +z) level.
        assert!(!looks_level(&ahead, DVec3::Z));
        assert!(looks_level(&turned(90.0, 0.0, 0.0), DVec3::Z));
    }

    #[test]
    fn a_wall_cut_into_clusters_hides_what_lies_behind_it_as_one_surface() {
        use crate::scene::builtin::shapes::cuboid;
        use crate::scene::{SceneBuilder, TriangleSoup};
        // A wall 4 m wide and 3 m high, 5 m ahead, of 96 × 72 squares
        // (each about 4 pixels across) cut into clusters of 512 triangles,
        // and a box behind its middle. The first cuts run across the
        // middle; the wall is moved half a pixel right and down, so that
        // they run through pixel centres.
        let half_a_pixel = 0.5 * 5.0 * (30f64.to_radians().tan() / 300.0);
        let corner = DVec3::new(-2.0 + half_a_pixel, -1.5 - half_a_pixel, -5.0);
        let wall = TriangleSoup::grid(corner, DVec3::X * 4.0, DVec3::Y * 3.0, [96, 72]);
        let mut behind = TriangleSoup::default();
        let (box_min, box_max) = (DVec3::new(-0.5, -0.5, -9.0), DVec3::new(0.5, 0.5, -8.0));
        cuboid(&mut behind, box_min, box_max);
        let mut builder = SceneBuilder::new("test wall".into(), 512);
        for (name, soup) in [("wall", &wall), ("box", &behind)] {
            let group = builder.add_mesh(name, &soup.positions, &soup.indices).unwrap();
            builder.add_object(name, &group, DAffine3::IDENTITY).unwrap();
        }
        let (scene, hierarchy) = one_object_a_leaf(builder.finish().unwrap());
        let the_box = scene.objects.len() as u32 - 1;
        assert!(the_box >= 16, "the wall is cut into {the_box} clusters");
        let camera = camera_down_z();
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        let drawn = drawn_over(&mut swr, &scene, &hierarchy, &camera, 2);
        let box_drawn: Vec<bool> = drawn.iter().map(|objects| objects.contains(&the_box)).collect();
        // Once the wall is known, the box behind it is not drawn: its
        // clusters' shared edges leave no seam the box could be seen
        // through.
        assert_eq!(box_drawn, [true, false]);
        // And at every pixel centre the buffer vouches for no depth nearer
        // than where the pixel's ray first meets the wall or the box.
        let solids = [
            Aabb::new(corner, corner + DVec3::new(4.0, 3.0, 0.0)),
            Aabb::new(box_min, box_max),
        ];
        assert_vouches_no_nearer_than(&swr, &camera, &solids);
    }

    /// The occluder triangles `swr` rasterised in each of `frames` frames of
    /// `cubes` seen down −Z, each frame told that its previous one drew
    /// its triangles at `ms_a_triangle`, and the objects each frame drew.
    /// Three cubes side by side, none behind another.
    const SIDE_BY_SIDE: [DVec3; 3] = [
        DVec3::new(-4.0, -0.5, -10.0),
        DVec3::new(-0.5, -0.5, -10.0),
        DVec3::new(3.0, -0.5, -10.0),
    ];

    /// Each frame's occluder triangles and drawn objects, where every frame
    /// takes `frame_ms` and drawing a triangle `ms_a_triangle` of it.
    fn rasterised_and_drawn(
        cubes_at: &[DVec3],
        frames: u32,
        frame_ms: f64,
        ms_a_triangle: f64,
    ) -> (Vec<u64>, Vec<Vec<u32>>) {
        let (scene, hierarchy) = cubes(cubes_at);
        let camera = camera_down_z();
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        let (mut rasterised, mut drawn) = (Vec::new(), Vec::<Vec<u32>>::new());
        for frame in 0..frames {
            let mut calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
            let previous = drawn.last().map(|objects| {
                let triangles = 12 * objects.len() as u64;
                PreviousFrame {
                    frame_ms,
                    render_ms: triangles as f64 * ms_a_triangle,
                    triangles_drawn: triangles,
                }
            });
            let stats = swr.frame(
                &mut calls,
                &FrameInput {
                    previous,
                    ..input(frame, &camera, &scene, &hierarchy)
                },
            );
            rasterised.push(stats.occluder_triangles);
            let mut objects = calls.drawn();
            objects.sort_unstable();
            drawn.push(objects);
        }
        if rasterised.last() == Some(&0) {
            assert!(
                swr.buffer.as_ref().unwrap().depths().iter().all(|&d| d == 0.0),
                "a resting buffer is empty"
            );
        }
        (rasterised, drawn)
    }

    #[test]
    fn a_resting_buffers_frame_is_frustum_cullings_own_in_what_it_visits_and_the_order_it_draws() {
        // Side by side, nothing hidden, and a cube behind the eye (so the
        // traversal meets nodes partly in the frustum and one outside):
        // frames 2 to 8 rest (as below) and are vfc's, fully-inside
        // shortcut included; frame 9 builds a buffer again from them.
        let behind = DVec3::new(-0.5, -0.5, 10.0);
        let (scene, hierarchy) = cubes(&[SIDE_BY_SIDE[0], SIDE_BY_SIDE[1], SIDE_BY_SIDE[2], behind]);
        let camera = camera_down_z();
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        let mut vfc = crate::cull::FrustumCulling::new(&scene);
        let recording = || Recording::new(|_: &Aabb| -> bool { panic!("neither asks the GPU anything") });
        for frame in 0..10 {
            let (mut calls, mut vfc_calls) = (recording(), recording());
            let previous = PreviousFrame {
                frame_ms: 1e3,
                render_ms: 36.0,
                triangles_drawn: 36,
            };
            let frame_input = || FrameInput {
                previous: Some(previous),
                ..input(frame, &camera, &scene, &hierarchy)
            };
            let stats = swr.frame(&mut calls, &frame_input());
            let vfc_stats = vfc.frame(&mut vfc_calls, &frame_input());
            let counts = |s: &TraversalStats| (s.nodes_visited, s.nodes_culled_frustum, s.nodes_culled_occlusion);
            // It says so (`auto` then takes it as `vfc`'s).
            assert_eq!(swr.frustum_only(), (2..9).contains(&frame), "frame {frame}");
            if (2..9).contains(&frame) {
                assert_eq!(stats.occluder_triangles, 0, "frame {frame} rests");
                assert_eq!(calls.drawn(), vfc_calls.drawn(), "frame {frame}");
                assert_eq!(counts(&stats), counts(&vfc_stats), "frame {frame}");
            }
        }
        // Frame 9 built a buffer again, of the three cubes frame 8 drew.
        assert_eq!(swr.occluders.len(), 3);
        assert!(swr.buffer.as_ref().unwrap().depths().iter().any(|&d| d > 0.0));
    }

    #[test]
    fn a_buffer_that_hides_nothing_rests_seven_frames_then_fifteen_then_thirty_one() {
        let (rasterised, drawn) = rasterised_and_drawn(&SIDE_BY_SIDE, 60, 1e3, 1.0);
        assert!(drawn.iter().all(|objects| objects == &[0, 1, 2]));
        // Frame 0 knows no occluder; frame 1's hide nothing, so frames 2 to
        // 8 build no buffer; frame 9 tries again and fails, so 10 to 24
        // rest; 25 fails, and 26 to 56 rest; 57 tries again.
        let tried: Vec<usize> = (0..rasterised.len()).filter(|&f| rasterised[f] > 0).collect();
        assert_eq!(tried, [1, 9, 25, 57]);
        assert!(tried.iter().all(|&f| rasterised[f] == 36));
    }

    /// Six cubes in a column down −X from the eye, the nearest hiding the
    /// rest.
    fn column_down_x() -> impl Iterator<Item = DVec3> {
        (0..6).map(|k| DVec3::new(-3.0 - 2.0 * f64::from(k), -0.5, -0.5))
    }

    /// Which of `frames` frames `swr` rested in, and what each drew, over
    /// cubes at `corners`, the eye at the origin looking down −X where
    /// `looks_down_x` says and down −Z elsewhere; every frame takes 10 ms,
    /// and drawing a triangle `ms_a_triangle` of it.
    fn rests_while_turning(
        corners: &[DVec3],
        frames: u32,
        looks_down_x: impl Fn(u32) -> bool,
        ms_a_triangle: f64,
    ) -> (Vec<bool>, Vec<Vec<u32>>) {
        let (scene, hierarchy) = cubes(corners);
        let down_z = camera_down_z();
        let down_x = Camera {
            rotation: glam::DQuat::from_rotation_y(90f64.to_radians()),
            ..down_z
        };
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        let (mut rested, mut drawn) = (Vec::new(), Vec::<Vec<u32>>::new());
        for frame in 0..frames {
            let camera = if looks_down_x(frame) { &down_x } else { &down_z };
            let mut calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
            let previous = drawn.last().map(|objects| {
                let triangles = 12 * objects.len() as u64;
                PreviousFrame {
                    frame_ms: 10.0,
                    render_ms: triangles as f64 * ms_a_triangle,
                    triangles_drawn: triangles,
                }
            });
            swr.frame(
                &mut calls,
                &FrameInput {
                    previous,
                    ..input(frame, camera, &scene, &hierarchy)
                },
            );
            let mut objects = calls.drawn();
            objects.sort_unstable();
            drawn.push(objects);
            rested.push(swr.frustum_only());
        }
        (rested, drawn)
    }

    #[test]
    fn a_rest_ends_where_the_frustum_outgrows_the_one_whose_buffer_did_not_pay() {
        // Down −Z, one cube, nothing behind it: frame 1's buffer hides
        // nothing, so 2 to 8 would rest. From frame 3 the eye looks down
        // −X along the column (six times the triangles).
        let corners: Vec<DVec3> = std::iter::once(DVec3::new(-0.5, -0.5, -3.0))
            .chain(column_down_x())
            .collect();
        let (rested, drawn) = rests_while_turning(&corners, 6, |frame| frame >= 3, 1.0);
        assert_eq!(rested, [false, false, true, false, false, false]);
        // Frame 3 takes the column in its frustum as occluders (last
        // frame's cube is off screen), and the nearest cube hides the rest.
        assert!(drawn[3..].iter().all(|objects| objects == &[1]), "{drawn:?}");
    }

    #[test]
    fn a_rest_counts_what_the_failed_buffer_hid_as_in_its_frustum() {
        // Down −X, the column: the nearest cube hides five, but drawing
        // costs next to nothing, so the buffer does not pay (frame 1) and
        // 2 to 8 rest. Its frustum held the six (72 triangles), twelve of
        // them drawn. From frame 3 the eye looks down −Z at five cubes
        // side by side (60 triangles): over four times what was drawn,
        // not over four times what the frustum held, so the rest goes on.
        let row = (0..5).map(|k| DVec3::new(-4.0 + 2.0 * f64::from(k), -0.5, -10.0));
        let corners: Vec<DVec3> = column_down_x().chain(row).collect();
        let (rested, _) = rests_while_turning(&corners, 5, |frame| frame < 3, 1e-12);
        assert_eq!(rested, [false, false, true, true, true]);
    }

    #[test]
    fn a_buffer_that_pays_brings_the_rests_back_to_the_shortest() {
        let mut rest = Rest::default();
        // Which frames of `frames` rest, each buffer paying as `pays` says.
        let mut run = |frames: u32, pays: &dyn Fn(u32) -> bool| -> Vec<u32> {
            (0..frames)
                .filter(|&f| {
                    let resting = rest.take();
                    if !resting {
                        rest.after(pays(f), 0.0, 0);
                    }
                    resting
                })
                .collect()
        };
        // Fails at 0 (rests 1-7), at 8 (9-23), pays at 24, fails at 25
        // (rests 26-32: seven again, not 31).
        let resting = run(40, &|f| f == 24 || f > 25);
        let expected: Vec<u32> = (1..8).chain(9..24).chain(26..33).collect();
        assert_eq!(resting, expected);
        // Told to start over (a culler seeded by another), it rests no more.
        let mut swr = SoftwareOcclusionCulling::new(SwrParams::from_params(&ModeParams::default()).unwrap());
        swr.rest.after(false, 0.0, 0);
        swr.seed_visible(&[]);
        assert!(!swr.rest.take());
    }

    #[test]
    fn a_buffer_that_costs_much_of_a_frame_rests_as_long_as_its_share_of_the_time_pays_for() {
        // Half a frame: 34 frames' 1.5 % pay for it; a hundredth of one, the
        // schedule's 7; a NaN, the schedule too.
        for (cost, rest) in [(0.5, 34), (0.01, 7), (f64::NAN, 7)] {
            let mut rests = Rest::default();
            rests.after(false, cost, 0);
            assert_eq!(rests.left, rest, "{cost}");
        }
        // The cubes side by side hide nothing, on frames so light that a
        // buffer costs many of them: it rests the longest, 127 frames.
        let (rasterised, _) = rasterised_and_drawn(&SIDE_BY_SIDE, 140, 1e-9, 1e-12);
        let tried: Vec<usize> = (0..rasterised.len()).filter(|&f| rasterised[f] > 0).collect();
        assert_eq!(tried, [1, 129]);
    }

    #[test]
    fn a_buffer_that_hides_less_drawing_than_it_costs_rests_and_one_that_hides_more_does_not() {
        // A near cube hides the one behind it; a third stands aside.
        let one_behind = [
            DVec3::new(-0.5, -0.5, -3.0),
            DVec3::new(-0.5, -0.5, -20.0),
            DVec3::new(8.0, -0.5, -20.0),
        ];
        // Drawing a triangle costs next to nothing: hiding 12 of them saves
        // less than the buffer costs, so it rests after each try (7, then
        // 15 frames: the buffer costs little of the frame's second),
        // drawing the hidden cube meanwhile.
        let (rasterised, drawn) = rasterised_and_drawn(&one_behind, 28, 1e3, 1e-12);
        let tried: Vec<usize> = (0..rasterised.len()).filter(|&f| rasterised[f] > 0).collect();
        assert_eq!(tried, [1, 9, 25]);
        for (f, objects) in drawn.iter().enumerate() {
            let hid = tried.contains(&f);
            assert_eq!(objects, &if hid { vec![0, 2] } else { vec![0, 1, 2] }, "frame {f}");
        }
        // Drawing a triangle costs a second: the buffer pays every frame.
        let (rasterised, drawn) = rasterised_and_drawn(&one_behind, 28, 1e5, 1e3);
        assert_eq!(rasterised[..3], [0, 36, 24]);
        assert!(rasterised[2..].iter().all(|&t| t == 24));
        assert!(drawn[1..].iter().all(|objects| objects == &[0, 2]));
    }

    #[test]
    fn a_box_found_hidden_lies_behind_what_the_buffer_vouches_for_wherever_a_pixel_ray_meets_it() {
        use crate::camera::look_rotation;
        // The ray through a pixel centre and where it enters a box, from
        // the field of view and a slab test alone.
        use crate::gpu::{entry_depth, pixel_ray};
        use crate::rng::Rng;
        let mut rng = Rng::new(23);
        let size = Resolution {
            width: 401,
            height: 299,
        };
        let camera = Camera {
            eye: DVec3::new(3.0, 2.0, 10.0),
            rotation: look_rotation(DVec3::new(-0.3, -0.2, -1.0), DVec3::Y),
            fov_y: 60f64.to_radians(),
            near: 0.1,
            aspect: size.aspect(),
        };
        let (view, frustum) = (camera.view_rotation(), camera.frustum());
        let projector = Projector::new(&camera, size);
        // Walls: rectangles 20 to 200 m ahead, facing the eye at a slant.
        let walls: Vec<[DVec3; 4]> = (0..12)
            .map(|_| {
                let along = rng.range(20.0, 200.0);
                let centre = camera.eye
                    + camera.rotation * DVec3::new(rng.range(-0.5, 0.5) * along, rng.range(-0.4, 0.4) * along, -along);
                let facing = camera.rotation * DVec3::new(rng.range(-0.8, 0.8), rng.range(-0.8, 0.8), 1.0);
                let side = facing.cross(DVec3::Y).normalize() * rng.range(2.0, 0.3 * along);
                let up = side.cross(facing).normalize() * rng.range(2.0, 0.3 * along);
                [
                    centre - side - up,
                    centre + side - up,
                    centre + side + up,
                    centre - side + up,
                ]
            })
            .collect();
        let (mut tested, mut hidden, mut by_planes) = (0, 0, 0);
        for cells in [Resolution { width: 97, height: 61 }, size] {
            let mut buffer = OcclusionBuffer::new(size, cells);
            let meshes: Vec<_> = walls
                .iter()
                .filter_map(|wall| {
                    let on_screen = wall.map(|c| projector.project(c - camera.eye, camera.near).map(|(p, _)| p));
                    let [Some(a), Some(b), Some(c), Some(d)] = on_screen else {
                        return None;
                    };
                    let corners = [a, b, c, d].map(|at| ScreenVertex {
                        at,
                        slack: SubpixelPrecision::COARSEST.vertex_error(size),
                        depth_error: 0.0,
                    });
                    Some((corners.to_vec(), vec![0, 1, 2, 0, 2, 3]))
                })
                .collect();
            mesh::rasterise_meshes(&mut buffer, &meshes);
            buffer.build_pyramid();
            let tester = Tester {
                buffer: &buffer,
                projector: &projector,
                rays: PixelRays::new(&camera, size),
                camera: &camera,
                view: &view,
                margins: BoxMargins::new(
                    DepthMargins::for_backend(wgpu::Backend::Vulkan),
                    SubpixelPrecision::COARSEST,
                    &camera,
                    size,
                )
                .for_exact_tests(),
            };
            for k in 0..1500 {
                // Sides from 1 cm (flat boxes) to 30 m; every other box just
                // behind a wall (by 0.05 to 5 % of its distance), the rest
                // anywhere 1 to 300 m ahead.
                let half = DVec3::new(rng.range(0.005, 15.0), rng.range(0.005, 15.0), rng.range(0.005, 15.0));
                let (centre, half) = if k % 2 == 0 {
                    let wall = &walls[k / 2 % walls.len()];
                    let on_wall = wall[0]
                        .lerp(wall[1], rng.range(0.0, 1.0))
                        .lerp(wall[3].lerp(wall[2], rng.range(0.0, 1.0)), rng.range(0.0, 1.0));
                    let (away, distance) = ((on_wall - camera.eye).normalize(), on_wall.distance(camera.eye));
                    let half = half * rng.range(0.001, 0.1) * distance / half.length();
                    let gap = rng.range(0.0005, 0.05) * distance;
                    (on_wall + away * (half.length() + gap), half)
                } else {
                    let along = rng.range(1.0, 300.0);
                    let offset = DVec3::new(rng.range(-0.6, 0.6) * along, rng.range(-0.45, 0.45) * along, -along);
                    (camera.eye + camera.rotation * offset, half)
                };
                let b = Aabb::new(centre - half, centre + half);
                if frustum.classify(&b) == Containment::Outside {
                    continue;
                }
                tested += 1;
                if tester.test(&b) != Verdict::Hidden {
                    continue;
                }
                hidden += 1;
                // Whether its nearest corner alone would have hidden it.
                if let EyeBox::Testable(q) = eye_relative_box(&camera, &view, tester.margins, &b)
                    && let Some(on_screen) = projector.box_on_screen(&q)
                    && !buffer.hides(
                        on_screen.first,
                        on_screen.last,
                        on_screen.nearest,
                        &BoxPlanes::default(),
                    )
                {
                    by_planes += 1;
                }
                for py in 0..size.height {
                    for px in 0..size.width {
                        let (x, y) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
                        if let Some(depth) = entry_depth(&camera, &b, pixel_ray(&camera, size, x, y)) {
                            let vouched = buffer.vouched_at(x, y);
                            assert!(
                                depth < vouched,
                                "{cells:?}: {b:?} enters at depth {depth} at ({x}, {y}), where the buffer vouches for {vouched}"
                            );
                        }
                    }
                }
            }
        }
        assert!(hidden > 300 && hidden < tested, "{hidden} of {tested} hidden");
        assert!(by_planes > 100, "{by_planes} of them hidden only by their planes");
    }

    #[test]
    fn threads_leave_the_buffer_and_the_drawn_objects_exactly_as_one_thread_does() {
        use crate::camera::generate::default_path;
        use crate::hierarchy::{Hierarchy, HierarchyParams};
        use crate::scene::{LoadOptions, SceneSpec, load};
        let scene = load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let path = default_path(&scene).and_then(|(p, _)| p.with_frames(24)).unwrap();
        let mut runs = [1, 2, 5].map(|threads| {
            let params = ModeParams::parse(&[format!("swr.threads={threads}")], &[ModeId::Swr]).unwrap();
            SoftwareOcclusionCulling::new(SwrParams::from_params(&params).unwrap())
        });
        let mut shared_out = 0;
        for frame in 0..24 {
            let camera = path.camera(frame, Resolution::DEFAULT.aspect());
            let seen: Vec<_> = runs
                .iter_mut()
                .map(|swr| {
                    let mut calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
                    let stats = swr.frame(&mut calls, &input(frame, &camera, &scene, &hierarchy));
                    let planes = swr.buffer.as_ref().map(|b| b.planes().to_vec());
                    (calls.drawn(), stats, swr.occluder_depths(), planes)
                })
                .collect();
            assert!(seen.iter().all(|s| *s == seen[0]), "frame {frame}");
            // Enough for two threads at least.
            if seen[0].1.occluder_triangles >= TRIANGLES_PER_THREAD {
                shared_out += 1;
            }
        }
        assert!(shared_out > 10, "{shared_out} frames had occluders enough to share out");
    }

    #[test]
    fn threads_and_layers_are_refused_beyond_their_caps_and_threads_used_only_where_the_budget_gives_them_work() {
        let params = |items: &[&str]| {
            let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
            let parsed = ModeParams::parse(&items, &[ModeId::Swr]).map_err(|e| e.to_string())?;
            SwrParams::from_params(&parsed).map_err(|e| e.to_string())
        };
        let error = params(&["swr.threads=65"]).unwrap_err();
        assert!(error.contains("at most 64"), "{error}");
        assert_eq!(
            params(&["swr.threads=64"]).unwrap().threads_used(),
            17,
            "65536 triangles: 17 threads' work"
        );
        assert_eq!(
            params(&["swr.threads=64", "swr.triangles=100"]).unwrap().threads_used(),
            1
        );
        assert_eq!(params(&["swr.threads=3"]).unwrap().threads_used(), 3);
        for refused in ["swr.layers=0", "swr.layers=9"] {
            let error = params(&[refused]).unwrap_err();
            assert!(error.contains("from 1 to 8"), "{error}");
        }
        assert_eq!(params(&["swr.layers=8"]).unwrap().layers, 8);
    }

    #[test]
    fn the_error_meter_catches_a_buffer_that_breaks_the_conservative_rule() {
        use crate::cull::culler::Labeled;
        use crate::gpu::GpuContext;
        use crate::hierarchy::HierarchyParams;
        use crate::stress::{cases, run_case};
        // Cubes seen only through slits 1.2 pixels wide (stress case
        // `slits`): cells of 3 pixels that the wall covers in the middle
        // but not at the slit.
        let case = cases::all().into_iter().find(|c| c.name == "slits").unwrap();
        let size = case.resolution.unwrap();
        for gpu in &GpuContext::every_adapter() {
            // Buffers built every frame, whatever they cost.
            let params = SwrParams {
                rests: false,
                ..SwrParams::from_params(&ModeParams::default()).unwrap()
            };
            let careful = SoftwareOcclusionCulling::new(params);
            let careless = SoftwareOcclusionCulling {
                careless: true,
                ..SoftwareOcclusionCulling::new(params)
            };
            let mut cullers: Vec<Box<dyn Culler>> = vec![
                Box::new(careful),
                Box::new(Labeled {
                    label: "careless".into(),
                    inner: Box::new(careless),
                }),
            ];
            let outcome = run_case(
                gpu,
                &case,
                &HierarchyParams::default(),
                &mut cullers,
                size,
                false,
                &mut |_| {},
            )
            .unwrap();
            let total = |mode: &str, f: fn(&crate::measure::FrameStats) -> Option<u64>| -> u64 {
                outcome.rows.iter().filter(|r| r.mode == mode).filter_map(f).sum()
            };
            let at = &gpu.adapter;
            assert_eq!(total("swr", |r| r.error_pixels), 0, "{at}");
            assert_eq!(total("swr", |r| r.missed_objects), 0, "{at}");
            assert!(
                total("careless", |r| r.missed_objects) > 0,
                "{at}: the careless buffer hides a cube"
            );
            assert!(total("careless", |r| r.error_pixels) > 0, "{at}");
        }
    }
}
