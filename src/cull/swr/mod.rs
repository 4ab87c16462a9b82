//! `swr`: CPU software occlusion culling, the family Intel's Masked
//! Software Occlusion Culling (O3DE), Godot 4's occlusion culling and Umbra
//! belong to: occluders are rasterised on the CPU into a small depth buffer
//! and boxes tested against it, so culling never waits for the GPU and
//! reads nothing back. Each frame, on the CPU:
//!
//! 1. **Occluders**: last frame's visible objects, largest on screen first,
//!    while their triangles fit `swr.triangles`. They are drawn this frame
//!    whatever the test below finds, so the buffer holds only depth that
//!    really is on screen.
//! 2. **Rasterise** their triangles, projected in f64, into a buffer of
//!    `swr.resolution` cells, conservatively (buffer.rs: a cell takes a
//!    triangle's farthest depth over the pixels it holds, and only where the
//!    triangle covers all of them, with the GPU's snapping and f32 error as
//!    margins); triangles reaching the near plane are left out (fewer
//!    occluders is always safe). A cell is written only by a triangle that
//!    covers it whole, so meshes of triangles about a cell's size occlude
//!    little (MOC's coverage masks merge such triangles).
//! 3. **Pyramid** of the buffer's farthest depths.
//! 4. **Test**: the hierarchy is walked as `vfc` walks it; a node in the
//!    frustum is also tested by its box (grown and raised as every box test
//!    here, gpu/conservative.rs): its screen rectangle's pixels, rounded
//!    outward, against the farthest depth of the cells holding them. A
//!    hidden node stops its subtree; a box reaching the near plane is
//!    visible. A leaf's objects are tested one by one.
//! 5. **Draw** the visible objects not already drawn as occluders; the
//!    visible objects are next frame's occluder candidates.
//!
//! Departures: MOC keeps coverage masks per tile with two depths (its
//! "masked" buffer) and rasterises with SIMD over threads; this first
//! version is a plain buffer of cells, one depth each, rasterised scalar on
//! one thread (issue 21 asks for the rest). Occluders are whole visible
//! objects (MOC and Godot take authored occluder meshes).

mod buffer;

use glam::{DMat3, DMat4, DVec2, DVec3, Vec4Swizzles};
use serde::Serialize;

use crate::bounds::Aabb;
use crate::camera::{Camera, Containment};
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{BoxMargins, DepthMargins, EyeBox, Frame, GpuError, GpuSetup, QueryBox, Resolution, eye_relative_box};
use crate::scene::Scene;
use buffer::{OcclusionBuffer, ScreenTriangle, VertexError};

/// This mode's entry in the registry.
pub(super) const MODE: ModeInfo = ModeInfo {
    id: ModeId::Swr,
    summary: "CPU software occlusion culling: last frame's visible objects rasterised conservatively into a small depth buffer on the CPU, the hierarchy's boxes tested against it (Intel's MOC, Godot, Umbra)",
    conservative: true,
    params: &[RESOLUTION, TRIANGLES],
    needs: Needs::Nothing,
    check: |params| SwrParams::from_params(params).map(drop),
    build: |scene, params| {
        Ok(Box::new(SoftwareOcclusionCulling::new(
            scene,
            SwrParams::from_params(params)?,
        )))
    },
};

const RESOLUTION: ParamInfo = ParamInfo {
    key: "resolution",
    default: "256x192",
    summary: "cells of the CPU depth buffer, WxH (at most the render size on each side)",
};

const TRIANGLES: ParamInfo = ParamInfo {
    key: "triangles",
    default: "32768",
    summary: "occluder triangles rasterised a frame at most: last frame's visible objects, largest on screen first",
};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SwrParams {
    pub resolution: Resolution,
    pub triangles: u64,
}

impl SwrParams {
    pub fn from_params(params: &ModeParams) -> Result<SwrParams, ModeError> {
        Ok(SwrParams {
            resolution: params.get(ModeId::Swr, &RESOLUTION)?,
            triangles: params.get(ModeId::Swr, &TRIANGLES)?,
        })
    }
}

