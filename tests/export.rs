//! `occlu export`: the scene and path as a GLB load back as the same
//! triangles, bounds and cameras, and render the same depth.

mod common;

use occlu::camera::generate::default_path;
use occlu::gpu::Resolution;
use occlu::scene::{LoadOptions, SceneSpec, load};

#[test]
fn an_exported_city_and_walk_load_back_and_render_the_same() {
    let city = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
    let (walk, _) = default_path(&city).unwrap();
    let walk = walk.with_frames(12).unwrap();
    let aspect = 4.0 / 3.0;
    let dir = tempfile::tempdir().unwrap();
    let file = common::write(
        dir.path(),
        "city.glb",
        occlu::export::glb(&city, &walk, aspect).unwrap(),
    );
    let back = load(&SceneSpec::File(file), &LoadOptions::default()).unwrap();
    assert_eq!(back.objects.len(), city.objects.len());
    assert_eq!(back.triangles(), city.triangles());
    let reach = city.bounds.extent().length();
    assert!(back.bounds.min.distance(city.bounds.min) < 1e-6 * reach);
    assert!(back.bounds.max.distance(city.bounds.max) < 1e-6 * reach);
    // Its default path is the exported walk, frame for frame.
    let (replay, why) = default_path(&back).unwrap();
    assert!(why.contains("'occlu path'"), "{why}");
    assert_eq!(replay.frames, walk.frames);
    let size = Resolution {
        width: 160,
        height: 120,
    };
    for f in 0..walk.frames {
        let (a, b) = (walk.camera(f, aspect), replay.camera(f, aspect));
        assert!(
            a.eye.distance(b.eye) < 1e-5 * reach,
            "frame {f}: {} vs {}",
            a.eye,
            b.eye
        );
        assert!(a.rotation.dot(b.rotation).abs() > 1.0 - 1e-9, "frame {f}");
        assert!((a.fov_y - b.fov_y).abs() < 1e-6 && (a.near - b.near).abs() < 1e-6 * a.near);
        if f % 6 == 0 {
            let (da, db) = (
                common::reference_depth(&city, &a, size),
                common::reference_depth(&back, &b, size),
            );
            let covered = da.iter().filter(|&&d| d > 0.0).count();
            let moved = da
                .iter()
                .zip(&db)
                .filter(|(x, y)| (*x - *y).abs() > 1e-5 * x.abs().max(1e-3))
                .count();
            assert!(
                covered > 1000 && moved * 100 <= covered,
                "frame {f}: {moved} of {covered} pixels differ"
            );
        }
    }
}

#[test]
fn a_z_up_model_is_exported_y_up_as_gltf_expects() {
    let dir = tempfile::tempdir().unwrap();
    let model = common::write(dir.path(), "town.obj", common::boxes_obj(&common::town(false)));
    let town = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
    assert_eq!(town.up.axis, occlu::scene::up::UpAxis::Z);
    let (path, _) = default_path(&town).unwrap();
    let path = path.with_frames(4).unwrap();
    let file = common::write(
        dir.path(),
        "town.glb",
        occlu::export::glb(&town, &path, 4.0 / 3.0).unwrap(),
    );
    let back = load(&SceneSpec::File(file), &LoadOptions::default()).unwrap();
    // +Z turned to +Y: (x, y, z) becomes (x, z, -y).
    let turn = |v: glam::DVec3| glam::DVec3::new(v.x, v.z, -v.y);
    let (a, b) = (turn(town.bounds.min), turn(town.bounds.max));
    let expected = occlu::bounds::Aabb::new(a.min(b), a.max(b));
    assert!(
        back.bounds.min.distance(expected.min) < 1e-4 && back.bounds.max.distance(expected.max) < 1e-4,
        "{:?} vs {expected:?}",
        back.bounds
    );
    assert_eq!(back.up.axis, occlu::scene::up::UpAxis::Y);
    let (replay, _) = default_path(&back).unwrap();
    for f in 0..path.frames {
        let (p, q) = (path.camera(f, 4.0 / 3.0), replay.camera(f, 4.0 / 3.0));
        assert!(
            turn(p.eye).distance(q.eye) < 1e-4,
            "frame {f}: {} vs {}",
            turn(p.eye),
            q.eye
        );
    }
}

#[test]
fn an_export_of_a_path_whose_field_of_view_changes_says_it_keeps_frame_0s() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str, last_fov: f64| {
        let text = format!(
            r#"{{"frames": 4, "keyframes": [
                {{"time": 0, "position": [2, 1.7, 2], "target": [20, 1.7, 15], "fov_y_deg": 90}},
                {{"time": 1, "position": [3, 1.7, 2], "target": [20, 1.7, 15], "fov_y_deg": {last_fov}}}]}}"#
        );
        common::write(dir.path(), name, text)
    };
    let export = |path: &std::path::Path| {
        let glb = dir.path().join("out.glb");
        let out = common::occlu(&[
            "export",
            "--scene",
            "city:blocks=1",
            "--path",
            path.to_str().unwrap(),
            "-o",
            glb.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{:?}", common::own_stderr(&out));
        common::own_stderr(&out).join("\n")
    };
    let said = export(&path("zoom.json", 10.0));
    assert!(
        said.contains(
            "warning: the path's field of view changes (10° to 90°): the export keeps frame 0's, 90°, throughout"
        ),
        "{said}"
    );
    let said = export(&path("steady.json", 90.0));
    assert!(!said.contains("field of view"), "{said}");
}

#[test]
fn a_path_at_the_narrowest_field_of_view_exports_and_replays_at_it() {
    // 1° in f32 radians reads back as 0.99999997°: still the path's 1°.
    let dir = tempfile::tempdir().unwrap();
    let path = common::write(
        dir.path(),
        "narrow.json",
        r#"{"frames": 3, "fov_y_deg": 1, "keyframes": [
            {"time": 0, "position": [2, 1.7, 2], "target": [20, 1.7, 15]},
            {"time": 1, "position": [3, 1.7, 2], "target": [20, 1.7, 15]}]}"#,
    );
    let path = occlu::camera::path::CameraPath::load(&path).unwrap();
    let city = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
    let file = common::write(
        dir.path(),
        "narrow.glb",
        occlu::export::glb(&city, &path, 4.0 / 3.0).unwrap(),
    );
    let back = load(&SceneSpec::File(file), &LoadOptions::default()).unwrap();
    assert_eq!(back.cameras.len(), 1, "{:?}", back.warnings);
    let (replay, why) = default_path(&back).unwrap();
    assert!(why.contains("'occlu path'"), "{why}");
    assert_eq!(replay.camera(1, 4.0 / 3.0).fov_y, 1f64.to_radians());
}
