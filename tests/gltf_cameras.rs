//! A glTF file's own cameras and camera animations become paths: positions
//! and orientations at the keys match what the file says, computed here by
//! hand from its numbers.

mod common;

use common::gltf_writer::{GltfWriter, cube};
use common::{occlu, stdout, write};
use glam::{DQuat, DVec3};
use occlu::camera::generate::{PathKind, PathRequest, default_path, plan};
use occlu::camera::path::CameraPath;
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};
use serde_json::json;

/// 90° about +Y, as glTF writes quaternions (x, y, z, w).
const QUARTER_TURN: [f32; 4] = [
    0.0,
    std::f32::consts::FRAC_1_SQRT_2,
    0.0,
    std::f32::consts::FRAC_1_SQRT_2,
];

/// A cube, two still cameras (one under a turned parent) and a camera on a
/// rig that one animation moves (translation LINEAR, rotation STEP) and
/// another dollies (CUBICSPLINE, over 2 s); a third animation spins the
/// cube and moves no camera.
fn model(dir: &std::path::Path) -> std::path::PathBuf {
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let mesh = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let cube_node = w.node(json!({"name": "cube", "mesh": mesh, "translation": [0.0, 0.0, -5.0]}));
    let front = w.node(json!({"name": "front", "camera": 0, "translation": [0.0, 2.0, 10.0]}));
    let side = w.node(json!({"name": "side", "camera": 1, "translation": [0.0, 1.0, 3.0]}));
    let turned =
        w.node(json!({"name": "turned", "children": [side], "translation": [5.0, 0.0, 0.0], "rotation": QUARTER_TURN}));
    let ride = w.node(json!({"name": "ride", "camera": 0, "translation": [0.0, 1.5, 0.0]}));
    let rig = w.node(json!({"name": "rig", "children": [ride]}));
    let times = w.floats(&[0.0, 1.0, 2.0], "SCALAR");
    let moves = w.floats(&[0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 0.0, -10.0], "VEC3");
    let turn_times = w.floats(&[0.0, 1.0], "SCALAR");
    let turns = w.floats(
        &[
            0.0,
            0.0,
            0.0,
            1.0,
            QUARTER_TURN[0],
            QUARTER_TURN[1],
            QUARTER_TURN[2],
            QUARTER_TURN[3],
        ],
        "VEC4",
    );
    // In-tangent, value, out-tangent per key; keys 2 s apart, out-tangent
    // 1 at the start, in-tangent -1 at the end.
    let dolly_times = w.floats(&[0.0, 2.0], "SCALAR");
    let dolly = w.floats(
        &[
            0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ],
        "VEC3",
    );
    let spin = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "VEC4");
    w.extra.insert(
        "cameras".into(),
        json!([
            {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}},
            {"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.2, "zfar": 100.0}}
        ]),
    );
    w.extra.insert(
        "animations".into(),
        json!([
            {"name": "tour", "samplers": [
                {"input": times, "output": moves, "interpolation": "LINEAR"},
                {"input": turn_times, "output": turns, "interpolation": "STEP"}
             ], "channels": [
                {"sampler": 0, "target": {"node": rig, "path": "translation"}},
                {"sampler": 1, "target": {"node": rig, "path": "rotation"}}
             ]},
            {"name": "dolly", "samplers": [{"input": dolly_times, "output": dolly, "interpolation": "CUBICSPLINE"}],
             "channels": [{"sampler": 0, "target": {"node": rig, "path": "translation"}}]},
            {"name": "spin", "samplers": [{"input": turn_times, "output": spin, "interpolation": "LINEAR"}],
             "channels": [{"sampler": 0, "target": {"node": cube_node, "path": "rotation"}}]}
        ]),
    );
    let model = dir.join("scene.glb");
    std::fs::write(&model, w.glb(&[cube_node, front, turned, rig])).unwrap();
    model
}

fn request(kind: PathKind, animation: Option<&str>) -> PathRequest {
    PathRequest {
        kind,
        animation: animation.map(str::to_string),
    }
}

fn scene(dir: &std::path::Path) -> Scene {
    load(&SceneSpec::File(model(dir)), &LoadOptions::default()).unwrap()
}

/// Asserts keyframe `k` of `path` stands at `eye` turned by `rotation`.
fn assert_key(path: &CameraPath, k: usize, eye: DVec3, rotation: DQuat) {
    let key = &path.keyframes[k];
    assert!(key.position.distance(eye) < 1e-6, "key {k}: {} vs {eye}", key.position);
    assert!(
        key.rotation.dot(rotation).abs() > 1.0 - 1e-9,
        "key {k}: {} vs {rotation}",
        key.rotation
    );
}

