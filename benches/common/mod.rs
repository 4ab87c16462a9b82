//! What the benchmarks share: the built-in scenes they run, each one's
//! default walk, a generated scan, medians.
#![allow(dead_code)] // each benchmark uses its own subset

use glam::DVec3;
use occlu::camera::Camera;
use occlu::camera::generate::default_path;
use occlu::gpu::Resolution;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

/// Heavy occlusion at two sizes, little occlusion, and an interior.
pub const SCENES: [&str; 4] = ["city:blocks=8", "city:blocks=16", "forest", "office"];

/// Frames of each walk.
pub const FRAMES: u32 = 120;

/// Scene `spec` (a model file where one of that name exists, otherwise a
/// built-in scene), its hierarchy, and the cameras of its default walk
/// over [`FRAMES`] frames at the default render size's aspect.
pub fn walk(spec: &str) -> (Scene, Hierarchy, Vec<Camera>) {
    let source = match std::path::Path::new(spec).is_file() {
        true => SceneSpec::File(spec.into()),
        false => SceneSpec::Builtin(spec.into()),
    };
    let scene = load(&source, &LoadOptions::default()).expect("bench scene");
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = default_path(&scene)
        .and_then(|(p, _)| p.with_frames(FRAMES))
        .expect("built-in walk");
    let cameras = (0..FRAMES)
        .map(|i| path.camera(i, Resolution::DEFAULT.aspect()))
        .collect();
    (scene, hierarchy, cameras)
}

pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// A closed bumpy sphere as a scan gives it: a cube of `n`×`n` quads a face,
/// projected onto the sphere with equal angles (so triangles are about the
/// same size everywhere) and pushed in and out along the radius by a few
/// per cent; vertices shared, every triangle wound outward.
pub fn scan(n: u32) -> (Vec<DVec3>, Vec<u32>) {
    let mut ids = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |lattice: [u32; 3]| {
        *ids.entry(lattice).or_insert_with(|| {
            let cube = DVec3::from_array(
                lattice.map(|i| (std::f64::consts::FRAC_PI_4 * (2.0 * f64::from(i) / f64::from(n) - 1.0)).tan()),
            );
            let d = cube.normalize();
            let radius = 1.0 + 0.04 * (7.0 * d.x).sin() * (5.0 * d.y).cos() + 0.02 * (11.0 * d.z).sin();
            positions.push(d * radius);
            positions.len() as u32 - 1
        })
    };
    let mut indices = Vec::with_capacity(36 * (n * n) as usize);
    for axis in 0..3 {
        for side in [0, n] {
            // (u, v) run so that u × v points out of the cube.
            let (mut u, mut v) = ((axis + 1) % 3, (axis + 2) % 3);
            if side == 0 {
                std::mem::swap(&mut u, &mut v);
            }
            let at = |a: u32, b: u32| {
                let mut lattice = [side; 3];
                lattice[u] = a;
                lattice[v] = b;
                lattice
            };
            for a in 0..n {
                for b in 0..n {
                    let [p00, p10, p11, p01] =
                        [at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)].map(&mut vertex);
                    indices.extend([p00, p10, p11, p00, p11, p01]);
                }
            }
        }
    }
    (positions, indices)
}
