//! The default path's class where it used to miss the model: an interior
//! (a hall under a roof) is walked inside, alone or on a ground plane 20
//! times wider; a furnished room on a huge plane is framed, not the plane;
//! and every model in ../shared/models and every built-in scene keeps the
//! kind of path it had. Each is checked by the test's own computations:
//! rays tried against every triangle in turn, the room's box from the list
//! the test built it from, the camera's pixel rays through that box.

mod common;

use common::gltf_writer::{GltfWriter, cube_indices};
use common::hall::hall;
use common::{
    boxes_obj, cannot_run, first_hit, frames_too_near, occlu, shared_models, shared_models_dir, stderr, town,
    world_triangles, write,
};
use glam::DVec3;
use occlu::bounds::Aabb;
use occlu::camera::generate::{Generated, PathKind, plan};
use occlu::camera::path::{CameraPath, PathFile};
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};
use serde_json::json;

type Boxes = Vec<(String, DVec3, DVec3)>;

fn part(name: &str, min: [f64; 3], max: [f64; 3]) -> (String, DVec3, DVec3) {
    (name.to_string(), DVec3::from(min), DVec3::from(max))
}

/// The box of `boxes`, as the test built them.
fn box_of(boxes: &[(String, DVec3, DVec3)]) -> Aabb {
    boxes
        .iter()
        .fold(Aabb::EMPTY, |b, (_, min, max)| b.union(Aabb::new(*min, *max)))
}

/// A flat plane under `boxes`, `times` as wide as their box and centred
/// under it, its top at `top`.
fn plane_under(boxes: &[(String, DVec3, DVec3)], times: f64, top: f64) -> (String, DVec3, DVec3) {
    let b = box_of(boxes);
    let (c, half) = (b.center(), b.extent() * 0.5 * times);
    let (min, max) = (c - half, c + half);
    part("ground", [min.x, top - 0.1, min.z], [max.x, top, max.z])
}

fn load_boxes(dir: &std::path::Path, boxes: &[(String, DVec3, DVec3)]) -> Scene {
    load_obj(dir, boxes_obj(boxes))
}

/// `boxes` as a GLB file in `dir`, each box a mesh on a node of its own,
/// loaded.
fn load_glb(dir: &std::path::Path, boxes: &[(String, DVec3, DVec3)]) -> Scene {
    let mut gltf = GltfWriter::default();
    let roots: Vec<usize> = boxes
        .iter()
        .map(|(name, min, max)| {
            let pick = |corner: usize, bit: usize, lo: f64, hi: f64| if corner & bit == 0 { lo } else { hi } as f32;
            let corners: Vec<[f32; 3]> = (0..8)
                .map(|c| {
                    [
                        pick(c, 1, min.x, max.x),
                        pick(c, 2, min.y, max.y),
                        pick(c, 4, min.z, max.z),
                    ]
                })
                .collect();
            let mesh = gltf.mesh(name, &[(&corners, Some(&cube_indices()), 4)]);
            gltf.node(json!({"name": name, "mesh": mesh}))
        })
        .collect();
    let model = dir.join("model.glb");
    std::fs::write(&model, gltf.glb(&roots)).unwrap();
    load(&SceneSpec::File(model), &LoadOptions::default()).unwrap()
}

fn load_obj(dir: &std::path::Path, obj: String) -> Scene {
    let model = write(dir, "model.obj", obj);
    load(&SceneSpec::File(model), &LoadOptions::default()).unwrap()
}

/// `boxes` as one OBJ object, one mesh (as a scan or a merged export
/// gives a model).
fn one_object(boxes: &[(String, DVec3, DVec3)]) -> String {
    let obj = boxes_obj(boxes);
    let faces = obj.lines().filter(|line| !line.starts_with("o "));
    std::iter::once("o model")
        .chain(faces)
        .map(|line| format!("{line}\n"))
        .collect()
}

