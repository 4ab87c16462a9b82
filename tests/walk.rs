//! The default path of a model: a walk through a flat place's free space at
//! eye height, never nearer a surface than the near plane; inside a dome
//! rather than around it; an orbit around an object. Distances are checked
//! against a brute-force computation over every triangle, which shares no
//! code with the ray caster the planner uses.

mod common;

use common::{boxes_obj, distance, first_hit, frames_too_near, town, world_triangles, write};
use glam::DVec3;
use occlu::camera::generate::{PathKind, default_path, plan};
use occlu::camera::path::CameraPath;
use occlu::raycast::RayCaster;
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

fn load_obj(dir: &std::path::Path, boxes: &[(String, DVec3, DVec3)]) -> Scene {
    let model = write(dir, "model.obj", boxes_obj(boxes));
    load(&SceneSpec::File(model), &LoadOptions::default()).unwrap()
}

/// `model` loaded with meshes cut into clusters of `cluster_triangles`,
/// and its default path, which must be a walk (with why).
fn walked(model: &std::path::Path, cluster_triangles: u32) -> (Scene, CameraPath, String) {
    let options = LoadOptions {
        cluster_triangles,
        ..LoadOptions::default()
    };
    let scene = load(&SceneSpec::File(model.to_path_buf()), &options).unwrap();
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    (scene, path, why)
}

/// The buildings of [`town`] (all but the ground).
fn buildings(scene: &Scene) -> Vec<occlu::bounds::Aabb> {
    scene
        .objects
        .iter()
        .filter(|o| o.name.starts_with("building"))
        .map(|o| o.bounds)
        .collect()
}

#[test]
fn a_flat_town_is_walked_through_its_streets_at_eye_height() {
    let dir = tempfile::tempdir().unwrap();
    for swap in [false, true] {
        let scene = load_obj(dir.path(), &town(swap));
        let up = scene.up.axis.vector();
        let (path, why) = default_path(&scene).unwrap();
        assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
        assert!(
            why.contains("a place with open ground") && why.contains("eye height 1.7"),
            "{why}"
        );
        let houses = buildings(&scene);
        for f in 0..path.frames {
            let camera = path.camera(f, 4.0 / 3.0);
            // The town stands on its ground at height 0 (in +Z or +Y).
            assert!((camera.eye.dot(up) - 1.7).abs() < 1e-6, "frame {f}: {}", camera.eye);
            assert!(
                houses.iter().all(|h| !h.contains_point(camera.eye)),
                "frame {f}: inside a building at {}",
                camera.eye
            );
        }
        assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
        assert_eq!(
            path.frames_with_geometry_within_near(&RayCaster::new(&scene), 4.0 / 3.0),
            Ok(0)
        );
        // Down the streets between the blocks, not round the open edge.
        let (right, ahead) = scene.up.axis.ground_axes();
        let between = (0..path.frames)
            .filter(|&f| {
                let eye = path.camera(f, 4.0 / 3.0).eye;
                let (x, y) = (eye.dot(right).abs(), eye.dot(ahead).abs());
                (10.0..=110.0).contains(&x) && (10.0..=110.0).contains(&y)
            })
            .count();
        assert!(
            2 * between >= path.frames as usize,
            "{between} of {} frames between the blocks",
            path.frames
        );
    }
}

#[test]
fn a_closed_hall_around_the_town_is_space_to_walk_in() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = town(true);
    // A closed box around the town, its floor level with the ground.
    boxes.push((
        "hall".into(),
        DVec3::new(-20.0, 0.0, -20.0),
        DVec3::new(140.0, 60.0, 140.0),
    ));
    let scene = load_obj(dir.path(), &boxes);
    let (path, why) = default_path(&scene).unwrap();
    assert!(
        path.source.ends_with("walk") && why.contains("'hall' hides"),
        "{}: {why}",
        path.source
    );
    for f in 0..path.frames {
        let eye = path.camera(f, 4.0 / 3.0).eye;
        assert!((eye.y - 1.7).abs() < 1e-6, "frame {f}: {eye} ({why})");
    }
}

