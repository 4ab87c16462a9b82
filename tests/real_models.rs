//! Every conservative mode is exact on real third-party models, and no GPU
//! walk draws more than `vfc` in any frame: every model
//! in ../shared/models (beside the project root; CI has it too), with its
//! path file where one sits beside it (`NAME.*.json`, the paths its
//! failures were found on) or else a short generated path, on every backend
//! present, frame by frame. Skips, saying so, where that folder is absent.

mod common;

use std::time::Instant;

use common::{cannot_run, gpus, hierarchy, run_modes, shared_models, shared_models_dir};
use occlu::camera::generate::default_path;
use occlu::camera::path::CameraPath;
use occlu::cull::{Culler, ModeParams, create, modes};
use occlu::gpu::Resolution;
use occlu::scene::{LoadOptions, SceneSpec, load};

/// Frames of the generated path of a model without a path file.
const GENERATED_FRAMES: u32 = 8;

#[test]
fn every_conservative_mode_is_exact_on_every_shared_model() {
    let dir = shared_models_dir();
    if !dir.is_dir() {
        cannot_run(&format!("no real models at {} (../shared/models)", dir.display()));
        return;
    }
    let models = shared_models(&dir);
    assert!(!models.is_empty(), "{} holds no .obj, .gltf or .glb", dir.display());
    let gpus = gpus();
    let mut failures = Vec::new();
    for (model, path_file) in &models {
        let scene = load(&SceneSpec::File(model.clone()), &LoadOptions::default()).unwrap();
        let hierarchy = hierarchy(&scene);
        let path = match path_file {
            Some(file) => CameraPath::load(file).unwrap(),
            None => default_path(&scene).unwrap().0.with_frames(GENERATED_FRAMES).unwrap(),
        };
        for gpu in &gpus {
            let started = Instant::now();
            let mut cullers: Vec<Box<dyn Culler>> = modes()
                .filter(|m| m.conservative && m.unsupported_on(gpu).is_none())
                .map(|m| create(m.id.name(), &scene, &ModeParams::exercising_every_frame()).unwrap())
                .collect();
            let out = run_modes(gpu, &scene, &hierarchy, &path, &mut cullers, Resolution::DEFAULT);
            assert_eq!(out.rows.len(), cullers.len() * path.frames as usize);
            let vfc_triangles = |frame: u32| {
                out.rows
                    .iter()
                    .find(|r| r.mode == "vfc" && r.frame == frame)
                    .map(|r| r.triangles_drawn)
            };
            for row in &out.rows {
                // A GPU walk draws nothing the frustum leaves out.
                let walk = row.traversal.drawn_early + row.traversal.drawn_late > 0;
                if let Some(vfc) = vfc_triangles(row.frame).filter(|&vfc| walk && row.triangles_drawn > vfc) {
                    failures.push(format!(
                        "{} on {}: {} frame {}: {} triangles, vfc {vfc}",
                        model.display(),
                        gpu.adapter.backend,
                        row.mode,
                        row.frame,
                        row.triangles_drawn
                    ));
                }
                if row.error_pixels != Some(0) || row.missed_objects != Some(0) {
                    failures.push(format!(
                        "{} on {}: {} frame {}: {:?} wrong pixels, {:?} missed",
                        model.display(),
                        gpu.adapter.backend,
                        row.mode,
                        row.frame,
                        row.error_pixels,
                        row.missed_objects
                    ));
                }
            }
            eprintln!(
                "{} ({} frames, {} modes) on {}: {:.1} s",
                model.display(),
                path.frames,
                cullers.len(),
                gpu.adapter.backend,
                started.elapsed().as_secs_f64()
            );
        }
    }
    assert!(
        failures.is_empty(),
        "{} frames not exact or drawing more than vfc:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