pub struct SoftwareOcclusionCulling {
    params: SwrParams,
    /// Made for the frame's render size, and again when it changes.
    buffer: Option<OcclusionBuffer>,
    /// The backend's depth margins, known once prepared (GL's, the larger,
    /// until then).
    depth_margins: DepthMargins,
    /// Whether its buffers break the conservative rule on purpose
    /// ([`OcclusionBuffer::careless`]).
    #[cfg(test)]
    careless: bool,
    /// The objects found visible last frame.
    visible: Vec<u32>,
    /// Scratch, reused so a frame allocates nothing once warm.
    candidates: Vec<(f64, u32)>,
    /// An occluder's vertices on screen, each projected once.
    projected: Vec<Option<(DVec3, f64)>>,
    occluders: Vec<u32>,
    is_occluder: Vec<bool>,
    found: Vec<u32>,
    to_draw: Vec<u32>,
    stack: Vec<u32>,
}

impl SoftwareOcclusionCulling {
    pub fn new(scene: &Scene, params: SwrParams) -> Self {
        SoftwareOcclusionCulling {
            params,
            buffer: None,
            depth_margins: DepthMargins::for_backend(wgpu::Backend::Gl),
            #[cfg(test)]
            careless: false,
            visible: Vec::new(),
            candidates: Vec::new(),
            projected: Vec::new(),
            occluders: Vec::new(),
            is_occluder: vec![false; scene.objects.len()],
            found: Vec::new(),
            to_draw: Vec::new(),
            stack: Vec::new(),
        }
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

    /// A tested box on screen; `None` where a corner does not project to
    /// a finite point (then nothing can be said of it: it is visible).
    fn box_on_screen(&self, q: &QueryBox) -> Option<BoxOnScreen> {
        let (min, max) = (q.min.xyz().as_dvec3(), q.max.xyz().as_dvec3());
        let (mut low, mut high, mut nearest) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
        for corner in 0..8 {
            let pick = |bit: u32, axis: usize| if corner & bit != 0 { max[axis] } else { min[axis] };
            let clip = self.view_projection * DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2)).extend(1.0);
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

/// A tested box on screen.
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
    camera: &'a Camera,
    view: &'a DMat3,
    margins: BoxMargins,
}

impl Tester<'_> {
    /// `bounds` (in the frustum) against the buffer.
    fn test(&self, bounds: &Aabb) -> Verdict {
        let on_screen = match eye_relative_box(self.camera, self.view, self.margins, bounds) {
            EyeBox::ReachesNear => None,
            EyeBox::Testable(q) => self.projector.box_on_screen(&q),
        };
        match on_screen {
            // Hidden only when strictly behind.
            Some(b) if b.nearest < f64::from(self.buffer.farthest_over(b.first, b.last)) => Verdict::Hidden,
            _ => Verdict::Visible,
        }
    }
}

impl Culler for SoftwareOcclusionCulling {
    fn name(&self) -> &str {
        "swr"
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::json!(self.params)
    }

