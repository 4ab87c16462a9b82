//! Helpers shared by the integration tests.
#![allow(dead_code)] // each test binary uses its own subset

pub mod gltf_writer;
pub mod hall;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::{DAffine3, DVec3};
use occlu::bench::{RunOutput, run};
use occlu::camera::generate::{PathKind, generate};
use occlu::camera::path::{CameraPath, Interpolation, KeyframeFile, PathFile};
use occlu::cull::{Culler, FrameInput, TraversalStats};
use occlu::gpu::{BackendChoice, Frame, GpuContext, Resolution};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::scene::{LoadOptions, Scene, SceneBuilder, SceneSpec, load};
use occlu::session::RunOptions;
use occlu::world::World;

/// `bench` arguments that keep a run tiny: a one-block city, two frames,
/// no warm-up (a resolution is the caller's).
pub const TINY_RUN: &[&str] = &["--scene", "city:blocks=1", "--frames", "2", "--warmup", "0"];

/// Runs the `occlu` binary built for these tests.
pub fn occlu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(args)
        .output()
        .expect("occlu binary runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// stderr without the loader noise of headless Vulkan (libwayland prints
/// "XDG_RUNTIME_DIR is invalid" when the Vulkan loader probes for Wayland).
pub fn own_stderr(o: &Output) -> Vec<String> {
    stderr(o)
        .lines()
        .filter(|l| !l.contains("XDG_RUNTIME_DIR"))
        .map(str::to_string)
        .collect()
}

/// `out` exited with `code` after one line on stderr holding `needles`;
/// `what` names the command in a failure.
pub fn said_one_line(out: &Output, code: i32, needles: &[&str], what: &str) {
    let lines = own_stderr(out);
    assert_eq!(out.status.code(), Some(code), "{what}: {lines:?}");
    assert_eq!(lines.len(), 1, "{what}: one line expected, got {lines:?}");
    for n in needles {
        assert!(lines[0].contains(n), "{what}: '{}' lacks '{n}'", lines[0]);
    }
    assert!(!lines[0].contains("panicked"), "{what}: {}", lines[0]);
}

pub fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).expect("fixture written");
    p
}

/// Says that a test cannot run here, and why: a line on a developer's
/// machine, where the fixtures are optional; a failure where they are
/// required (`OCCLU_REQUIRE_FIXTURES=1`, which `.ci/run` sets), so that CI
/// never passes a test that did not run.
pub fn cannot_run(why: &str) {
    assert!(
        std::env::var_os("OCCLU_REQUIRE_FIXTURES").is_none_or(|v| v != "1"),
        "{why}: OCCLU_REQUIRE_FIXTURES=1 requires it"
    );
    eprintln!("skipped: {why}");
}

/// `../shared/models` beside the project root: third-party models that
/// tests skip, saying so, where the folder is absent.
pub fn shared_models_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models")
}

/// Model files under `dir`, in sorted order, with the path file of each
/// (`NAME.*.json` beside `NAME.ext`), if any.
pub fn shared_models(dir: &Path) -> Vec<(PathBuf, Option<PathBuf>)> {
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

/// Every triangle of `scene` in world space.
pub fn world_triangles(scene: &Scene) -> Vec<[DVec3; 3]> {
    let mut out = Vec::new();
    for o in &scene.objects {
        let m = &scene.meshes[o.mesh as usize];
        let indices = &scene.indices[m.first_index as usize..(m.first_index + m.index_count) as usize];
        for t in indices.chunks(3) {
            out.push([0, 1, 2].map(|k| {
                let v = DVec3::from(scene.vertices[t[k] as usize].map(f64::from));
                o.transform.transform_point3(v)
            }));
        }
    }
    out
}

/// The distance from `p` to triangle `t`: to its plane when the foot lies
/// inside, else to the nearest of its edges.
pub fn distance(p: DVec3, t: &[DVec3; 3]) -> f64 {
    let [a, b, c] = *t;
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let n = n.normalize();
        let foot = p - n * n.dot(p - a);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).cross(foot - u).dot(n) >= 0.0);
        if inside {
            return (p - foot).length();
        }
    }
    let segment = |u: DVec3, v: DVec3| {
        let s = ((p - u).dot(v - u) / (v - u).length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        (p - (u + (v - u) * s)).length()
    };
    segment(a, b).min(segment(b, c)).min(segment(c, a))
}

