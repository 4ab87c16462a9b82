//! Which way is up: +Z-up models are recognised, and generated paths and
//! the overview follow the scene's up axis.

mod common;

use common::{boxes_obj, occlu, stdout, town, write};
use glam::DVec3;
use occlu::auto_or::AutoOr;
use occlu::camera::generate::{PathKind, generate};
use occlu::camera::path::CameraPath;
use occlu::scene::up::{UpAxis, UpChoice};
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

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
    let z_up = load_obj(dir.path(), "z.obj", &town(false), AutoOr::Auto);
    assert_eq!(z_up.up.axis, UpAxis::Z, "{}", z_up.up.why);
    assert!(
        z_up.up.why.contains("objects standing on its Z minimum"),
        "{}",
        z_up.up.why
    );
    let y_up = load_obj(dir.path(), "y.obj", &town(true), AutoOr::Auto);
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
    let facade = load_obj(dir.path(), "f.obj", &facade, AutoOr::Auto);
    assert_eq!(facade.up.axis, UpAxis::Y, "{}", facade.up.why);
    // --up wins.
    let forced = load_obj(dir.path(), "z2.obj", &town(false), AutoOr::Given(UpAxis::Y));
    assert_eq!(forced.up.axis, UpAxis::Y);
}

#[test]
fn generated_paths_circle_and_walk_about_the_up_axis() {
    let dir = tempfile::tempdir().unwrap();
    for (swap, up) in [(false, DVec3::Z), (true, DVec3::Y)] {
        let scene = load_obj(dir.path(), "t.obj", &town(swap), AutoOr::Auto);
        let c = scene.bounds.center();
        // One frame per keyframe, so each lies on the circle exactly.
        let orbit = CameraPath::from_file(&generate(PathKind::Orbit, &scene, 25).unwrap(), "orbit").unwrap();
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
        let walk = CameraPath::from_file(&generate(PathKind::Walk, &scene, 20).unwrap(), "walk").unwrap();
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
