//! `swr`'s buffer vouches, at every pixel it holds, for no depth nearer
//! than the GPU draws there: its depths held against the reference depth,
//! pixel by pixel, on each backend present. The scene is den-haag.obj on
//! its orbit (../shared/models): buildings about 1 km away with the near
//! plane at 0.1, so reverse-Z depths near 1e-4, where GL keeps only the
//! absolute precision of numbers near 1 (docs/box-tests.md, rule 1): the
//! margins of an occluder's depth (swr/mesh.rs, `DEPTH_MARGIN` and the
//! backend's `DepthMargins`) are what keep the buffer behind what the GPU
//! draws. So is leaving out of the patches a triangle the fragment stage
//! may discard (mesh.rs, `kept`): without it, one pixel of frame 3 fails
//! on Vulkan.
//! The whole orbit is checked, each frame after the one before, as a run
//! takes them (`swr`'s occluders are last frame's visible objects).

mod common;

use common::{cannot_run, gpus, hierarchy, shared_models_dir};
use occlu::camera::path::CameraPath;
use occlu::cull::{Culler, ModeParams, create};
use occlu::gpu::Resolution;
use occlu::scene::{LoadOptions, SceneSpec, load};
use occlu::session::{RunOptions, Session};
use occlu::world::World;

/// One cell a pixel, so a cell's depth is its triangles' plane at the
/// pixel's centre (no farther corner of a larger cell to hide behind).
const SIZE: Resolution = Resolution::DEFAULT;

#[test]
fn swrs_buffer_vouches_for_no_depth_nearer_than_the_gpu_draws_at_any_pixel_of_a_distant_city() {
    let dir = shared_models_dir();
    let (model, path) = (dir.join("den-haag.obj"), dir.join("den-haag.orbit60.json"));
    if !model.is_file() || !path.is_file() {
        cannot_run(&format!("no {} with its orbit (../shared/models)", model.display()));
        return;
    }
    let scene = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
    let path = CameraPath::load(&path).unwrap();
    let params = ModeParams::default()
        .with("swr.rests", "false")
        .with("swr.resolution", &format!("{}x{}", SIZE.width, SIZE.height));
    let options = RunOptions {
        warmup: 0,
        resolution: SIZE,
        measure_error: true,
    };
    let mut failures = Vec::new();
    for gpu in gpus() {
        let mut world = World::new(scene.clone(), hierarchy(&scene));
        let mut swr: Vec<Box<dyn Culler>> = vec![create("swr", &scene, &params).unwrap()];
        let mut session = Session::new(&gpu, &world, &mut swr, true, &options).unwrap();
        let mut held_pixels = 0;
        for frame in 0..path.frames {
            let camera = path.camera(frame, SIZE.aspect());
            session.frame(frame, &camera, &mut world, &mut swr, 0).unwrap();
            let drawn = session.reference_depth().unwrap();
            let Some(held) = swr[0].occluder_depths() else { continue };
            assert_eq!(
                (held.width, held.height, held.depths.len()),
                (SIZE.width, SIZE.height, drawn.len())
            );
            for (pixel, (&vouched, &depth)) in held.depths.iter().zip(&drawn).enumerate() {
                held_pixels += usize::from(vouched > 0.0);
                // Reverse-Z: the buffer's depth must be no nearer (no
                // larger) than the depth the GPU drew.
                if vouched > depth {
                    failures.push(format!(
                        "{} frame {frame} pixel ({}, {}): vouched {vouched:e}, drawn {depth:e} ({:.2} steps of 2^-24 nearer)",
                        gpu.adapter.backend,
                        pixel as u32 % SIZE.width,
                        pixel as u32 / SIZE.width,
                        f64::from(vouched - depth) * f64::from(1u32 << 24),
                    ));
                }
            }
        }
        // The check held something: the buildings fill a few percent of
        // the view.
        assert!(
            held_pixels > 10_000,
            "{}: the buffer held only {held_pixels} pixels over {} frames",
            gpu.adapter.backend,
            path.frames
        );
    }
    let shown: Vec<&String> = failures.iter().take(10).collect();
    assert!(
        failures.is_empty(),
        "{} pixels where swr vouched for a depth nearer than the GPU drew:\n{shown:#?}",
        failures.len()
    );
}
