//! The frustum test of single objects on the GPU, which keeps a walk from
//! drawing what `vfc` leaves out: last frame's visible objects that have
//! left the frustum (drawn early, as occluders, without a test) and the
//! objects of a visible bottom-depth node that lie outside it (marked with
//! their node). `cs_early_frustum` takes the first out of the early list,
//! `cs_compact` the second out of the marks (walk.wgsl). The same frame, and
//! boxes of the same form (the objects', or the tree nodes'), make every
//! tested box of every walk on the GPU (prepare_nodes.wgsl), so its CPU
//! hands over only the camera.
//! object_frustum.wgsl holds what those passes share, bound as group 3.
//!
//! Each object's box is uploaded once as its centre in two f32 parts (high
//! and low, as large-world renderers keep positions) and its half extent
//! rounded up, and again only when the object moves; each frame brings the
//! eye in two parts and the frustum's planes. The shader makes the centre
//! eye-relative part by part, so a box 1e7 from the origin is tested as
//! precisely as one beside it.
//!
//! Precision, counting each f32 operation as one unit in the last place
//! (2^-23, what WGSL, Vulkan and GLSL ES promise; round-to-nearest halves
//! it): the eye-relative centre is within 3 · 2^-23 of the reach (the box's
//! largest eye-relative coordinate) on each axis, and within 2^-44 of the
//! larger of the eye's and the centre's distance from the origin for the low
//! parts ([`GPU_ABSOLUTE_ERROR`]); dotted with a unit normal (‖n‖₁ ≤ √3),
//! with the normal's own rounding, the extent rounded up and the plane sum's
//! six roundings, the test's value is within 17 · 2^-23 ≈ [`GPU_ERROR`] =
//! 2.4e-6 of the reach, plus the absolute part, of the exact one. An object
//! is outside where the value falls below −([`GPU_OUTSIDE_SLACK`] = 3e-6 of
//! the reach plus the absolute part), so it is truly outside (the slack
//! exceeds the error), and every object `vfc` finds outside (by
//! [`OUTSIDE_SLACK`], 6e-6, at least the slack plus the error) is, but for
//! boxes whose reach from the eye is under about 1e-7 of their distance
//! from the origin (0.7 m at 1e7), where the absolute part dominates.

use glam::DVec3;

use std::cell::Cell;
use std::rc::Rc;

use crate::bounds::Aabb;
use crate::camera::{Camera, OUTSIDE_SLACK};
use crate::cull::last_frame::{LastFrame, Since};
use crate::gpu::{
    BoxMargins, GpuContext, GpuError, bind_buffers, bind_group_layout, check_storage_binding, storage_buffer,
};
use crate::scene::Scene;

/// Relative slack of the GPU's outside test (see the module's header).
pub(super) const GPU_OUTSIDE_SLACK: f64 = 3e-6;
/// Bound on the GPU test's error, relative to the box's reach.
pub(super) const GPU_ERROR: f64 = 2.4e-6;
/// Bound on the error the low parts' rounding adds, relative to the eye's or
/// the box's distance from the origin (2^-44), both in the slack.
pub(super) const GPU_ABSOLUTE_ERROR: f64 = 1.0 / (1u64 << 44) as f64;

const _: () = assert!(GPU_OUTSIDE_SLACK > GPU_ERROR && OUTSIDE_SLACK >= GPU_OUTSIDE_SLACK + GPU_ERROR);

/// An object's box as walk.wgsl's `ObjectBox` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct ObjectBox {
    centre_high: [f32; 4],
    centre_low: [f32; 4],
    /// Half the box's size on each axis, rounded up.
    extent: [f32; 4],
}

/// The frame's eye, frustum and box margins as object_frustum.wgsl's
/// `ObjectFrustum` reads them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct ShaderFrustum {
    eye_high: [f32; 4],
    eye_low: [f32; 4],
    /// Each plane's inward unit normal (xyz) and offset (w), eye-centred.
    planes: [[f32; 4]; 5],
    /// The view direction (xyz) and the near distance (w).
    forward: [f32; 4],
    /// [`BoxMargins::for_shader`].
    margins: [f32; 4],
}

/// Every object's box on the GPU, as object_frustum.wgsl's `object_boxes`
/// reads it, and the frame whose poses it holds. Kept with a walk's
/// `VisibleLists`, so the walks that share those share one upload.
pub(super) struct ObjectBoxes {
    buffer: wgpu::Buffer,
    made_for: Cell<LastFrame>,
}

impl ObjectBoxes {
    /// For `objects` objects, none uploaded yet; fails where the adapter
    /// cannot bind a box for each.
    pub(super) fn new(gpu: &GpuContext, objects: u32) -> Result<ObjectBoxes, GpuError> {
        let bytes = u64::from(objects.max(1)) * size_of::<ObjectBox>() as u64;
        check_storage_binding(gpu, "storage binding for the objects' boxes (bytes)", bytes)?;
        Ok(ObjectBoxes {
            buffer: storage_buffer(gpu, "object boxes", bytes, wgpu::BufferUsages::COPY_DST),
            made_for: Cell::new(LastFrame::default()),
        })
    }
}