/// The nearest `t` in `(0, max_t]` where `origin + t·direction` meets one
/// of `triangles`, tried one by one: the ray meets the triangle's plane,
/// and the point lies in the triangle.
pub fn first_hit(triangles: &[[DVec3; 3]], origin: DVec3, direction: DVec3, max_t: f64) -> Option<f64> {
    triangles
        .iter()
        .filter_map(|&[a, b, c]| {
            let n = (b - a).cross(c - a);
            let t = n.dot(a - origin) / n.dot(direction);
            let p = origin + direction * t;
            (t > 0.0 && t <= max_t && distance(p, &[a, b, c]) < 1e-9).then_some(t)
        })
        .min_by(f64::total_cmp)
}

/// Frames of `path` with a surface nearer the eye than the near plane's
/// corners, by brute force.
pub fn frames_too_near(path: &CameraPath, triangles: &[[DVec3; 3]]) -> Vec<u32> {
    let aspect = 4.0 / 3.0;
    (0..path.frames)
        .filter(|&f| {
            let camera = path.camera(f, aspect);
            let t = (camera.fov_y / 2.0).tan();
            let corner = camera.near * (1.0 + t * t * (1.0 + aspect * aspect)).sqrt();
            triangles.iter().any(|tri| distance(camera.eye, tri) < corner)
        })
        .collect()
}

/// Two objects (a quad and a tetrahedron) and a 'g' group: 2 + 4 + 1 = 7 triangles.
pub const THREE_OBJECTS_OBJ: &str = "\
# three objects
o quad
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 1 2 3 4
o tetra
v 2 0 0
v 3 0 0
v 2 1 0
v 2 0 1
f 5 6 7
f 5 6 8
f 5 7 8
f 6 7 8
g lone
v 4 0 0
v 5 0 0
v 4 1 0
f 9 10 11
";

/// Every backend that has an adapter here (Vulkan and GL on the reference
/// machine). Fails when there is none at all: the tests need a GPU or a
/// software rasteriser.
pub fn gpus() -> Vec<GpuContext> {
    let found: Vec<GpuContext> = [BackendChoice::Vulkan, BackendChoice::Gl]
        .into_iter()
        .filter_map(|b| GpuContext::new(b).ok())
        .collect();
    assert!(
        !found.is_empty(),
        "no Vulkan or GL adapter: install Mesa (scripts/install-deps) to run the GPU tests"
    );
    found
}

/// The backends present here, by the names `--backend` takes.
pub fn backends() -> Vec<String> {
    gpus().iter().map(|g| g.adapter.backend.to_lowercase()).collect()
}

/// A one-frame path: the camera at `eye` looking at `target`.
pub fn still(eye: DVec3, target: DVec3, fov_y_deg: f64) -> CameraPath {
    held(eye, target, fov_y_deg, 1)
}

/// The camera held at `eye`, looking at `target`, for `frames` frames.
pub fn held(eye: DVec3, target: DVec3, fov_y_deg: f64, frames: u32) -> CameraPath {
    let file = PathFile {
        frames: Some(frames),
        fps: None,
        near: Some(0.1),
        fov_y_deg: Some(fov_y_deg),
        up: None,
        interpolation: Interpolation::Linear,
        keyframes: vec![KeyframeFile {
            time: 0.0,
            position: eye.to_array(),
            target: Some(target.to_array()),
            direction: None,
            orientation: None,
            up: None,
            fov_y_deg: None,
        }],
    };
    CameraPath::from_file(&file, "test").unwrap()
}