/// The default path of `scene`, in `frames` frames.
fn default_of(scene: &Scene, frames: u32) -> (Generated, CameraPath) {
    let generated = plan(None, scene, Some(frames)).unwrap();
    let path = CameraPath::from_file(&generated.file, "default").unwrap();
    (generated, path)
}

/// Every keyframe of `generated` stands inside the model (a ray straight
/// up meets it, and level rays meet it in at least `walls` of eight
/// directions within `reach`, six at the route's ends), `eye` above a
/// floor, looking level and along the route.
fn assert_walked_inside(scene: &Scene, generated: &Generated, reach: f64, eye: f64, walls: usize) {
    let why = &generated.why;
    assert_eq!(generated.kind, PathKind::Walk, "{why}");
    let triangles = world_triangles(scene);
    let keys = &generated.file.keyframes;
    assert!(keys.len() >= 32, "{} keyframes ({why})", keys.len());
    for (k, key) in keys.iter().enumerate() {
        let p = DVec3::from(key.position);
        assert!(
            first_hit(&triangles, p, DVec3::Y, f64::INFINITY).is_some(),
            "key {k} at {p}: open to the sky ({why})"
        );
        let met = (0..8)
            .filter(|&a| {
                let angle = std::f64::consts::TAU * f64::from(a) / 8.0;
                let direction = DVec3::new(angle.cos(), 0.0, angle.sin());
                first_hit(&triangles, p, direction, reach).is_some()
            })
            .count();
        let least = if k == 0 || k + 1 == keys.len() { 6 } else { walls };
        assert!(met >= least, "key {k} at {p}: walls in {met} of 8 directions ({why})");
        let floor = first_hit(&triangles, p, DVec3::NEG_Y, f64::INFINITY);
        assert!(
            floor.is_some_and(|t| (t - eye).abs() < 1e-6),
            "key {k} at {p}: floor {floor:?} below ({why})"
        );
        let look = DVec3::from(key.target.expect("a walk looks at a point ahead")) - p;
        let along = match keys.get(k + 1) {
            Some(next) => DVec3::from(next.position) - p,
            None => p - DVec3::from(keys[k - 1].position),
        };
        assert!(
            look.y.abs() < 1e-9 && look.dot(along) > 0.0,
            "key {k} at {p}: looks {look}, the route goes {along}"
        );
    }
}

/// The default path of `scene` (in 120 frames) walks inside it as
/// [`assert_walked_inside`] says, with `walls` within `reach`, and comes
/// near no surface; its reason.
fn walked_inside(scene: &Scene, reach: f64, walls: usize) -> String {
    let (generated, path) = default_of(scene, 120);
    assert!(generated.why.starts_with("an interior"), "{}", generated.why);
    assert_walked_inside(scene, &generated, reach, 1.7, walls);
    assert_eq!(frames_too_near(&path, &world_triangles(scene)), Vec::<u32>::new());
    generated.why
}

/// The hall with `beside` added: [`walked_inside`], walls within the
/// hall's own size.
fn hall_walked_inside(beside: Boxes) -> String {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = hall();
    let reach = box_of(&boxes).extent().length();
    boxes.extend(beside);
    walked_inside(&load_boxes(dir.path(), &boxes), reach, 6)
}

#[test]
fn a_hall_under_a_roof_is_walked_inside() {
    hall_walked_inside(Vec::new());
    // The whole hall one mesh: what the orbit would miss is judged by
    // triangles, whatever the objects.
    let dir = tempfile::tempdir().unwrap();
    let boxes = hall();
    walked_inside(
        &load_obj(dir.path(), one_object(&boxes)),
        box_of(&boxes).extent().length(),
        6,
    );
}

