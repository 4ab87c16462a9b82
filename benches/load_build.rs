//! Load and hierarchy-build time on generated models, phase by phase.
//!
//! `cargo bench --bench load_build` writes four models into a temporary
//! folder and loads each several times:
//!
//! - `scan-1m.obj` and `scan-8m.obj`: one closed surface of small, even
//!   triangles (a bumpy sphere, about 1 M and 8 M triangles), in one OBJ
//!   mesh, as a 3D scanner writes it: the closed-solid test and the
//!   clustering see the whole mesh at once;
//! - `tiles.obj`: 100 objects of 8 192 triangles and one of 199 712 (about
//!   1 M triangles);
//! - `instances.glb`: 40 closed meshes of 432 to 24 300 triangles, each
//!   placed 50 times under a node tree (2 000 instances), as in a CAD
//!   assembly;
//!
//! and builds the built-in city. For each it prints the median of every
//! phase (`LoadPhases`: read, parse, validate, closed-solid test,
//! clustering; then the hierarchy build) on its own line, and the median of
//! the whole load + build. Target on the project's 2-core machine: load +
//! build of the 1 M-triangle scan under 1 s, of the 8 M one under 8 s.

mod common;

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

use common::{median, scan};
use glam::DVec3;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, LoadPhases, SceneSpec, load};
use serde_json::json;

#[path = "../tests/common/gltf_writer.rs"]
#[allow(dead_code)] // the bench writes meshes and nodes only
mod gltf_writer;

/// Loads of each model; the 8 M-triangle scan gets fewer.
const RUNS: usize = 5;
const RUNS_OF_LARGE: usize = 3;