#[test]
fn a_thick_ground_slab_is_walked_on_not_in_even_when_split_into_clusters() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = town(true);
    // The ground 5 thick: its inside must not count as room to walk.
    boxes[0].1.y = -5.0;
    let model = write(dir.path(), "model.obj", boxes_obj(&boxes));
    // Whole, and every box cut into three clusters (none closed alone).
    for cluster_triangles in [4096, 4] {
        let (scene, path, _) = walked(&model, cluster_triangles);
        let houses = buildings(&scene);
        for f in 0..path.frames {
            let eye = path.camera(f, 4.0 / 3.0).eye;
            assert!(
                (eye.y - 1.7).abs() < 1e-6,
                "clusters of {cluster_triangles}, frame {f}: {eye}"
            );
            assert!(houses.iter().all(|h| !h.contains_point(eye)), "frame {f}: {eye}");
        }
    }
}

/// A town of `n`×`n` blocks `block` wide with streets `street` wide, on a
/// ground slab reaching `margin` beyond them, +Y up.
fn town_grid(n: u32, block: f64, street: f64, margin: f64) -> Vec<(String, DVec3, DVec3)> {
    let size = f64::from(n) * (block + street) - street;
    let mut boxes = vec![(
        "ground".to_string(),
        DVec3::new(-margin, -1.0, -margin),
        DVec3::new(size + margin, 0.0, size + margin),
    )];
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (f64::from(i) * (block + street), f64::from(j) * (block + street));
            let height = 8.0 + f64::from((i * 7 + j * 3) % 5) * 4.0;
            boxes.push((
                format!("building_{i}_{j}"),
                DVec3::new(x, 0.0, z),
                DVec3::new(x + block, height, z + block),
            ));
        }
    }
    boxes
}

/// How many of `path`'s frames have the eye inside the square `[lo, hi]²`
/// of the ground (x and z).
fn frames_within(path: &CameraPath, lo: f64, hi: f64) -> usize {
    (0..path.frames)
        .filter(|&f| {
            let eye = path.camera(f, 4.0 / 3.0).eye;
            (lo..=hi).contains(&eye.x) && (lo..=hi).contains(&eye.z)
        })
        .count()
}

#[test]
fn streets_a_few_metres_wide_in_a_large_town_are_walked() {
    let dir = tempfile::tempdir().unwrap();
    // 12×12 blocks 28 wide with streets of 5.2: 393 across, with 20 of
    // open ground around. (160 cells across, as before, were 2.7 wide: no
    // street held the three cell centres an open cell needs.)
    let boxes = town_grid(12, 28.0, 5.2, 20.0);
    let scene = load_obj(dir.path(), &boxes);
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    let houses = buildings(&scene);
    for f in 0..path.frames {
        let eye = path.camera(f, 4.0 / 3.0).eye;
        assert!((eye.y - 1.7).abs() < 1e-6, "frame {f}: {eye}");
        assert!(houses.iter().all(|h| !h.contains_point(eye)), "frame {f}: {eye}");
    }
    // Down the narrow streets, not round the open margin.
    let between = frames_within(&path, 28.0, 365.0);
    assert!(
        2 * between >= path.frames as usize,
        "{between} of {} frames ({why})",
        path.frames
    );
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}