/// The objects' boxes on the GPU (shared with the walks that share them)
/// and the frame's frustum, for one walk.
pub(super) struct ObjectFrustum {
    boxes: Rc<ObjectBoxes>,
    frustum: wgpu::Buffer,
    /// Group 3 of the passes that read them, and its layout.
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) group: wgpu::BindGroup,
    /// Staged on the CPU, written in [`ObjectFrustum::write`]: the frustum,
    /// and the objects whose boxes changed, in increasing order, with their
    /// boxes.
    staged_frustum: ShaderFrustum,
    staged_objects: Vec<u32>,
    staged_boxes: Vec<ObjectBox>,
}

impl ObjectFrustum {
    /// Over `boxes`, which it keeps up to date.
    pub(super) fn new(gpu: &GpuContext, boxes: Rc<ObjectBoxes>) -> ObjectFrustum {
        let copy = wgpu::BufferUsages::COPY_DST;
        let frustum = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("object frustum"),
            size: size_of::<ShaderFrustum>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | copy,
            mapped_at_creation: false,
        });
        let layout = bind_group_layout(
            gpu,
            "object frustum",
            &[
                (
                    wgpu::ShaderStages::COMPUTE,
                    wgpu::BufferBindingType::Storage { read_only: true },
                ),
                (wgpu::ShaderStages::COMPUTE, wgpu::BufferBindingType::Uniform),
            ],
        );
        ObjectFrustum {
            group: bind_buffers(gpu, &layout, &[&boxes.buffer, &frustum]),
            layout,
            boxes,
            frustum,
            staged_frustum: ShaderFrustum::default(),
            staged_objects: Vec::new(),
            staged_boxes: Vec::new(),
        }
    }

    /// On the CPU, before frame `frame`: stages `camera`'s frustum and the
    /// frame's box `margins`, and the boxes of the objects `moved` since the
    /// previous frame (of every mover where no walk sharing the boxes ran in
    /// it; none where one ran in this frame already).
    pub(super) fn prepare(&mut self, camera: &Camera, margins: BoxMargins, scene: &Scene, moved: &[u32], frame: u32) {
        let (eye, planes) = camera.frustum().planes();
        let (eye_high, eye_low) = split(eye);
        let forward = camera.forward().as_vec3();
        self.staged_frustum = ShaderFrustum {
            eye_high,
            eye_low,
            planes: planes.map(|(n, offset)| [n.x as f32, n.y as f32, n.z as f32, offset as f32]),
            forward: [forward.x, forward.y, forward.z, camera.near as f32],
            margins: margins.for_shader(camera),
        };
        // Every box in the first frame; after a gap in the frames the boxes
        // were made for, every mover's (the only objects that ever change);
        // else those that moved since the frame before.
        self.staged_objects.clear();
        let mut made_for = self.boxes.made_for.get();
        match made_for.advance(frame) {
            Since::First => self.staged_objects.extend(0..scene.objects.len() as u32),
            Since::Gap => self.staged_objects.extend(scene.movers.iter().map(|m| m.object)),
            Since::Next => self.staged_objects.extend_from_slice(moved),
            Since::Same => {}
        }
        self.boxes.made_for.set(made_for);
        self.staged_objects.sort_unstable();
        self.staged_boxes.clear();
        let boxes = self
            .staged_objects
            .iter()
            .map(|&o| object_box(&scene.objects[o as usize].bounds));
        self.staged_boxes.extend(boxes);
    }

    /// Every object's box, as object_frustum.wgsl's `object_boxes`.
    pub(super) fn boxes(&self) -> &wgpu::Buffer {
        &self.boxes.buffer
    }

    /// Writes what [`ObjectFrustum::prepare`] staged.
    pub(super) fn write(&self, gpu: &GpuContext) {
        gpu.queue
            .write_buffer(&self.frustum, 0, bytemuck::bytes_of(&self.staged_frustum));
        let size = size_of::<ObjectBox>() as u64;
        // Consecutive objects in one write: every object at once in the
        // first frame, a few for the movers.
        let ids = &self.staged_objects;
        let mut start = 0;
        while start < ids.len() {
            let end = (start + 1..ids.len())
                .find(|&k| ids[k] != ids[k - 1] + 1)
                .unwrap_or(ids.len());
            let boxes = bytemuck::cast_slice(&self.staged_boxes[start..end]);
            gpu.queue
                .write_buffer(&self.boxes.buffer, u64::from(ids[start]) * size, boxes);
            start = end;
        }
    }
}

/// `v` as f32 high parts and the f32 remainders, the w's 0.
fn split(v: DVec3) -> ([f32; 4], [f32; 4]) {
    let high = v.as_vec3();
    let low = (v - high.as_dvec3()).as_vec3();
    ([high.x, high.y, high.z, 0.0], [low.x, low.y, low.z, 0.0])
}