/// One storey of rooms in metres, +Y up, as an office or a flat has them:
/// 4 × 4 rooms 8 m square under a roof 3 m up, walls 0.2 m thick, each
/// with a door 1 m wide and 2.1 m tall in each room's stretch of it, the
/// outer walls' too: at its middle (so lines of doors run from wall to
/// wall), or `staggered` a quarter of the way along it or three quarters,
/// by turns; a box a piece.
fn storey_of_rooms(staggered: bool) -> Boxes {
    let (rooms, side, ceiling, door, lintel, half_wall) = (4, 8.0, 3.0, 1.0, 2.1, 0.1);
    let span = f64::from(rooms) * side;
    let mut boxes = vec![
        part("floor", [0.0, -0.2, 0.0], [span, 0.0, span]),
        part("roof", [0.0, ceiling, 0.0], [span, ceiling + 0.2, span]),
    ];
    for line in 0..=rooms {
        let at = f64::from(line) * side;
        for room in 0..rooms {
            let (from, to) = (f64::from(room) * side, f64::from(room + 1) * side);
            let middle = match (staggered, (line + room) % 2) {
                (false, _) => (from + to) / 2.0,
                (true, 0) => from + side / 4.0,
                (true, _) => from + side * 3.0 / 4.0,
            };
            let pieces = [
                ("a", from, middle - door / 2.0, 0.0),
                ("b", middle + door / 2.0, to, 0.0),
                ("lintel", middle - door / 2.0, middle + door / 2.0, lintel),
            ];
            for (piece, a, b, bottom) in pieces {
                // A wall along x at z = `at`, and one along z at x = `at`.
                boxes.push(part(
                    &format!("wall_x{line}_{room}_{piece}"),
                    [a, bottom, at - half_wall],
                    [b, ceiling, at + half_wall],
                ));
                boxes.push(part(
                    &format!("wall_z{line}_{room}_{piece}"),
                    [at - half_wall, bottom, a],
                    [at + half_wall, ceiling, b],
                ));
            }
        }
    }
    boxes
}

/// [`walked_inside`] for a storey of rooms: a doorway sees out along its
/// line of doors and, doors being at the middle of square rooms' walls,
/// along both diagonals through the neighbours' doors, so keyframes on the
/// way need two walls of eight.
fn storey_walked_inside(boxes: &Boxes) {
    let dir = tempfile::tempdir().unwrap();
    walked_inside(&load_boxes(dir.path(), boxes), box_of(boxes).extent().length(), 2);
}

#[test]
fn a_storey_of_rooms_3_m_tall_with_doors_2_1_m_tall_lined_up_wall_to_wall_is_walked_inside() {
    storey_walked_inside(&storey_of_rooms(false));
}

#[test]
fn a_storey_of_rooms_with_a_chimney_is_walked_inside_not_on_its_roof() {
    // The chimney rises 2.5 m above the roof, so the roof lies more than
    // the room a floor needs below the model's top.
    let mut boxes = storey_of_rooms(false);
    boxes.push(part("chimney", [14.0, 3.2, 14.0], [15.0, 5.7, 15.0]));
    storey_walked_inside(&boxes);
}

#[test]
fn a_storey_of_rooms_with_staggered_doors_is_walked_a_cell_clear_of_its_thin_walls() {
    // Walls 0.2 m thick, cells of 0.2 m: a wall may stand between two
    // cells' centres, where no ray down meets it.
    storey_walked_inside(&storey_of_rooms(true));
}

#[test]
fn streets_over_a_metro_under_every_one_of_them_are_walked_as_without_it() {
    // The town is 120 m across, +Y up, its streets 10 m wide between
    // blocks 18 m square; a tunnel, four boxes 5 m high and 2 m down, runs
    // the whole width under each of its six inner streets (two thirds of
    // the open ground lies over one).
    let mut boxes = town(true);
    let planned = |boxes: &Boxes| {
        let dir = tempfile::tempdir().unwrap();
        let (generated, _) = default_of(&load_boxes(dir.path(), boxes), 10);
        let keys: Vec<[f64; 3]> = generated.file.keyframes.iter().map(|k| k.position).collect();
        (generated.why, keys)
    };
    let without = planned(&boxes);
    assert!(without.0.contains("through the streets"), "{}", without.0);
    for (k, from) in [28.0, 56.0, 84.0].into_iter().enumerate() {
        let to = from + 10.0;
        // Along x at z = from..to, and along z at x = from..to.
        for along_x in [true, false] {
            let piece = |name: &str, [y0, y1]: [f64; 2], [a, b]: [f64; 2]| {
                let name = format!("{name}_{k}_{along_x}");
                match along_x {
                    true => part(&name, [0.0, y0, a], [120.0, y1, b]),
                    false => part(&name, [a, y0, 0.0], [b, y1, 120.0]),
                }
            };
            boxes.extend([
                piece("floor", [-7.2, -7.0], [from, to]),
                piece("roof", [-2.2, -2.0], [from, to]),
                piece("wall_a", [-7.0, -2.2], [from - 0.2, from]),
                piece("wall_b", [-7.0, -2.2], [to, to + 0.2]),
            ]);
        }
    }
    assert_eq!(planned(&boxes), without);
}