    fn traverses_hierarchy(&self) -> bool {
        true
    }

    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        self.depth_margins = setup.gpu.depth_margins;
        Ok(())
    }

    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let (camera, scene, size) = (input.camera, input.scene, input.resolution);
        let mut stats = TraversalStats::default();
        let buffer = match &mut self.buffer {
            Some(b) if b.target() == size => b,
            slot => slot.insert(OcclusionBuffer::new(size, self.params.resolution)),
        };
        #[cfg(test)]
        {
            buffer.careless = self.careless;
        }
        let projector = Projector::new(camera, size);
        let margins = BoxMargins::new(self.depth_margins, camera, size);
        let view = camera.view_rotation();

        let frustum = camera.frustum();

        // 1. Occluders: last frame's visible objects still on screen,
        // largest first.
        self.candidates.clear();
        for &o in &self.visible {
            let bounds = &scene.objects[o as usize].bounds;
            if frustum.classify(bounds) == Containment::Outside {
                continue;
            }
            let area = match eye_relative_box(camera, &view, margins, bounds) {
                EyeBox::ReachesNear => f64::INFINITY,
                EyeBox::Testable(q) => projector.box_on_screen(&q).map_or(0.0, |b| b.area),
            };
            if area > 0.0 {
                self.candidates.push((area, o));
            }
        }
        self.candidates
            .sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        self.occluders.clear();
        let mut budget = self.params.triangles;
        for &(_, o) in &self.candidates {
            let triangles = u64::from(scene.objects[o as usize].triangles);
            if triangles <= budget {
                budget -= triangles;
                self.occluders.push(o);
                self.is_occluder[o as usize] = true;
            }
        }
        ctx.draw(&self.occluders);

        // 2-3. Their triangles into the buffer, then the pyramid.
        buffer.clear();
        for &o in &self.occluders {
            stats.occluder_triangles += rasterise_object(buffer, &projector, camera, scene, o, &mut self.projected);
        }
        buffer.build_pyramid();

        // 4. The hierarchy, in the frustum and not hidden.
        let tester = Tester {
            buffer,
            projector: &projector,
            camera,
            view: &view,
            margins,
        };
        let hierarchy = input.hierarchy;
        self.found.clear();
        self.stack.clear();
        self.stack.push(0);
        while let Some(index) = self.stack.pop() {
            let node = &hierarchy.nodes[index as usize];
            stats.nodes_visited += 1;
            if frustum.classify(&node.bounds) == Containment::Outside {
                stats.nodes_culled_frustum += 1;
                continue;
            }
            if tester.test(&node.bounds) == Verdict::Hidden {
                stats.nodes_culled_occlusion += 1;
                continue;
            }
            if !node.is_leaf() {
                self.stack.extend(node.children().map(|c| c as u32));
                continue;
            }
            for &o in hierarchy.subtree_objects(node) {
                let bounds = &scene.objects[o as usize].bounds;
                if frustum.classify(bounds) != Containment::Outside && tester.test(bounds) == Verdict::Visible {
                    self.found.push(o);
                }
            }
        }

        // 5. The visible objects not drawn yet; they are next frame's
        // candidates.
        self.to_draw.clear();
        self.to_draw
            .extend(self.found.iter().filter(|&&o| !self.is_occluder[o as usize]));
        ctx.draw(&self.to_draw);
        for &o in &self.occluders {
            self.is_occluder[o as usize] = false;
        }
        std::mem::swap(&mut self.visible, &mut self.found);
        stats
    }
}

/// The GPU's error in an f32 vertex position, as a fraction of the
/// object's reach from the eye: 4 steps of 2^-24.
const F32_POSITION_ERROR: f64 = 4.0 / (1u32 << 24) as f64;