/// `b` as its centre in two parts and its half extent, rounded up.
pub(super) fn object_box(b: &Aabb) -> ObjectBox {
    let (centre_high, centre_low) = split((b.min + b.max) / 2.0);
    let half = (b.max - b.min) / 2.0;
    let up = |x: f64| {
        let r = x as f32;
        if f64::from(r) < x { r.next_up() } else { r }
    };
    ObjectBox {
        centre_high,
        centre_low,
        extent: [up(half.x), up(half.y), up(half.z), 0.0],
    }
}

/// What the GPU's test says of `b` from `camera`, computed in f64: `Some`
/// outside or not, `None` where its value lies within the GPU's error of the
/// slack, so the f32 test may say either (the twin of walk.wgsl's
/// `outside_frustum`).
#[cfg(test)]
pub(super) fn gpu_verdict(camera: &Camera, b: &Aabb) -> Option<bool> {
    let (eye, planes) = camera.frustum().planes();
    let world_centre = (b.min + b.max) / 2.0;
    let (centre, half) = (world_centre - eye, (b.max - b.min) / 2.0);
    let reach = (centre.abs() + half).max_element();
    let absolute = GPU_ABSOLUTE_ERROR * eye.abs().max(world_centre.abs()).max_element();
    let least = planes
        .iter()
        .map(|&(n, offset)| n.dot(centre) + n.abs().dot(half) + offset)
        .fold(f64::INFINITY, f64::min);
    let margin = least + GPU_OUTSIDE_SLACK * reach + absolute;
    (margin.abs() > GPU_ERROR * reach + absolute).then_some(margin < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::gpu_walk::VisibleLists;
    use crate::gpu::{BackendChoice, DrawRange};
    use crate::scene::{LoadOptions, SceneSpec, load};

    #[test]
    fn walks_that_share_lists_stage_each_frames_boxes_once() {
        let scene = load(
            &SceneSpec::Builtin("city:blocks=1,movers=4".into()),
            &LoadOptions::default(),
        )
        .unwrap();
        let gpu = GpuContext::new(BackendChoice::Auto).unwrap();
        let draw = DrawRange {
            first_index: 0,
            index_count: 3,
        };
        let lists = VisibleLists::new(&gpu, &vec![draw; scene.objects.len()]).unwrap();
        let [mut a, mut b] = [0, 1].map(|_| ObjectFrustum::new(&gpu, lists.boxes.clone()));
        let camera = Camera {
            eye: DVec3::new(0.0, 50.0, 0.0),
            rotation: crate::camera::look_rotation(DVec3::NEG_Y, DVec3::Z),
            fov_y: 1.0,
            near: 0.1,
            aspect: 1.0,
        };
        let margins = BoxMargins::new(
            gpu.depth_margins,
            gpu.subpixel,
            &camera,
            crate::gpu::Resolution::DEFAULT,
        );
        let movers: Vec<u32> = scene.movers.iter().map(|m| m.object).collect();
        let staged = |walk: &mut ObjectFrustum, frame: u32, moved: &[u32]| {
            walk.prepare(&camera, margins, &scene, moved, frame);
            walk.staged_objects.clone()
        };
        let every: Vec<u32> = (0..scene.objects.len() as u32).collect();
        // The first frame's boxes go once, whichever walk makes them; a
        // walk after another in its frame stages nothing.
        assert_eq!(staged(&mut a, 0, &[]), every);
        assert_eq!(staged(&mut b, 0, &[]), Vec::<u32>::new());
        assert_eq!(staged(&mut a, 1, &movers[..1]), &movers[..1]);
        // b follows a's frame: only what moved since.
        assert_eq!(staged(&mut b, 2, &movers[1..2]), &movers[1..2]);
        // After frames no walk made boxes for, every mover's.
        assert_eq!(staged(&mut a, 5, &movers[2..3]), movers);
        assert_eq!(staged(&mut a, 6, &[]), Vec::<u32>::new());
    }

    #[test]
    fn boxes_split_into_parts_that_sum_to_their_centre_and_cover_their_extent() {
        let b = Aabb {
            min: DVec3::new(1e7 + 0.123_456_789, -3.5, 0.1),
            max: DVec3::new(1e7 + 2.987_654_321, 4.25, 0.100_000_001),
        };
        let o = object_box(&b);
        let centre = (b.min + b.max) / 2.0;
        for axis in 0..3 {
            let sum = f64::from(o.centre_high[axis]) + f64::from(o.centre_low[axis]);
            // The low part rounds what the high one leaves (2^-48 of it).
            let within = GPU_ABSOLUTE_ERROR / 8.0 * centre[axis].abs();
            assert!(
                (sum - centre[axis]).abs() <= within,
                "axis {axis}: {sum} for {}",
                centre[axis]
            );
            let half = (b.max[axis] - b.min[axis]) / 2.0;
            assert!(f64::from(o.extent[axis]) >= half, "axis {axis} covers");
            assert!(
                f64::from(o.extent[axis]) <= half * (1.0 + 1e-7),
                "axis {axis} by a step"
            );
        }
    }
}