#[test]
fn a_roof_on_columns_is_circled_saying_how_little_of_it_is_indoors() {
    let dir = tempfile::tempdir().unwrap();
    let hall = hall();
    let canopy: Boxes = hall
        .into_iter()
        .filter(|(name, _, _)| !name.starts_with("wall") && name != "lintel")
        .collect();
    let (generated, _) = default_of(&load_boxes(dir.path(), &canopy), 10);
    let why = &generated.why;
    assert_eq!(generated.kind, PathKind::Orbit, "{why}");
    assert!(
        why.contains("% of the walkable floor under a roof and joined, 0% indoors ("),
        "{why}"
    );
}

#[test]
fn a_roofed_porch_outside_the_door_is_left_out_of_the_walk() {
    // Outside the door (x 48, z 10 to 14): a floor and a roof 5 high on
    // two posts, 12 deep and 16 wide, open on three sides.
    hall_walked_inside(vec![
        part("porch_floor", [48.0, -0.5, 4.0], [60.0, 0.0, 20.0]),
        part("porch_roof", [48.0, 5.0, 4.0], [60.0, 5.5, 20.0]),
        part("porch_post_a", [59.0, 0.0, 4.0], [60.0, 5.0, 5.0]),
        part("porch_post_b", [59.0, 0.0, 19.0], [60.0, 5.0, 20.0]),
    ]);
}

#[test]
fn a_hall_on_a_ground_plane_20_times_wider_is_walked_inside() {
    let why = hall_walked_inside(vec![plane_under(&hall(), 20.0, -0.5)]);
    assert!(why.contains("without 'ground'"), "{why}");
}

#[test]
fn a_hall_and_a_ground_plane_20_times_wider_in_one_mesh_are_walked_inside() {
    // As a merged export gives them: the plane is a slab of 12 of the
    // mesh's triangles, not a part of its own.
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = hall();
    let reach = box_of(&boxes).extent().length();
    boxes.push(plane_under(&boxes, 20.0, -0.5));
    let why = walked_inside(&load_obj(dir.path(), one_object(&boxes)), reach, 6);
    assert!(why.contains("without the 12 largest triangles of 'model'"), "{why}");
}

