//! A recording double of [`Frame`] for unit tests of a mode's logic, with
//! no GPU: it records what the mode drew and each batch of boxes it
//! tested, and answers every test by a rule the test gives. Also the
//! scenes and inputs such tests run on.

use glam::{DQuat, DVec3};

use crate::bounds::Aabb;
use crate::camera::Camera;
use crate::cull::culler::FrameInput;
use crate::gpu::{BoxTest, BoxVisibility, Frame, GpuFrame, Resolution};
use crate::hierarchy::{Hierarchy, HierarchyParams};
use crate::scene::builtin::shapes::cuboid;
use crate::scene::{Scene, SceneBuilder, TriangleSoup};

/// Pixels a visible box reports, visible and in all (so its ratio is 1).
pub const PIXELS: u64 = 100;

/// One call a mode made, in order.
#[derive(Clone, Debug, PartialEq)]
pub enum Call {
    Draw(Vec<u32>),
    /// A batch of boxes tested: one round trip.
    Test(Vec<Aabb>),
}

/// The double: `visible` answers whether a tested box shows.
pub struct Recording<F: FnMut(&Aabb) -> bool> {
    /// Every call, in order.
    pub calls: Vec<Call>,
    visible: F,
}

impl<F: FnMut(&Aabb) -> bool> Recording<F> {
    pub fn new(visible: F) -> Self {
        Recording {
            calls: Vec::new(),
            visible,
        }
    }

    /// Every object drawn, in order.
    pub fn drawn(&self) -> Vec<u32> {
        let draws = self.calls.iter().filter_map(|c| match c {
            Call::Draw(objects) => Some(objects),
            Call::Test(_) => None,
        });
        draws.flatten().copied().collect()
    }

    /// Every batch of boxes tested, in order.
    pub fn batches(&self) -> Vec<&[Aabb]> {
        let tests = self.calls.iter().filter_map(|c| match c {
            Call::Test(boxes) => Some(boxes.as_slice()),
            Call::Draw(_) => None,
        });
        tests.collect()
    }

    fn answer(&mut self, boxes: &[Aabb], out: &mut Vec<BoxVisibility>) {
        self.calls.push(Call::Test(boxes.to_vec()));
        out.clear();
        for b in boxes {
            out.push(BoxVisibility::Samples(if (self.visible)(b) { PIXELS } else { 0 }));
        }
    }
}

impl<F: FnMut(&Aabb) -> bool> Frame for Recording<F> {
    fn draw(&mut self, objects: &[u32]) {
        self.calls.push(Call::Draw(objects.to_vec()));
    }

    fn test_boxes(&mut self, boxes: &[Aabb], _kind: BoxTest, out: &mut Vec<BoxVisibility>) {
        self.answer(boxes, out);
    }

    fn test_boxes_with_totals(
        &mut self,
        boxes: &[Aabb],
        _sampling: u32,
        out: &mut Vec<BoxVisibility>,
        totals: &mut Vec<u64>,
    ) {
        self.answer(boxes, out);
        totals.clear();
        totals.resize(boxes.len(), PIXELS);
    }

    fn on_gpu(&mut self) -> Option<&mut dyn GpuFrame> {
        None
    }
}

/// A scene of unit cubes whose lowest corners are `corners`, one object
/// each, and a hierarchy over it with one object per leaf.
pub fn cubes(corners: &[DVec3]) -> (Scene, Hierarchy) {
    let boxes: Vec<(DVec3, DVec3)> = corners.iter().map(|&c| (c, c + DVec3::ONE)).collect();
    cuboids(&boxes)
}

/// One object per cuboid `(min, max)`, each in a leaf of its own.
pub fn cuboids(boxes: &[(DVec3, DVec3)]) -> (Scene, Hierarchy) {
    let mut builder = SceneBuilder::new("test cuboids".into(), 4096);
    for (k, &(min, max)) in boxes.iter().enumerate() {
        let mut soup = TriangleSoup::default();
        cuboid(&mut soup, min, max);
        let name = format!("cube{k}");
        let group = builder
            .add_mesh(&name, &soup.positions, &soup.indices)
            .expect("a cuboid is valid geometry");
        builder
            .add_object(&name, &group, glam::DAffine3::IDENTITY)
            .expect("test cuboids lie within range");
    }
    one_object_a_leaf(builder.finish().expect("at least one cuboid"))
}

/// `scene` and a hierarchy over it with one object per leaf.
pub fn one_object_a_leaf(scene: Scene) -> (Scene, Hierarchy) {
    let params = HierarchyParams {
        max_leaf_objects: 1,
        ..HierarchyParams::default()
    };
    let hierarchy = Hierarchy::build(&scene.objects, &params);
    (scene, hierarchy)
}

/// A camera at the origin looking down −Z, 60° high, 4:3.
pub fn camera_down_z() -> Camera {
    Camera {
        eye: DVec3::ZERO,
        rotation: DQuat::IDENTITY,
        fov_y: 60f64.to_radians(),
        near: 0.1,
        aspect: 4.0 / 3.0,
    }
}

/// Frame `frame`'s input: `scene` and `hierarchy` seen by `camera` at
/// 800×600, nothing moved.
pub fn input<'a>(frame: u32, camera: &'a Camera, scene: &'a Scene, hierarchy: &'a Hierarchy) -> FrameInput<'a> {
    FrameInput {
        frame,
        camera,
        resolution: Resolution::DEFAULT,
        scene,
        hierarchy,
        moved: &[],
        reference_visible: None,
        previous: None,
        warm_up: false,
    }
}