/// The camera at `eye` looking along `directions[f]` in frame `f`.
pub fn turning(eye: DVec3, directions: &[DVec3], fov_y_deg: f64) -> CameraPath {
    let file = PathFile {
        frames: None,
        fps: Some(1.0),
        near: Some(0.1),
        fov_y_deg: Some(fov_y_deg),
        up: None,
        interpolation: Interpolation::Linear,
        keyframes: directions
            .iter()
            .enumerate()
            .map(|(f, d)| KeyframeFile {
                time: f as f64,
                position: eye.to_array(),
                target: None,
                direction: Some(d.to_array()),
                orientation: None,
                up: None,
                fov_y_deg: None,
            })
            .collect(),
    };
    CameraPath::from_file(&file, "test").unwrap()
}

/// A scene of axis-aligned boxes, one object each.
pub fn boxes(list: &[(DVec3, DVec3)]) -> Scene {
    let mut b = SceneBuilder::new("test boxes".into(), 4096);
    for (k, &(min, max)) in list.iter().enumerate() {
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                )
            })
            .collect();
        let idx = gltf_writer::cube_indices();
        let group = b.add_mesh(&format!("box{k}"), &corners, &idx).unwrap();
        b.add_object(&format!("box{k}"), &group, DAffine3::IDENTITY).unwrap();
    }
    b.finish().unwrap()
}

/// The hierarchy `occlu bench` builds over `scene`.
pub fn hierarchy(scene: &Scene) -> Hierarchy {
    Hierarchy::build(&scene.objects, &HierarchyParams::default())
}

/// Hierarchy parameters that put every object in a leaf of its own, so each
/// box is tested alone, with no neighbour in its leaf to make it visible.
pub fn one_object_per_leaf() -> HierarchyParams {
    HierarchyParams {
        max_leaf_objects: 1,
        traversal_cost: 0.0,
        ..HierarchyParams::default()
    }
}

/// Runs `cullers` over `path` in `scene` (its movers moving) with
/// error measurement and no warm-up.
pub fn run_modes(
    gpu: &GpuContext,
    scene: &Scene,
    hierarchy: &Hierarchy,
    path: &CameraPath,
    cullers: &mut [Box<dyn Culler + '_>],
    resolution: Resolution,
) -> RunOutput {
    let options = RunOptions {
        warmup: 0,
        resolution,
        measure_error: true,
    };
    let mut world = World::new(scene.clone(), hierarchy.clone());
    run(gpu, &mut world, path, cullers, &options, None, &mut |_, _| {
        std::ops::ControlFlow::Continue(())
    })
    .unwrap()
}

/// The small built-in city (`city:blocks=2`), its hierarchy, and its street
/// walk sampled at `frames` frames: the shared workload of the GPU tests.
pub fn small_city(frames: u32) -> (Scene, Hierarchy, CameraPath) {
    builtin("city:blocks=2", frames)
}

/// The built-in scene `spec`, its hierarchy and its walk.
pub fn builtin(spec: &str, frames: u32) -> (Scene, Hierarchy, CameraPath) {
    let scene = load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap();
    let hierarchy = hierarchy(&scene);
    let path = CameraPath::from_file(&generate(PathKind::Walk, &scene, frames).unwrap(), "walk").unwrap();
    (scene, hierarchy, path)
}

/// The depth direct rendering draws of `scene` from `camera` at
/// `resolution` (its aspect replaces the camera's), on the first adapter.
pub fn reference_depth(scene: &Scene, camera: &occlu::camera::Camera, resolution: Resolution) -> Vec<f32> {
    let gpu = gpus().remove(0);
    let options = RunOptions {
        warmup: 0,
        resolution,
        measure_error: true,
    };
    let mut world = World::new(scene.clone(), hierarchy(scene));
    let mut dr = vec![occlu::cull::create("dr", scene, &occlu::cull::ModeParams::default()).unwrap()];
    let mut session = occlu::session::Session::new(&gpu, &world, &mut dr, true, &options).unwrap();
    let camera = occlu::camera::Camera {
        aspect: resolution.aspect(),
        ..*camera
    };
    session.frame(0, &camera, &mut world, &mut dr, 0).unwrap();
    session.reference_depth().unwrap()
}

/// The resolution the city tests render at.
pub const SMALL: Resolution = Resolution {
    width: 160,
    height: 120,
};

/// Draws the reference visible set minus its first object: a culler that
/// wrongly culls one visible object per frame.
pub struct DropOneVisible(pub Vec<u32>);
impl Culler for DropOneVisible {
    fn name(&self) -> &str {
        "drop-one"
    }
    fn needs_reference(&self) -> bool {
        true
    }
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        self.0.clear();
        self.0.extend(input.reference_visible.unwrap().iter().skip(1));
        ctx.draw(&self.0);
        TraversalStats::default()
    }
}