#[test]
fn path_gen_says_the_class_and_why_and_kind_still_overrides_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = hall();
    let walls = box_of(&boxes);
    boxes.push(plane_under(&boxes, 20.0, -0.5));
    let model = write(dir.path(), "hall.obj", boxes_obj(&boxes));
    let output = dir.path().join("path.json");
    let path_gen = |kind: &[&str]| {
        let out = occlu(
            &[
                &["path", "gen", model.to_str().unwrap(), "-o", output.to_str().unwrap()],
                kind,
            ]
            .concat(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let file: PathFile = serde_json::from_slice(&std::fs::read(&output).unwrap()).unwrap();
        (stderr(&out), file)
    };
    let (said, _) = path_gen(&[]);
    assert!(said.contains("(walk: an interior ("), "{said}");
    assert!(said.contains("without 'ground'"), "{said}");
    // Asked for, an orbit circles the hall, not the plane.
    let (said, orbit) = path_gen(&["--kind", "orbit"]);
    assert!(said.contains("(orbit: asked for; framing its detail"), "{said}");
    let size = walls.extent().length();
    for key in &orbit.keyframes {
        let away = distance_to_box(DVec3::from(key.position), &walls);
        assert!(away <= 3.0 * size, "{away:.1} from the hall, {size:.1} across");
    }
}

/// A room 10 × 10 in metres, +Y up, without a roof: walls 3 tall (a door
/// in the south one) and furniture, each piece an object.
fn furnished_room() -> Boxes {
    vec![
        part("wall_north", [0.0, 0.0, 9.8], [10.0, 3.0, 10.0]),
        part("wall_west", [0.0, 0.0, 0.0], [0.2, 3.0, 9.8]),
        part("wall_east", [9.8, 0.0, 0.0], [10.0, 3.0, 9.8]),
        part("wall_south_a", [0.2, 0.0, 0.0], [4.0, 3.0, 0.2]),
        part("wall_south_b", [6.0, 0.0, 0.0], [9.8, 3.0, 0.2]),
        part("table", [4.0, 0.0, 4.0], [6.0, 0.8, 5.5]),
        part("chair_a", [4.5, 0.0, 3.2], [5.0, 1.0, 3.7]),
        part("chair_b", [5.0, 0.0, 5.8], [5.5, 1.0, 6.3]),
        part("bed", [7.0, 0.0, 1.0], [9.5, 0.6, 3.0]),
        part("wardrobe", [0.2, 0.0, 7.0], [1.2, 2.2, 9.8]),
        part("sofa", [3.0, 0.0, 8.4], [7.0, 0.9, 9.6]),
        part("shelf", [9.2, 0.0, 5.0], [9.8, 2.0, 8.0]),
    ]
}

/// [`furnished_room`] on a floor and under a ceiling, its walls 3 m
/// tall: 10.2 wide, too small to be taken as metres by its width.
fn roofed_room() -> Boxes {
    let mut boxes = furnished_room();
    boxes.push(part("floor", [-0.1, -0.2, -0.1], [10.1, 0.0, 10.1]));
    boxes.push(part("ceiling", [-0.1, 3.0, -0.1], [10.1, 3.2, 10.1]));
    boxes
}

#[test]
fn a_room_10_m_wide_under_its_ceiling_is_walked_at_a_persons_eye_height() {
    let dir = tempfile::tempdir().unwrap();
    let boxes = roofed_room();
    let why = walked_inside(&load_boxes(dir.path(), &boxes), box_of(&boxes).extent().length(), 6);
    assert!(why.contains("in metres for rooms 3.00 m high"), "{why}");
}

#[test]
fn the_room_in_centimetres_as_gltf_is_read_in_metres_as_its_format_says() {
    let dir = tempfile::tempdir().unwrap();
    let boxes: Boxes = roofed_room()
        .into_iter()
        .map(|(name, min, max)| (name, min * 100.0, max * 100.0))
        .collect();
    let (generated, _) = default_of(&load_glb(dir.path(), &boxes), 120);
    // A hall 1 km wide and 300 m high, walked at a person's eye, as a
    // sky box 300 m high over a town must be.
    assert!(
        generated.why.contains("at eye height 1.700 (cells"),
        "{}",
        generated.why
    );
}

#[test]
fn the_room_in_centimetres_and_millimetres_is_walked_at_a_persons_eye_height_in_them() {
    for (per_metre, unit) in [(100.0, "centimetres"), (1000.0, "millimetres")] {
        let dir = tempfile::tempdir().unwrap();
        let boxes: Boxes = roofed_room()
            .into_iter()
            .map(|(name, min, max)| (name, min * per_metre, max * per_metre))
            .collect();
        let scene = load_boxes(dir.path(), &boxes);
        let (generated, path) = default_of(&scene, 120);
        let why = &generated.why;
        assert!(why.contains(&format!("in {unit} for rooms 3.00 m high")), "{why}");
        assert_walked_inside(&scene, &generated, box_of(&boxes).extent().length(), 1.7 * per_metre, 6);
        assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
    }
}

/// `boxes` as an OBJ file whose boxes of one name in a row are one object.
fn grouped_obj(boxes: &[(String, DVec3, DVec3)]) -> String {
    let mut last = None;
    boxes_obj(boxes)
        .lines()
        .filter(|line| match line.strip_prefix("o ") {
            Some(name) => last.replace(name) != Some(name),
            None => true,
        })
        .map(|line| format!("{line}\n"))
        .collect()
}

/// The shell of a room `w` × `d` and `h` high in metres, its walls and
/// slabs 0.2 thick: floor, ceiling, and walls with a door `door` wide
/// under a lintel at `lintel`, each piece an object, or all one object
/// named "shell".
fn room_shell(w: f64, d: f64, h: f64, [door, lintel]: [f64; 2], one_object: bool) -> Boxes {
    let t = 0.2;
    let pieces = [
        ("floor", [-t, -t, -t], [w + t, 0.0, d + t]),
        ("ceiling", [-t, h, -t], [w + t, h + t, d + t]),
        ("wall_west", [-t, 0.0, -t], [0.0, h, d + t]),
        ("wall_east", [w, 0.0, -t], [w + t, h, d + t]),
        ("wall_north", [0.0, 0.0, d], [w, h, d + t]),
        ("wall_south_a", [0.0, 0.0, -t], [(w - door) / 2.0, h, 0.0]),
        ("wall_south_b", [(w + door) / 2.0, 0.0, -t], [w, h, 0.0]),
        ("lintel", [(w - door) / 2.0, lintel, -t], [(w + door) / 2.0, h, 0.0]),
    ];
    pieces
        .into_iter()
        .map(|(name, min, max)| part(if one_object { "shell" } else { name }, min, max))
        .collect()
}

/// A chair of legs, a seat 0.45–0.5 m up and a back, its corner at `x`,
/// `z`, one object named `name`.
fn chair(name: &str, x: f64, z: f64) -> Boxes {
    let legs = [(0.0, 0.0), (0.4, 0.0), (0.0, 0.4), (0.4, 0.4)];
    let mut boxes: Boxes = legs
        .iter()
        .map(|&(a, b)| part(name, [x + a, 0.0, z + b], [x + a + 0.05, 0.45, z + b + 0.05]))
        .collect();
    boxes.push(part(name, [x, 0.45, z], [x + 0.45, 0.5, z + 0.45]));
    boxes.push(part(name, [x, 0.5, z + 0.4], [x + 0.45, 0.9, z + 0.45]));
    boxes
}

/// A room 8 × 6 m and 3 m high whose shell is one object, with twelve
/// chairs gathered in its middle, each an object: the shell is huge and
/// nearly empty beside them.
fn room_round_its_chairs() -> Boxes {
    let mut boxes = room_shell(8.0, 6.0, 3.0, [1.0, 2.1], true);
    for k in 0..12 {
        let (x, z) = (2.8 + 0.8 * f64::from(k % 4), 2.0 + 0.8 * f64::from(k / 4));
        boxes.extend(chair(&format!("chair_{k}"), x, z));
    }
    boxes
}

#[test]
fn a_room_whose_shell_is_one_object_round_its_gathered_chairs_is_walked_inside_it() {
    let dir = tempfile::tempdir().unwrap();
    let boxes = room_round_its_chairs();
    let scene = load_obj(dir.path(), grouped_obj(&boxes));
    let (generated, path) = default_of(&scene, 120);
    let why = &generated.why;
    assert!(
        why.contains("'shell' hides") && why.contains("which stand on it"),
        "{why}"
    );
    assert!(why.contains("in metres for rooms 3.00 m high"), "{why}");
    assert_walked_inside(&scene, &generated, box_of(&boxes).extent().length(), 1.7, 6);
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}

#[test]
fn a_hall_in_metres_is_walked_on_its_floor_not_over_its_chairs() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = room_shell(20.0, 15.0, 10.0, [2.0, 3.0], false);
    for k in 0..12 {
        let (i, j) = (f64::from(k % 4), f64::from(k / 4));
        boxes.extend(chair(&format!("chair_{k}"), 0.6 + i * 6.1, 0.6 + j * 6.7));
    }
    let scene = load_obj(dir.path(), grouped_obj(&boxes));
    let (generated, _) = default_of(&scene, 120);
    let why = &generated.why;
    assert!(why.contains("through the interior"), "{why}");
    for (k, key) in generated.file.keyframes.iter().enumerate() {
        let y = key.position[1];
        assert!(
            (y - 1.7).abs() < 1e-6,
            "key {k} at {:?}: the eye {y} over the floor ({why})",
            key.position
        );
    }
}