/// Rasterises object `o`'s triangles (placed where the scene has it this
/// frame) into `buffer`; returns how many it rasterised.
///
/// The GPU transforms the object's f32 vertices by an f32 model-view whose
/// translation is about as long as the object's reach from the eye, so its
/// corners may land a few steps of 2^-24 of that reach from ours: that
/// error, over the corner's view depth, in pixels and in relative depth, is
/// the triangle's [`VertexError`]. Triangles with a corner within that
/// error (and 2^-10 of the near distance) of the near plane are left out:
/// the GPU may clip them.
///
/// Each vertex is projected once, into `projected` (reused scratch).
fn rasterise_object(
    buffer: &mut OcclusionBuffer,
    projector: &Projector,
    camera: &Camera,
    scene: &Scene,
    o: u32,
    projected: &mut Vec<Option<(DVec3, f64)>>,
) -> u64 {
    let object = &scene.objects[o as usize];
    let (min, max) = (object.bounds.min - camera.eye, object.bounds.max - camera.eye);
    let position_error = F32_POSITION_ERROR * min.abs().max(max.abs()).max_element();
    let near = camera.near * (1.0 + 1.0 / 1024.0) + position_error;
    let pixels_at_unit_depth = projector.size.y / (2.0 * (camera.fov_y / 2.0).tan());
    let mesh = &scene.meshes[object.mesh as usize];
    let indices = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
    // A mesh's indices reach a run of vertices; each is projected once.
    let (first, last) = indices
        .iter()
        .fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    projected.clear();
    if first <= last {
        projected.extend(scene.vertices[first as usize..=last as usize].iter().map(|p| {
            let local = DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
            projector.project(object.transform.transform_point3(local) - camera.eye, near)
        }));
    }
    let mut rasterised = 0;
    for corners in indices.chunks_exact(3) {
        let on_screen = [0, 1, 2].map(|k| projected[(corners[k] - first) as usize]);
        if let [Some((a, wa)), Some((b, wb)), Some((c, wc))] = on_screen {
            let nearest = wa.min(wb).min(wc);
            let error = VertexError {
                pixels: position_error * pixels_at_unit_depth / nearest,
                depth: position_error / nearest,
            };
            buffer.rasterise(&ScreenTriangle {
                corners: [a, b, c],
                error,
            });
            rasterised += 1;
        }
    }
    rasterised
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::recording::{Recording, camera_down_z, cubes, input};

    #[test]
    fn an_object_behind_an_occluder_is_drawn_until_the_occluder_is_known_and_each_object_once() {
        // A cube 2 m ahead hides one 17 m further on; a third stands aside.
        // The far one shows within one triangle of the near one's face: a
        // cell is written only by a triangle covering it whole, so cells on
        // the face's diagonal stay empty (see the module's doc).
        let (scene, hierarchy) = cubes(&[
            DVec3::new(-0.5, -0.5, -3.0),
            DVec3::new(-0.5, 2.6, -20.0),
            DVec3::new(8.0, -0.5, -20.0),
        ]);
        let camera = camera_down_z();
        let params = SwrParams::from_params(&ModeParams::default()).unwrap();
        let mut swr = SoftwareOcclusionCulling::new(&scene, params);
        let (mut drawn, mut stats) = (Vec::new(), Vec::new());
        for frame in 0..3 {
            let mut frame_calls = Recording::new(|_: &Aabb| -> bool { panic!("swr asks the GPU nothing") });
            stats.push(swr.frame(&mut frame_calls, &input(frame, &camera, &scene, &hierarchy)));
            let mut objects = frame_calls.drawn();
            objects.sort_unstable();
            drawn.push(objects);
        }
        // Frame 0 knows no occluder: everything in view. Frame 1 draws those
        // as occluders and finds the far cube hidden; frame 2 leaves it out.
        assert_eq!(drawn, [vec![0, 1, 2], vec![0, 1, 2], vec![0, 2]]);
        assert_eq!(stats[0].occluder_triangles, 0);
        assert_eq!(stats[2].occluder_triangles, 2 * 12, "the two visible cubes' triangles");
        assert!(stats[1].nodes_culled_occlusion > 0 && stats[2].nodes_culled_occlusion > 0);
    }

    #[test]
    fn the_error_meter_catches_a_buffer_that_breaks_the_conservative_rule() {
        use crate::cull::culler::Labeled;
        use crate::gpu::{BackendChoice, GpuContext};
        use crate::hierarchy::HierarchyParams;
        use crate::stress::{cases, run_case};
        // Cubes seen only through slits 1.2 pixels wide (stress case
        // `slits`): cells of 3 pixels that the wall covers in the middle
        // but not at the slit.
        let case = cases::all().into_iter().find(|c| c.name == "slits").unwrap();
        let size = case.resolution.unwrap();
        let gpus: Vec<GpuContext> = [BackendChoice::Vulkan, BackendChoice::Gl]
            .into_iter()
            .filter_map(|b| GpuContext::new(b).ok())
            .collect();
        assert!(!gpus.is_empty(), "no adapter: install Mesa (scripts/install-deps)");
        for gpu in &gpus {
            let params = SwrParams::from_params(&ModeParams::default()).unwrap();
            let careful = SoftwareOcclusionCulling::new(&case.scene, params);
            let careless = SoftwareOcclusionCulling {
                careless: true,
                ..SoftwareOcclusionCulling::new(&case.scene, params)
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
