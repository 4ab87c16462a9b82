//! Every conservative mode is exact on real third-party models: every model
//! in ../shared/models (beside the project root; CI has it too), with its
//! path file where one sits beside it (`NAME.*.json`, the paths its
//! failures were found on) or else a short generated path, on every backend
//! present, frame by frame. Skips, saying so, where that folder is absent.

mod common;

use std::path::{Path, PathBuf};
use std::time::Instant;

use common::{gpus, hierarchy, run_modes};
use occlu::camera::generate::default_path;
use occlu::camera::path::CameraPath;
use occlu::cull::{Culler, ModeParams, create, modes};
use occlu::gpu::Resolution;
use occlu::scene::{LoadOptions, SceneSpec, load};

/// Frames of the generated path of a model without a path file.
const GENERATED_FRAMES: u32 = 8;

fn models_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models")
}

/// Model files under `dir`, in sorted order, with the path file of each
/// (`NAME.*.json` beside `NAME.ext`), if any.
fn models(dir: &Path) -> Vec<(PathBuf, Option<PathBuf>)> {
    let mut files: Vec<PathBuf> = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else {
                files.push(path);
            }
        }
    }
    files.sort();
    let extension = |p: &Path| p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    files
        .iter()
        .filter(|p| matches!(extension(p).as_deref(), Some("obj" | "gltf" | "glb")))
        .map(|model| {
            let stem = model.file_stem().unwrap().to_string_lossy();
            let path = files.iter().find(|p| {
                extension(p).as_deref() == Some("json")
                    && p.parent() == model.parent()
                    && p.file_name()
                        .unwrap()
                        .to_string_lossy()
                        .starts_with(&format!("{stem}."))
            });
            (model.clone(), path.cloned())
        })
        .collect()
}

#[test]
fn every_conservative_mode_is_exact_on_every_shared_model() {
    let dir = models_dir();
    if !dir.is_dir() {
        eprintln!("skipped: no real models at {} (../shared/models)", dir.display());
        return;
    }
    let models = models(&dir);
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
                .map(|m| create(m.id.name(), &scene, &ModeParams::default()).unwrap())
                .collect();
            let out = run_modes(gpu, &scene, &hierarchy, &path, &mut cullers, Resolution::DEFAULT);
            assert_eq!(out.rows.len(), cullers.len() * path.frames as usize);
            for row in &out.rows {
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
        "{} frames not exact:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