#[test]
fn a_town_in_a_sky_box_is_framed_without_the_sky_even_where_it_stands_on_its_floor() {
    for on_its_floor in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let mut boxes = town(true);
        // A closed box 20 times the town's width round it, one object:
        // centred on the town, or with its floor as the town's ground.
        let (c, half) = (box_of(&boxes).center(), 10.0 * box_of(&boxes).extent().x);
        let (mut lo, mut hi) = (c - DVec3::splat(half), c + DVec3::splat(half));
        if on_its_floor {
            boxes.retain(|(name, _, _)| name != "ground");
            (lo.y, hi.y) = (-1.0, 2.0 * half);
        }
        for (a, b) in [
            ([lo.x, lo.y, lo.z], [hi.x, lo.y + 1.0, hi.z]),
            ([lo.x, hi.y - 1.0, lo.z], [hi.x, hi.y, hi.z]),
            ([lo.x, lo.y, lo.z], [lo.x + 1.0, hi.y, hi.z]),
            ([hi.x - 1.0, lo.y, lo.z], [hi.x, hi.y, hi.z]),
            ([lo.x, lo.y, lo.z], [hi.x, hi.y, lo.z + 1.0]),
            ([lo.x, lo.y, hi.z - 1.0], [hi.x, hi.y, hi.z]),
        ] {
            boxes.push(part("sky", a, b));
        }
        let (generated, _) = default_of(&load_obj(dir.path(), grouped_obj(&boxes)), 60);
        let why = &generated.why;
        assert!(why.contains("'sky' hides") && why.contains("without 'sky'"), "{why}");
        assert!(why.contains("at eye height 1.700 (cells"), "{why}");
    }
}

