//! The default path where it used to miss the model: a furnished room on a
//! huge plane is framed, not the plane. Checked by the test's own
//! computations: the room's box from the list the test built it from, the
//! camera's pixel rays through that box, distances to every triangle.

mod common;

use common::{boxes_obj, frames_too_near, world_triangles, write};
use glam::DVec3;
use occlu::bounds::Aabb;
use occlu::camera::generate::{Generated, plan};
use occlu::camera::path::CameraPath;
use occlu::scene::{LoadOptions, Scene, SceneSpec, load};

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
    let model = write(dir, "model.obj", boxes_obj(boxes));
    load(&SceneSpec::File(model), &LoadOptions::default()).unwrap()
}

/// The default path of `scene`, in `frames` frames.
fn default_of(scene: &Scene, frames: u32) -> (Generated, CameraPath) {
    let generated = plan(None, scene, Some(frames)).unwrap();
    let path = CameraPath::from_file(&generated.file, "default").unwrap();
    (generated, path)
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