#[test]
fn the_files_cameras_are_visited_in_order_with_their_views() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let names: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["front", "side", "ride"]);
    let generated = plan(Some(&request(PathKind::Cameras, None)), &scene, None).unwrap();
    let path = CameraPath::from_file(&generated.file, "cameras").unwrap();
    assert_eq!(path.frames, 3, "one frame per camera");
    let quarter = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    assert_key(&path, 0, DVec3::new(0.0, 2.0, 10.0), DQuat::IDENTITY);
    // The side camera: (0, 1, 3) turned a quarter about Y, then moved to x = 5.
    assert_key(&path, 1, DVec3::new(5.0 + 3.0, 1.0, 0.0), quarter);
    assert_key(&path, 2, DVec3::new(0.0, 1.5, 0.0), DQuat::IDENTITY);
    assert!((path.keyframes[0].fov_y - 0.8).abs() < 1e-6 && (path.keyframes[1].fov_y - 1.2).abs() < 1e-6);
    assert!((path.near - 0.05).abs() < 1e-9, "the nearest of the cameras' planes");
    // One warning for the animation that moves no camera.
    let unused: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("move no camera")).collect();
    assert_eq!(unused.len(), 1, "{:?}", scene.warnings);
    assert!(unused[0].contains("spin"));
}

#[test]
fn an_animated_camera_is_sampled_as_the_file_moves_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    // The default path is the animated camera's first animation.
    let (path, why) = default_path(&scene).unwrap();
    assert!(
        path.source.ends_with("animation") && why.contains("'ride'") && why.contains("'tour'"),
        "{why}"
    );
    let quarter = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    let at = |t: f64| {
        let k = path
            .keyframes
            .iter()
            .position(|key| (key.time - t).abs() < 1e-9)
            .unwrap();
        (k, path.keyframes[k].position, path.keyframes[k].rotation)
    };
    // LINEAR translation of the rig; STEP rotation: none before 1 s, a
    // quarter turn from 1 s on (the camera sits 1.5 up the rig's axis).
    for (t, rig, turn) in [
        (0.0, DVec3::ZERO, DQuat::IDENTITY),
        (0.5, DVec3::new(5.0, 0.0, 0.0), DQuat::IDENTITY),
        (1.0, DVec3::new(10.0, 0.0, 0.0), quarter),
        (1.5, DVec3::new(10.0, 0.0, -5.0), quarter),
        (2.0, DVec3::new(10.0, 0.0, -10.0), quarter),
    ] {
        let (k, _, _) = at(t);
        assert_key(&path, k, rig + DVec3::new(0.0, 1.5, 0.0), turn);
    }
    assert!((path.keyframes.last().unwrap().time - 2.0).abs() < 1e-12);
    assert_eq!(path.frames, 61, "2 s at 30 frames a second, both ends");
    // CUBICSPLINE over 2 s: the Hermite curve from 5 to 8 with tangents 1
    // and -1 per second, scaled by the 2 s between the keys.
    let dolly = plan(Some(&request(PathKind::Animation, Some("dolly"))), &scene, None).unwrap();
    let dolly = CameraPath::from_file(&dolly.file, "dolly").unwrap();
    for key in &dolly.keyframes {
        let u = key.time / 2.0;
        let (u2, u3) = (u * u, u * u * u);
        let x = (2.0 * u3 - 3.0 * u2 + 1.0) * 5.0 + (u3 - 2.0 * u2 + u) * 2.0 + (-2.0 * u3 + 3.0 * u2) * 8.0
            - (u3 - u2) * 2.0;
        assert!(
            (key.position.x - x).abs() < 1e-6,
            "at {} s: {} vs {x}",
            key.time,
            key.position.x
        );
    }
    assert_eq!(dolly.keyframes.len(), 61, "2 s at 30 samples a second");
}

