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
//!    triangle covers all of them); triangles reaching the near plane are
//!    left out (fewer occluders is always safe).
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

use glam::{DMat4, DVec2, DVec3, Vec4Swizzles};
use serde::Serialize;

use crate::camera::{Camera, Containment};
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::{ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
use crate::gpu::{BoxMargins, DepthMargins, EyeBox, Frame, GpuError, GpuSetup, QueryBox, Resolution, eye_relative_box};
use crate::scene::Scene;
pub use buffer::{OcclusionBuffer, ScreenTriangle};

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
    #[serde(serialize_with = "as_text")]
    pub resolution: Resolution,
    pub triangles: u64,
}

fn as_text<S: serde::Serializer>(r: &Resolution, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(r)
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
    /// The objects found visible last frame.
    visible: Vec<u32>,
    /// Scratch, reused so a frame allocates nothing once warm.
    candidates: Vec<(f64, u32)>,
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
            visible: Vec::new(),
            candidates: Vec::new(),
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

    /// The eye-relative point `p` on screen: (x, y) in pixels, z its depth;
    /// `None` nearer than `near` along the view (or behind the eye).
    fn project(&self, p: DVec3, near: f64) -> Option<DVec3> {
        let clip = self.view_projection * p.extend(1.0);
        if clip.w.is_nan() || clip.w < near {
            return None;
        }
        let ndc = clip.xyz() / clip.w;
        Some(DVec3::new(
            (ndc.x * 0.5 + 0.5) * self.size.x,
            (0.5 - ndc.y * 0.5) * self.size.y,
            ndc.z,
        ))
    }

    /// A tested box's pixels (first and last, x and y, clamped to the
    /// target), its screen area in pixels and its nearest depth, raised.
    fn box_on_screen(&self, q: &QueryBox) -> ([u32; 2], [u32; 2], f64, f64) {
        let (min, max) = (q.min.xyz().as_dvec3(), q.max.xyz().as_dvec3());
        let (mut low, mut high, mut nearest) = (DVec2::INFINITY, DVec2::NEG_INFINITY, f64::NEG_INFINITY);
        for corner in 0..8 {
            let pick = |bit: u32, axis: usize| if corner & bit != 0 { max[axis] } else { min[axis] };
            let clip = self.view_projection * DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2)).extend(1.0);
            let ndc = clip.xyz() / clip.w;
            let pixel = DVec2::new((ndc.x * 0.5 + 0.5) * self.size.x, (0.5 - ndc.y * 0.5) * self.size.y);
            low = low.min(pixel);
            high = high.max(pixel);
            nearest = nearest.max(ndc.z + f64::from(q.min.w));
        }
        let clamp = |v: f64, side: f64| v.floor().clamp(0.0, side - 1.0) as u32;
        let first = [clamp(low.x, self.size.x), clamp(low.y, self.size.y)];
        let last = [clamp(high.x, self.size.x), clamp(high.y, self.size.y)];
        let seen = (high.min(self.size) - low.max(DVec2::ZERO)).max(DVec2::ZERO);
        (first, last, seen.x * seen.y, nearest)
    }
}

/// How a box stands against the buffer.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Hidden,
    Visible,
}

/// `bounds` (in the frustum) tested against `buffer` for `camera`.
fn test_box(
    buffer: &OcclusionBuffer,
    projector: &Projector,
    camera: &Camera,
    margins: BoxMargins,
    bounds: &crate::bounds::Aabb,
) -> Verdict {
    match eye_relative_box(camera, &camera.view_rotation(), margins, bounds) {
        EyeBox::ReachesNear => Verdict::Visible,
        EyeBox::Testable(q) => {
            let (first, last, _, nearest) = projector.box_on_screen(&q);
            // Hidden only when strictly behind; a NaN is visible.
            if nearest < f64::from(buffer.farthest_over(first, last)) {
                Verdict::Hidden
            } else {
                Verdict::Visible
            }
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
        let projector = Projector::new(camera, size);
        let margins = BoxMargins::new(self.depth_margins, camera, size);
        let view = camera.view_rotation();

        // 1. Occluders: last frame's visible objects, largest first.
        self.candidates.clear();
        for &o in &self.visible {
            let area = match eye_relative_box(camera, &view, margins, &scene.objects[o as usize].bounds) {
                EyeBox::ReachesNear => f64::INFINITY,
                EyeBox::Testable(q) => projector.box_on_screen(&q).2,
            };
            self.candidates.push((area, o));
        }
        self.candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
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
            stats.occluder_triangles += rasterise_object(buffer, &projector, camera, scene, o);
        }
        buffer.build_pyramid();

        // 4. The hierarchy, in the frustum and not hidden.
        let frustum = camera.frustum();
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
            if test_box(buffer, &projector, camera, margins, &node.bounds) == Verdict::Hidden {
                stats.nodes_culled_occlusion += 1;
                continue;
            }
            if !node.is_leaf() {
                self.stack.extend(node.children().map(|c| c as u32));
                continue;
            }
            for &o in hierarchy.subtree_objects(node) {
                let bounds = &scene.objects[o as usize].bounds;
                if frustum.classify(bounds) != Containment::Outside
                    && test_box(buffer, &projector, camera, margins, bounds) == Verdict::Visible
                {
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

/// Rasterises object `o`'s triangles (placed where the scene has it this
/// frame) into `buffer`; returns how many it rasterised (those reaching the
/// near plane are left out).
fn rasterise_object(
    buffer: &mut OcclusionBuffer,
    projector: &Projector,
    camera: &Camera,
    scene: &Scene,
    o: u32,
) -> u64 {
    let object = &scene.objects[o as usize];
    let mesh = &scene.meshes[object.mesh as usize];
    let indices = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
    let to_eye = |v: u32| {
        let p = scene.vertices[v as usize];
        object
            .transform
            .transform_point3(DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])))
            - camera.eye
    };
    let mut rasterised = 0;
    for corners in indices.chunks_exact(3) {
        let on_screen = [0, 1, 2].map(|k| projector.project(to_eye(corners[k]), camera.near));
        if let [Some(a), Some(b), Some(c)] = on_screen {
            buffer.rasterise(&ScreenTriangle([a, b, c]));
            rasterised += 1;
        }
    }
    rasterised
}
