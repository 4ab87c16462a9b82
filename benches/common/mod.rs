//! What the benchmarks share: the built-in scenes they run, and each one's
//! default walk.

use occlu::camera::Camera;
use occlu::camera::generate::default_path;
use occlu::gpu::Resolution;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

/// Heavy occlusion at two sizes, and little occlusion.
pub const SCENES: [&str; 3] = ["city:blocks=8", "city:blocks=16", "forest"];

/// Frames of each walk.
pub const FRAMES: u32 = 120;

/// Built-in scene `spec`, its hierarchy, and the cameras of its default
/// walk over [`FRAMES`] frames at the default render size's aspect.
pub fn walk(spec: &str) -> (Scene, Hierarchy, Vec<Camera>) {
    let scene = load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).expect("built-in scene");
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = default_path(&scene)
        .and_then(|(p, _)| p.with_frames(FRAMES))
        .expect("built-in walk");
    let cameras = (0..FRAMES)
        .map(|i| path.camera(i, Resolution::DEFAULT.aspect()))
        .collect();
    (scene, hierarchy, cameras)
}