#[test]
fn info_lists_cameras_and_animations_and_bad_requests_say_why() {
    let dir = tempfile::tempdir().unwrap();
    let model = model(dir.path());
    let model = model.to_str().unwrap();
    let text = stdout(&occlu(&["info", model]));
    assert!(
        text.contains("camera      'side' (node 2, perspective, fov 68.8°, near 0.2)"),
        "{text}"
    );
    assert!(
        text.contains("animation   'tour' (2 channels, 2.00 s, moves camera 'ride')"),
        "{text}"
    );
    assert!(
        text.contains("animation   'spin' (1 channels, 1.00 s, moves no camera)"),
        "{text}"
    );
    let out = dir.path().join("p.json");
    let no_such = occlu(&[
        "path",
        "gen",
        model,
        "--kind",
        "animation=nope",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(no_such.status.code(), Some(2));
    assert!(common::stderr(&no_such).contains("no animation 'nope' moves a camera (those that do: tour, dolly)"));
    let obj = write(dir.path(), "m.obj", common::THREE_OBJECTS_OBJ);
    let none = occlu(&[
        "path",
        "gen",
        obj.to_str().unwrap(),
        "--kind",
        "cameras",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(none.status.code(), Some(2));
    assert!(common::stderr(&none).contains("the model has no cameras"));
    let bad = occlu(&[
        "path",
        "gen",
        obj.to_str().unwrap(),
        "--kind",
        "orbit=x",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(common::stderr(&bad).contains("only the animation kind takes a name"));
}

#[test]
fn a_camera_or_animation_occlu_cannot_use_is_left_out_with_a_warning() {
    let mut w = GltfWriter::default();
    let (p, i) = cube();
    let mesh = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let cube_node = w.node(json!({"name": "cube", "mesh": mesh}));
    let lost = w.node(json!({"name": "lost", "camera": 0}));
    let flat = w.node(json!({"name": "flat", "children": [lost], "scale": [0.0, 0.0, 0.0]}));
    let kept = w.node(json!({"name": "kept", "camera": 0, "translation": [0.0, 0.0, 5.0]}));
    let blind = w.node(json!({"name": "blind", "camera": 1}));
    let flat_view = w.node(json!({"name": "flat view", "camera": 2}));
    // Valid glTF, but wider than a view takes (179.989°), or nearer.
    let wide = w.node(json!({"name": "wide", "camera": 3}));
    let near = w.node(json!({"name": "near", "camera": 4}));
    // Kept, drawn in perspective, with a warning that says so.
    let ortho = w.node(json!({"name": "ortho", "camera": 5, "translation": [0.0, 0.0, 5.0]}));
    // Keys out of order, and keys at -0 and +0 in two channels.
    let backwards = w.floats(&[0.0, 2.0, 1.0], "SCALAR");
    let moves = w.floats(&[0.0; 9], "VEC3");
    let signed_zero = w.floats(&[-0.0, 1.0], "SCALAR");
    let zero = w.floats(&[0.0, 1.0], "SCALAR");
    let two = w.floats(&[0.0, 0.0, 5.0, 1.0, 0.0, 5.0], "VEC3");
    let scales = w.floats(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0], "VEC3");
    w.extra.insert(
        "cameras".into(),
        json!([
            {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}},
            {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.0}},
            {"type": "perspective", "perspective": {"yfov": 0.0, "znear": 0.05}},
            {"type": "perspective", "perspective": {"yfov": 3.1414, "znear": 0.05}},
            {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 1e-12}},
            {"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.05, "zfar": 100.0}}
        ]),
    );
    w.extra.insert(
        "animations".into(),
        json!([
            {"name": "backwards", "samplers": [{"input": backwards, "output": moves}],
             "channels": [{"sampler": 0, "target": {"node": kept, "path": "translation"}}]},
            {"name": "zeros", "samplers": [{"input": signed_zero, "output": two}, {"input": zero, "output": scales}],
             "channels": [{"sampler": 0, "target": {"node": kept, "path": "translation"}},
                          {"sampler": 1, "target": {"node": kept, "path": "scale"}}]}
        ]),
    );
    let dir = tempfile::tempdir().unwrap();
    let model = write(
        dir.path(),
        "odd.glb",
        w.glb(&[cube_node, flat, kept, blind, flat_view, wide, near, ortho]),
    );
    let scene = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
    let names: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["kept", "ortho"]);
    let said = scene.warnings.join(" | ");
    assert!(
        said.contains("camera 'ortho' is orthographic: occlu draws it in perspective"),
        "{said}"
    );
    assert!(said.contains("camera 'lost' is left out"), "{said}");
    assert!(
        said.contains("camera 'blind' is left out: its znear is 0: occlu's views take near planes from 1e-9 to 1e9"),
        "{said}"
    );
    assert!(
        said.contains(
            "camera 'flat view' is left out: its yfov is 0°: occlu's views take fields of view from 1° to 179.9°"
        ),
        "{said}"
    );
    assert!(
        said.contains("camera 'wide' is left out: its yfov is 179.989°"),
        "{said}"
    );
    assert!(
        said.contains("camera 'near' is left out: its znear is 0.000000000001:"),
        "{said}"
    );
    assert!(
        said.contains("animation 'backwards' is not replayed") && said.contains("increasing"),
        "{said}"
    );
    // -0 and +0 are one time: the second animation replays.
    let zeros = plan(Some(&request(PathKind::Animation, Some("zeros"))), &scene, None).unwrap();
    assert!(CameraPath::from_file(&zeros.file, "zeros").is_ok());
}