/// An OBJ of axis-aligned boxes `(name, min, max)`, coordinates as given.
pub fn boxes_obj(boxes: &[(String, DVec3, DVec3)]) -> String {
    let mut obj = String::new();
    for (k, (name, min, max)) in boxes.iter().enumerate() {
        obj += &format!("o {name}\n");
        for corner in 0..8 {
            let pick = |bit: usize, lo: f64, hi: f64| if corner & bit == 0 { lo } else { hi };
            let (x, y, z) = (pick(1, min.x, max.x), pick(2, min.y, max.y), pick(4, min.z, max.z));
            obj += &format!("v {x} {y} {z}\n");
        }
        let base = 8 * k as u32 + 1;
        for t in gltf_writer::cube_indices().chunks(3) {
            obj += &format!("f {} {} {}\n", t[0] + base, t[1] + base, t[2] + base);
        }
    }
    obj
}

/// A town of 4×4 blocks on a ground slab, built +Z up: 120 units across,
/// buildings 6 to 36 tall. `swap` turns it +Y up (y and z exchanged).
pub fn town(swap: bool) -> Vec<(String, DVec3, DVec3)> {
    let place = |v: DVec3| if swap { DVec3::new(v.x, v.z, v.y) } else { v };
    let mut boxes = vec![(
        "ground".to_string(),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(120.0, 120.0, 0.0),
    )];
    for i in 0..4 {
        for j in 0..4 {
            let (x, y) = (10.0 + 28.0 * f64::from(i), 10.0 + 28.0 * f64::from(j));
            let height = 6.0 + f64::from((i * 7 + j * 3) % 11) * 3.0;
            boxes.push((
                format!("building_{i}_{j}"),
                DVec3::new(x, y, 0.0),
                DVec3::new(x + 18.0, y + 18.0, height),
            ));
        }
    }
    boxes.into_iter().map(|(n, a, b)| (n, place(a), place(b))).collect()
}

/// Copies a run and rewrites its frames.csv with `edit` applied to each row.
pub fn tampered_copy(run: &Path, to: &Path, edit: &dyn Fn(&mut occlu::measure::FrameStats)) {
    rewritten_copy(run, to, &mut |rows| rows.iter_mut().for_each(edit));
}

/// Copies a run with its frames.csv rows rewritten by `edit` (which may
/// drop or add rows), and summary.json recording the new file's
/// fingerprint, as a run that measured those rows would have.
pub fn rewritten_copy(run: &Path, to: &Path, edit: &mut dyn FnMut(&mut Vec<occlu::measure::FrameStats>)) {
    std::fs::create_dir_all(to).unwrap();
    let mut rows: Vec<occlu::measure::FrameStats> = csv::Reader::from_path(run.join("frames.csv"))
        .unwrap()
        .deserialize()
        .map(Result::unwrap)
        .collect();
    edit(&mut rows);
    let mut writer = csv::Writer::from_path(to.join("frames.csv")).unwrap();
    for row in rows {
        writer.serialize(row).unwrap();
    }
    writer.flush().unwrap();
    let mut summary: occlu::report::Summary =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let frames = std::fs::read(to.join("frames.csv")).unwrap();
    summary.frames_csv = Some(occlu::report::Fingerprint::of(&frames));
    std::fs::write(to.join("summary.json"), serde_json::to_string_pretty(&summary).unwrap()).unwrap();
}