#[test]
fn a_town_on_a_slope_is_walked_across_the_slope_at_eye_height() {
    let dir = tempfile::tempdir().unwrap();
    // The town rising one unit in ten along x (every vertex lifted: walls
    // stay upright, ground and roofs tilt).
    let obj: String = boxes_obj(&town(true))
        .lines()
        .map(|line| match line.strip_prefix("v ") {
            Some(v) => {
                let [x, y, z] = [0, 1, 2].map(|k| v.split(' ').nth(k).unwrap().parse::<f64>().unwrap());
                format!("v {x} {} {z}\n", y + 0.1 * x)
            }
            None => format!("{line}\n"),
        })
        .collect();
    let model = write(dir.path(), "slope.obj", obj);
    let scene = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    let (mut least, mut most) = (f64::INFINITY, f64::NEG_INFINITY);
    for f in 0..path.frames {
        let eye = path.camera(f, 4.0 / 3.0).eye;
        // The ground is the plane y = x / 10.
        assert!((eye.y - 0.1 * eye.x - 1.7).abs() < 1e-6, "frame {f}: {eye}");
        (least, most) = (least.min(eye.x), most.max(eye.x));
    }
    // Up and down the slope, not along one contour.
    assert!(most - least >= 60.0, "x from {least} to {most} ({why})");
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}

#[test]
fn a_short_lane_in_open_ground_does_not_hold_the_walk() {
    let dir = tempfile::tempdir().unwrap();
    // A park 200 across with thin posts every 25 (too sparse to wall it),
    // and in one corner a lane 60 long between two walls: a street, but
    // short against the park.
    let mut boxes = vec![(
        "ground".to_string(),
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(200.0, 0.0, 200.0),
    )];
    for i in 0..8 {
        for j in 0..8 {
            let (x, z) = (12.5 + 25.0 * f64::from(i), 12.5 + 25.0 * f64::from(j));
            boxes.push((
                format!("post_{i}_{j}"),
                DVec3::new(x, 0.0, z),
                DVec3::new(x + 1.0, 10.0, z + 1.0),
            ));
        }
    }
    boxes.push((
        "wall_a".into(),
        DVec3::new(130.0, 0.0, 170.0),
        DVec3::new(190.0, 12.0, 175.0),
    ));
    boxes.push((
        "wall_b".into(),
        DVec3::new(130.0, 0.0, 185.0),
        DVec3::new(190.0, 12.0, 190.0),
    ));
    let scene = load_obj(dir.path(), &boxes);
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    let walk: f64 = (1..path.frames)
        .map(|f| {
            path.camera(f, 4.0 / 3.0)
                .eye
                .distance(path.camera(f - 1, 4.0 / 3.0).eye)
        })
        .sum();
    assert!(walk >= 150.0, "a walk of {walk:.1} ({why})");
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}

#[test]
fn an_island_town_is_walked_in_its_streets_not_on_the_sea_around_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = town_grid(4, 18.0, 10.0, 10.0);
    // The town on an island 3 above the sea, which reaches 300 beyond it.
    boxes[0].1.y = 0.0;
    boxes[0].2.y = 3.0;
    for building in &mut boxes[1..] {
        building.1.y += 3.0;
        building.2.y += 3.0;
    }
    boxes.push((
        "sea".into(),
        DVec3::new(-300.0, -1.0, -300.0),
        DVec3::new(402.0, 0.0, 402.0),
    ));
    let scene = load_obj(dir.path(), &boxes);
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    for f in 0..path.frames {
        let eye = path.camera(f, 4.0 / 3.0).eye;
        assert!((eye.y - 4.7).abs() < 1e-6, "frame {f}: {eye} ({why})");
    }
    let between = frames_within(&path, 0.0, 102.0);
    assert!(
        2 * between >= path.frames as usize,
        "{between} of {} frames ({why})",
        path.frames
    );
}