/// Whether the ray `origin + t·direction`, `t >= 0`, meets `b` (slab test).
fn meets(b: &Aabb, origin: DVec3, direction: DVec3) -> bool {
    let (mut near, mut far) = (0.0f64, f64::INFINITY);
    for axis in 0..3 {
        let (o, d, lo, hi) = (origin[axis], direction[axis], b.min[axis], b.max[axis]);
        if d == 0.0 {
            if o < lo || o > hi {
                return false;
            }
            continue;
        }
        let (a, c) = ((lo - o) / d, (hi - o) / d);
        near = near.max(a.min(c));
        far = far.min(a.max(c));
    }
    near <= far
}

/// The share of the frame's height from the highest to the lowest row of
/// pixels whose rays meet `b`, over a grid of 64 × 48 pixel rays.
fn height_share(camera: &occlu::camera::Camera, b: &Aabb) -> f64 {
    let (columns, rows) = (64, 48);
    let t = (camera.fov_y / 2.0).tan();
    let (right, up, forward) = (camera.rotation * DVec3::X, camera.rotation * DVec3::Y, camera.forward());
    let seen: Vec<usize> = (0..rows)
        .filter(|&row| {
            let y = 1.0 - (row as f64 + 0.5) / rows as f64 * 2.0;
            (0..columns).any(|column| {
                let x = (column as f64 + 0.5) / columns as f64 * 2.0 - 1.0;
                let direction = forward + right * (x * t * camera.aspect) + up * (y * t);
                meets(b, camera.eye, direction)
            })
        })
        .collect();
    match (seen.first(), seen.last()) {
        (Some(top), Some(bottom)) => (bottom - top + 1) as f64 / rows as f64,
        _ => 0.0,
    }
}