fn main() {
    let dir = std::env::temp_dir().join(format!("occlu-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // A cube of n×n quads a face has 12·n² triangles.
    for (name, n, runs) in [("scan-1m.obj", 289, RUNS), ("scan-8m.obj", 816, RUNS_OF_LARGE)] {
        let (positions, indices) = scan(n);
        let file = write(&dir, name, obj_text("scan", &positions, &indices).as_bytes());
        measure(&SceneSpec::File(file), runs);
    }
    let file = write(&dir, "tiles.obj", tiles_obj().as_bytes());
    measure(&SceneSpec::File(file), RUNS);
    let file = write(&dir, "instances.glb", &instances_glb());
    measure(&SceneSpec::File(file), RUNS);
    measure(&SceneSpec::Builtin("city".into()), RUNS);
    let _ = std::fs::remove_dir_all(&dir);
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write model");
    path
}

/// Loads and builds `spec` `runs` times and prints the median of each
/// phase and of the whole.
fn measure(spec: &SceneSpec, runs: usize) {
    let options = LoadOptions::default();
    let mut phases: Vec<(LoadPhases, Duration)> = Vec::with_capacity(runs);
    let mut wholes = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let started = Instant::now();
        let scene = load(spec, &options).expect("generated model loads");
        let built = Instant::now();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        wholes.push(started.elapsed());
        phases.push((scene.phases, built.elapsed()));
        last = Some(std::hint::black_box((scene, hierarchy)));
    }
    let (scene, hierarchy) = last.expect("runs > 0");
    let triangles = scene.triangles();
    let what = match spec {
        SceneSpec::File(path) => {
            let mb = std::fs::metadata(path).map_or(0.0, |m| m.len() as f64 / 1e6);
            format!(
                "{} ({mb:.1} MB)",
                path.file_name().unwrap_or_default().to_string_lossy()
            )
        }
        SceneSpec::Builtin(name) => format!("built-in {name}"),
    };
    println!(
        "{what}: {triangles} triangles, {} parts ({} closed), {} objects, {} nodes; medians of {runs} runs",
        scene.parts.len(),
        scene.parts.iter().filter(|p| p.closed).count(),
        scene.objects.len(),
        hierarchy.nodes.len()
    );
    let ms_of = |pick: fn(&(LoadPhases, Duration)) -> f64| median(phases.iter().map(pick).collect());
    let lines: [(&str, f64); 6] = [
        ("read", ms_of(|(p, _)| p.read_ms)),
        ("parse", ms_of(|(p, _)| p.parse_ms)),
        ("validate", ms_of(|(p, _)| p.validate_ms)),
        ("closed-solid test", ms_of(|(p, _)| p.closed_ms)),
        ("clustering", ms_of(|(p, _)| p.cluster_ms)),
        ("hierarchy", ms_of(|(_, h)| h.as_secs_f64() * 1e3)),
    ];
    for (phase, ms) in lines {
        println!("  {phase:<20} {ms:>9.1} ms");
    }
    let whole = median(wholes.iter().map(|d| d.as_secs_f64() * 1e3).collect());
    println!(
        "  {:<20} {whole:>9.1} ms  {:>6.2} M triangles/s\n",
        "load + build",
        triangles as f64 / whole / 1e3
    );
}

/// One OBJ object `name` of the triangles `indices` over `positions`.
fn obj_text(name: &str, positions: &[DVec3], indices: &[u32]) -> String {
    let mut text = String::with_capacity(positions.len() * 32 + indices.len() * 9);
    let _ = writeln!(text, "o {name}");
    for p in positions {
        let _ = writeln!(text, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    }
    for t in indices.chunks_exact(3) {
        let _ = writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    text
}

/// 100 terrain-like grids of 8 192 triangles and one of 199 712: 1 018 912.
fn tiles_obj() -> String {
    let mut text = String::with_capacity(64 << 20);
    let mut base = 1usize;
    let mut grid = |name: &str, n: usize, origin: (f64, f64), text: &mut String| {
        let _ = writeln!(text, "o {name}");
        for z in 0..=n {
            for x in 0..=n {
                let (fx, fz) = (origin.0 + x as f64 * 0.5, origin.1 + z as f64 * 0.5);
                let _ = writeln!(text, "v {fx:.4} {:.4} {fz:.4}", (fx * 0.3).sin() + (fz * 0.2).cos());
            }
        }
        let v = |x: usize, z: usize| base + z * (n + 1) + x;
        for z in 0..n {
            for x in 0..n {
                let _ = writeln!(text, "f {} {} {}", v(x, z), v(x + 1, z), v(x + 1, z + 1));
                let _ = writeln!(text, "f {} {} {}", v(x, z), v(x + 1, z + 1), v(x, z + 1));
            }
        }
        base += (n + 1) * (n + 1);
    };
    for i in 0..100 {
        grid(
            &format!("tile{i}"),
            64,
            ((i % 10) as f64 * 40.0, (i / 10) as f64 * 40.0),
            &mut text,
        );
    }
    grid("terrain", 316, (-200.0, -200.0), &mut text);
    text
}

/// 40 bumpy spheres of 6 to 45 quads a cube face, each placed at 50 spots:
/// 50 assemblies, each a node whose 40 children are the spheres.
fn instances_glb() -> Vec<u8> {
    let mut writer = gltf_writer::GltfWriter::default();
    let meshes: Vec<usize> = (6..46)
        .map(|n| {
            let (positions, indices) = scan(n);
            let positions: Vec<[f32; 3]> = positions.iter().map(|p| p.as_vec3().to_array()).collect();
            writer.mesh(&format!("part{n}"), &[(&positions, Some(&indices), 4)])
        })
        .collect();
    let roots: Vec<usize> = (0..50)
        .map(|assembly| {
            let children: Vec<usize> = meshes
                .iter()
                .enumerate()
                .map(|(k, &mesh)| {
                    let at = [(k % 8) as f64 * 2.5, (k / 8) as f64 * 2.5, 0.0];
                    writer.node(json!({"mesh": mesh, "translation": at}))
                })
                .collect();
            let at = [(assembly % 10) as f64 * 25.0, 0.0, (assembly / 10) as f64 * 25.0];
            writer.node(json!({"name": format!("assembly{assembly}"), "children": children, "translation": at}))
        })
        .collect();
    writer.glb(&roots)
}