#[test]
fn a_dome_around_the_town_makes_the_default_path_go_inside() {
    let dir = tempfile::tempdir().unwrap();
    let boxes = town(true);
    // A dome: one object, four walls and a roof (no floor) from -200 to 320
    // around the 120-unit town, 200 tall.
    let (lo, hi, top) = (-200.0, 320.0, 200.0);
    let mut obj = boxes_obj(&boxes);
    obj += "o dome\n";
    for (x, z) in [(lo, lo), (hi, lo), (hi, hi), (lo, hi)] {
        obj += &format!("v {x} -1 {z}\nv {x} {top} {z}\n");
    }
    let base = 8 * boxes.len();
    for k in 0..4 {
        let (a, b) = (2 * k, 2 * ((k + 1) % 4));
        let [a0, a1, b0, b1] = [a, a + 1, b, b + 1].map(|v| v + base + 1);
        obj += &format!("f {a0} {b0} {b1} {a1}\n");
    }
    obj += &format!("f {} {} {} {}\n", base + 2, base + 4, base + 6, base + 8);
    let model = write(dir.path(), "domed.obj", obj);
    // Whole, and split into clusters of 4 triangles (the dome in three).
    for cluster_triangles in [4096, 4] {
        let (scene, path, why) = walked(&model, cluster_triangles);
        // The orbit circles outside the dome, which hides the town.
        assert!(why.contains("'dome' hides"), "{why}");
        let houses = buildings(&scene);
        for f in 0..path.frames {
            let eye = path.camera(f, 4.0 / 3.0).eye;
            // On the town's ground, between its buildings.
            assert!((eye.y - 1.7).abs() < 1e-6, "frame {f}: {eye}");
            assert!(
                (0.0..=120.0).contains(&eye.x) && (0.0..=120.0).contains(&eye.z),
                "frame {f}: {eye}"
            );
            assert!(houses.iter().all(|h| !h.contains_point(eye)), "frame {f}: {eye}");
        }
        assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
    }
}

#[test]
fn objects_are_circled_and_built_in_streets_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    // A tower: taller than wide, an object.
    let tower = vec![("tower".to_string(), DVec3::ZERO, DVec3::new(10.0, 40.0, 10.0))];
    let scene = load_obj(dir.path(), &tower);
    let generated = plan(None, &scene, Some(30)).unwrap();
    assert_eq!(generated.kind, PathKind::Orbit, "{}", generated.why);
    let city = load(&SceneSpec::Builtin("city:blocks=2".into()), &LoadOptions::default()).unwrap();
    let (path, why) = default_path(&city).unwrap();
    assert!(
        path.source.ends_with("walk") && why == "the walk the scene was built with",
        "{why}"
    );
    let path = path.with_frames(40).unwrap();
    assert_eq!(frames_too_near(&path, &world_triangles(&city)), Vec::<u32>::new());
}

#[test]
fn the_ray_caster_agrees_with_every_triangle_tried_in_turn() {
    let dir = tempfile::tempdir().unwrap();
    let scene = load_obj(dir.path(), &town(false));
    let caster = RayCaster::new(&scene);
    let triangles = world_triangles(&scene);
    let mut rng = occlu::rng::Rng::new(12345);
    let mut random = || rng.range(0.0, 1.0);
    let mut hits = 0;
    for _ in 0..400 {
        let origin = DVec3::new(random() * 160.0 - 20.0, random() * 160.0 - 20.0, random() * 50.0);
        let direction = DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5);
        let expected = first_hit(&triangles, origin, direction, 400.0).unwrap_or(f64::INFINITY);
        match caster.first_hit(origin, direction, 400.0) {
            Some(hit) => {
                hits += 1;
                assert!(
                    (hit.t - expected).abs() < 1e-9,
                    "{origin} {direction}: {} vs {expected}",
                    hit.t
                );
            }
            None => assert!(expected.is_infinite(), "{origin} {direction}: missed {expected}"),
        }
        let nearest = triangles
            .iter()
            .map(|t| distance(origin, t))
            .fold(f64::INFINITY, f64::min);
        let found = caster.nearest_distance(origin, 1e9).unwrap();
        assert!((found - nearest).abs() < 1e-9, "{origin}: {found} vs {nearest}");
    }
    assert!(hits > 100, "the rays meet the town ({hits} of 400)");
}

#[test]
fn den_haag_is_walked_without_clipping() {
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models/den-haag.obj");
    if !model.exists() {
        common::cannot_run(&format!("{} is absent", model.display()));
        return;
    }
    let scene = load(&SceneSpec::File(model), &LoadOptions::default()).unwrap();
    let (path, why) = default_path(&scene).unwrap();
    assert!(path.source.ends_with("walk"), "{}: {why}", path.source);
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}