/// The distance from `p` to `b` (0 inside).
fn distance_to_box(p: DVec3, b: &Aabb) -> f64 {
    (b.min - p).max(p - b.max).max(DVec3::ZERO).length()
}

#[test]
fn a_furnished_room_on_a_huge_plane_is_framed_not_the_plane() {
    let dir = tempfile::tempdir().unwrap();
    let mut boxes = furnished_room();
    let room = box_of(&boxes);
    boxes.push(plane_under(&boxes, 22.0, 0.0));
    let scene = load_boxes(dir.path(), &boxes);
    let (generated, path) = default_of(&scene, 60);
    let why = &generated.why;
    assert!(why.contains("without 'ground'"), "{why}");
    let size = room.extent().length();
    for f in 0..path.frames {
        let camera = path.camera(f, 4.0 / 3.0);
        let away = distance_to_box(camera.eye, &room);
        assert!(
            away <= 3.0 * size,
            "frame {f}: {away:.1} from the room, {size:.1} across ({why})"
        );
        let share = height_share(&camera, &room);
        assert!(
            share >= 1.0 / 3.0,
            "frame {f}: the room fills {share:.2} of the height ({why})"
        );
    }
    assert_eq!(frames_too_near(&path, &world_triangles(&scene)), Vec::<u32>::new());
}

/// The kind of default path each model in ../shared/models had before
/// interiors and focus bounds, by file name.
const SHARED_KINDS: &[(&str, PathKind)] = &[
    ("bunny.obj", PathKind::Orbit),
    ("den-haag.obj", PathKind::Walk),
    ("teapot.obj", PathKind::Orbit),
    ("two-cylinder-engine.glb", PathKind::Orbit),
    ("building-garage.glb", PathKind::Orbit),
    ("building-small-a.glb", PathKind::Orbit),
    ("building-small-b.glb", PathKind::Orbit),
    ("building-small-c.glb", PathKind::Orbit),
    ("building-small-d.glb", PathKind::Orbit),
    ("grass-trees-tall.glb", PathKind::Orbit),
    ("grass-trees.glb", PathKind::Orbit),
    ("grass.glb", PathKind::Orbit),
    ("pavement-fountain.glb", PathKind::Walk),
    ("pavement.glb", PathKind::Orbit),
    ("road-corner.glb", PathKind::Walk),
    ("road-intersection.glb", PathKind::Walk),
    ("road-split.glb", PathKind::Walk),
    ("road-straight-lightposts.glb", PathKind::Walk),
    ("road-straight.glb", PathKind::Walk),
];

#[test]
fn every_shared_model_and_built_in_scene_keeps_its_kind_of_path() {
    for spec in ["city", "forest", "office"] {
        let mut scene = load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap();
        let generated = plan(None, &scene, Some(10)).unwrap();
        assert_eq!(generated.kind, PathKind::Walk, "{spec}: {}", generated.why);
        // Without the streets it was built with, as a file of it loads: a
        // place with open ground.
        scene.walk_hint = None;
        let generated = plan(None, &scene, Some(10)).unwrap();
        assert_eq!(generated.kind, PathKind::Walk, "{spec} as a file: {}", generated.why);
    }
    let dir = shared_models_dir();
    if !dir.exists() {
        cannot_run(&format!("no real models at {} (../shared/models)", dir.display()));
        return;
    }
    for (model, _) in shared_models(&dir) {
        let name = model.file_name().unwrap().to_string_lossy().into_owned();
        let Some(&(_, kind)) = SHARED_KINDS.iter().find(|(n, _)| *n == name) else {
            panic!("{name}: not in SHARED_KINDS; add the kind of path it gets today");
        };
        let scene = load(&SceneSpec::File(model.clone()), &LoadOptions::default()).unwrap();
        let generated = plan(None, &scene, Some(10)).unwrap();
        assert_eq!(generated.kind, kind, "{name}: {}", generated.why);
    }
}
