//! Which way is up: +Z-up models are recognised, and generated paths and
//! the overview follow the scene's up axis.

mod common;

use common::{occlu, stdout, write};
use glam::DVec3;
use occlu::camera::generate::{PathKind, generate};
use occlu::camera::path::CameraPath;
use occlu::scene::up::{UpAxis, UpChoice};
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

/// An OBJ of axis-aligned boxes `(name, min, max)`, coordinates as given.
fn boxes_obj(boxes: &[(String, DVec3, DVec3)]) -> String {
    let mut obj = String::new();
    for (k, (name, min, max)) in boxes.iter().enumerate() {
        obj += &format!("o {name}\n");
        for corner in 0..8 {
            let pick = |bit: usize, lo: f64, hi: f64| if corner & bit == 0 { lo } else { hi };
            let (x, y, z) = (pick(1, min.x, max.x), pick(2, min.y, max.y), pick(4, min.z, max.z));
            obj += &format!("v {x} {y} {z}\n");
        }
        let base = 8 * k + 1;
        for face in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            let [a, b, c, d] = face.map(|i| i + base);
            obj += &format!("f {a} {b} {c} {d}\n");
        }
    }
    obj
}

/// A town of 4×4 blocks on a ground slab, built +Z up: 120 units across,
/// buildings 6 to 36 tall. `swap` turns it +Y up (y and z exchanged).
fn town(swap: bool) -> Vec<(String, DVec3, DVec3)> {
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

fn load_obj(dir: &std::path::Path, name: &str, boxes: &[(String, DVec3, DVec3)], up: UpChoice) -> Scene {
    let model = write(dir, name, boxes_obj(boxes));
    let options = LoadOptions {
        up,
        ..LoadOptions::default()
    };
    load(&SceneSpec::File(model), &options).unwrap()
}

#[test]
fn auto_picks_z_for_a_z_up_town_and_y_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let z_up = load_obj(dir.path(), "z.obj", &town(false), UpChoice::Auto);
    assert_eq!(z_up.up.axis, UpAxis::Z, "{}", z_up.up.why);
    assert!(
        z_up.up.why.contains("objects standing on its Z minimum"),
        "{}",
        z_up.up.why
    );
    let y_up = load_obj(dir.path(), "y.obj", &town(true), UpChoice::Auto);
    assert_eq!(y_up.up.axis, UpAxis::Y, "{}", y_up.up.why);
    // A facade, thin in Z, whose parts span its whole depth: +Y.
    let facade: Vec<_> = (0..6)
        .map(|k| {
            let x = 12.0 * f64::from(k);
            let top = 10.0 + 5.0 * f64::from(k % 3);
            (
                format!("panel{k}"),
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(x + 10.0, top, 2.0),
            )
        })
        .collect();
    let facade = load_obj(dir.path(), "f.obj", &facade, UpChoice::Auto);
    assert_eq!(facade.up.axis, UpAxis::Y, "{}", facade.up.why);
    // --up wins.
    let forced = load_obj(dir.path(), "z2.obj", &town(false), UpChoice::Axis(UpAxis::Y));
    assert_eq!(forced.up.axis, UpAxis::Y);
}

#[test]
fn generated_paths_circle_and_walk_about_the_up_axis() {
    let dir = tempfile::tempdir().unwrap();
    for (swap, up) in [(false, DVec3::Z), (true, DVec3::Y)] {
        let scene = load_obj(dir.path(), "t.obj", &town(swap), UpChoice::Auto);
        let c = scene.bounds.center();
        // One frame per keyframe, so each lies on the circle exactly.
        let orbit = CameraPath::from_file(&generate(PathKind::Orbit, &scene, 25), "orbit").unwrap();
        assert_eq!(orbit.keyframes.len(), 25);
        let mut distances = Vec::new();
        for f in 0..25 {
            let camera = orbit.camera(f, 4.0 / 3.0);
            let offset = camera.eye - c;
            let height = offset.dot(up);
            let across = (offset - up * height).length();
            // 25° above the ground plane, looking at the centre, upright.
            assert!(
                (height / across - 25f64.to_radians().tan()).abs() < 1e-9,
                "{up} frame {f}"
            );
            assert!(camera.forward().dot(-offset.normalize()) > 0.999_999, "{up} frame {f}");
            let right = camera.rotation * DVec3::X;
            assert!(right.dot(up).abs() < 1e-9, "{up} frame {f}: rolled");
            assert!(
                (camera.rotation * DVec3::Y).dot(up) > 0.0,
                "{up} frame {f}: upside down"
            );
            distances.push(across);
        }
        assert!(distances.iter().all(|d| (d - distances[0]).abs() < 1e-9 * d));
        let walk = CameraPath::from_file(&generate(PathKind::Walk, &scene, 20), "walk").unwrap();
        let ground = scene
            .bounds
            .corners()
            .map(|p| p.dot(up))
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        for f in 0..20 {
            let camera = walk.camera(f, 4.0 / 3.0);
            assert!(camera.eye.dot(up) > ground, "{up} frame {f}: below the ground");
            assert!(camera.forward().dot(up).abs() < 1e-9, "{up} frame {f}: looks level");
        }
    }
}

#[test]
fn info_prints_the_up_axis_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "z.obj", boxes_obj(&town(false)));
    let model = model.to_str().unwrap();
    let auto = occlu(&["info", model]);
    assert!(auto.status.success());
    let text = stdout(&auto);
    assert!(text.contains("up          +Z (auto: OBJ looks +Z up"), "{text}");
    let given = stdout(&occlu(&["info", model, "--up", "-y"]));
    assert!(given.contains("up          -Y (given by --up)"), "{given}");
    let json: serde_json::Value = serde_json::from_str(&stdout(&occlu(&["info", model, "--json"]))).unwrap();
    assert_eq!(json["up"]["axis"], "+Z");
    let bad = occlu(&["info", model, "--up", "sideways"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(common::stderr(&bad).contains("'sideways' is not an up axis"));
}
