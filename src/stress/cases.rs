//! The built-in matrix of hard cases: scenes and cameras where occlusion
//! cullers are known to fail (the near plane, an eye inside a box, huge
//! coordinates, degenerate boxes, extreme fields of view, vertical views,
//! no temporal coherence, parts flush with distant walls, triangles seen
//! edge-on, target sizes that are not powers of two).
//!
//! Most cases are a small seeded town (a ground slab, a 5×5 grid of closed
//! buildings, crates in the streets) plus the objects and cameras their
//! difficulty needs; the last two, found on real models, build their own. Units are metres, +Y up. Geometry is written in world
//! coordinates in f64 and goes through [`SceneBuilder`] like any loaded
//! model, so the translated cases also exercise the loaders' re-centring.

use glam::DVec3;

use super::case::{Baseline, DepthTolerance, StressCase};
use crate::camera::{Camera, look_rotation};
use crate::gpu::Resolution;
use crate::rng::Rng;
use crate::scene::builtin::shapes::cuboid;
use crate::scene::cameras::FOV_RANGE;
use crate::scene::{SceneBuilder, TriangleSoup};

/// Buildings per side of the town's grid.
const GRID: i32 = 5;
/// Distance between building centres; buildings are 24 m wide, so streets
/// are 12 m wide, centred on x or z = ±18, ±54.
const PITCH: f64 = 36.0;
const HALF_BUILDING: f64 = 12.0;
const EYE: f64 = 1.7;
const NEAR: f64 = 0.1;
const FOV: f64 = 60.0;
/// The town is the same in every case.
const SEED: u64 = 0x5EED;

/// One object's triangles, in world coordinates.
struct Shape {
    name: String,
    soup: TriangleSoup,
}

/// A view: eye and forward direction; the up vector is always +Y, so
/// vertical views take [`look_rotation`]'s fallback.
#[derive(Clone, Copy)]
struct Shot {
    eye: DVec3,
    forward: DVec3,
}

fn at(eye: DVec3, target: DVec3) -> Shot {
    Shot {
        eye,
        forward: target - eye,
    }
}

fn looking(eye: DVec3, forward: DVec3) -> Shot {
    Shot { eye, forward }
}

/// A uniform scale, then a translation, applied to shapes and shots alike.
#[derive(Clone, Copy)]
struct Placement {
    scale: f64,
    offset: DVec3,
}

const IN_PLACE: Placement = Placement {
    scale: 1.0,
    offset: DVec3::ZERO,
};

/// What a case is made of before it is placed.
struct Draft {
    shapes: Vec<Shape>,
    shots: Vec<Shot>,
    near: f64,
    fov_deg: f64,
    /// The target size it must run at, if any.
    resolution: Option<Resolution>,
}

impl Draft {
    fn new(shapes: Vec<Shape>, shots: Vec<Shot>) -> Draft {
        Draft {
            shapes,
            shots,
            near: NEAR,
            fov_deg: FOV,
            resolution: None,
        }
    }

    fn case(&self, name: &str, summary: &str) -> StressCase {
        self.placed(name, summary, None, IN_PLACE)
    }

    /// The case with every shape and shot moved by `placement`.
    fn placed(&self, name: &str, summary: &str, baseline: Option<Baseline>, placement: Placement) -> StressCase {
        let mut builder = SceneBuilder::new(format!("stress:{name}"), crate::scene::DEFAULT_CLUSTER_TRIANGLES);
        for shape in &self.shapes {
            let positions: Vec<DVec3> = shape
                .soup
                .positions
                .iter()
                .map(|&p| p * placement.scale + placement.offset)
                .collect();
            let group = builder
                .add_mesh(&shape.name, &positions, &shape.soup.indices)
                .expect("stress geometry is finite and indexed correctly");
            builder
                .add_object(&shape.name, &group, glam::DAffine3::IDENTITY)
                .expect("stress geometry is within range");
        }
        let scene = builder.finish().expect("every stress case has geometry");
        let cameras = self
            .shots
            .iter()
            .map(|s| Camera {
                eye: s.eye * placement.scale + placement.offset,
                rotation: look_rotation(s.forward, DVec3::Y),
                fov_y: self.fov_deg.to_radians(),
                near: self.near * placement.scale,
                // Set to the viewport's when the case runs.
                aspect: 1.0,
            })
            .collect();
        StressCase {
            name: name.to_string(),
            summary: summary.to_string(),
            scene,
            cameras,
            baseline,
            resolution: self.resolution,
        }
    }
}

fn cuboid_shape(name: String, min: DVec3, max: DVec3) -> Shape {
    let mut soup = TriangleSoup::default();
    cuboid(&mut soup, min, max);
    Shape { name, soup }
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The shared town: ground, buildings of seeded heights, crates along the
/// streets.
fn town() -> Vec<Shape> {
    let mut rng = Rng::new(SEED);
    let reach = PITCH * f64::from(GRID) / 2.0 + 10.0;
    let mut shapes = vec![cuboid_shape(
        "ground".into(),
        v(-reach, -1.0, -reach),
        v(reach, 0.0, reach),
    )];
    let span = GRID / 2;
    for i in -span..=span {
        for j in -span..=span {
            let c = v(f64::from(i) * PITCH, 0.0, f64::from(j) * PITCH);
            let height = rng.range(8.0, 40.0);
            shapes.push(cuboid_shape(
                format!("building {i},{j}"),
                c - v(HALF_BUILDING, 0.0, HALF_BUILDING),
                c + v(HALF_BUILDING, height, HALF_BUILDING),
            ));
        }
    }
    let streets = [-54.0, -18.0, 18.0, 54.0];
    for k in 0..80 {
        let along = rng.range(-reach + 5.0, reach - 5.0);
        let across = streets[rng.int(0, 3) as usize] + rng.range(-5.0, 5.0);
        let size = rng.range(0.3, 1.5);
        let base = if k % 2 == 0 {
            v(across, 0.0, along)
        } else {
            v(along, 0.0, across)
        };
        shapes.push(cuboid_shape(format!("crate {k}"), base, base + DVec3::splat(size)));
    }
    shapes
}

/// A walk along the street at x = 18, turning round at the end: the eye is
/// inside the root box (and the ground's) throughout.
fn street_walk() -> Vec<Shot> {
    let mut shots: Vec<Shot> = (0..8)
        .map(|k| {
            let z = -70.0 + 20.0 * f64::from(k);
            let yaw = 0.3 * (f64::from(k) * 0.9).sin();
            looking(v(18.0, EYE, z), v(yaw.sin(), -0.05, yaw.cos()))
        })
        .collect();
    shots.push(looking(v(18.0, EYE, 80.0), v(-1.0, 0.0, -0.2)));
    shots.push(looking(v(18.0, EYE, 80.0), v(0.0, 0.1, -1.0)));
    shots
}

/// Every case, in the order `occlu stress` runs them.
pub fn all() -> Vec<StressCase> {
    let walk = Draft::new(town(), street_walk());
    let mut cases = vec![walk.case(
        "inside-root",
        "street walk, the eye inside the root box (baseline of the offset and scale cases)",
    )];
    for (name, offset) in [("offset-1e3", 1e3), ("offset-1e5", 1e5), ("offset-1e7", 1e7)] {
        cases.push(walk.placed(
            name,
            "inside-root with every coordinate translated by this much",
            Some(Baseline {
                case: "inside-root".into(),
                tolerance: DepthTolerance::EXACT,
            }),
            Placement {
                scale: 1.0,
                offset: v(offset, offset, -offset),
            },
        ));
    }
    for (name, scale) in [("scale-1e-3", 1e-3), ("scale-1e4", 1e4)] {
        cases.push(walk.placed(
            name,
            "inside-root scaled by this factor (near plane too)",
            Some(Baseline {
                case: "inside-root".into(),
                tolerance: DepthTolerance::SCALED,
            }),
            Placement {
                scale,
                offset: DVec3::ZERO,
            },
        ));
    }
    for (name, fov) in [("fov-170", 170.0), ("fov-1", 1.0)] {
        let draft = Draft {
            fov_deg: fov,
            ..Draft::new(town(), street_walk())
        };
        cases.push(draft.case(name, "the street walk with this vertical field of view"));
    }
    cases.extend([
        inside_leaf(),
        near_crossing(),
        on_face(),
        near_far(),
        flat_boxes(),
        coplanar(),
        vertical(),
        narrowest_view(),
        occluder_crowd(),
        teleport(),
        distant_plaques(),
        edge_on(),
        slits(),
    ]);
    // A depth pyramid's base is a power of two at most the target's size:
    // at other sizes a base texel covers one to two target texels, and one
    // that samples some of them culls what the others show (bevy#14062).
    for (width, height) in [(801, 599), (1, 1), (1023, 1), (8191, 3)] {
        let draft = Draft {
            resolution: Some(Resolution { width, height }),
            ..Draft::new(town(), street_walk())
        };
        let name = format!("size-{width}x{height}");
        cases.push(draft.case(
            &name,
            "the street walk at this target size (odd, flat or one pixel: a depth pyramid's base rounds down to a power of two)",
        ));
    }
    cases
}

/// A wall with vertical slits 1.2 pixels wide at 801×599 and a small cube
/// behind each: a cube shows in the one or two pixel columns its slit
/// leaves, at every offset against the texels of a depth pyramid (whose
/// base texels there are 1.56 pixels wide), so a pyramid that skips a
/// column culls it. Slits are 50 pixels apart, so the few texels a cube is
/// tested against see no other slit.
fn slits() -> StressCase {
    let size = Resolution {
        width: 801,
        height: 599,
    };
    // The eye 10 m before the wall: a pixel there is this wide.
    let (distance, fov) = (10.0, FOV.to_radians());
    let pixel = 2.0 * distance * (fov / 2.0).tan() / f64::from(size.height);
    let slit = 1.2 * pixel;
    let (half, depth) = (7.0, 0.1);
    let mut shapes = Vec::new();
    let mut left = -half;
    // 12 slits, each 1/8 pixel further off the pixel grid than the last.
    for k in 0..12 {
        let at = -5.5 + f64::from(k) + f64::from(k % 8) * pixel / 8.0;
        shapes.push(cuboid_shape(format!("wall {k}"), v(left, 0.0, 0.0), v(at, 6.0, depth)));
        // On the line of sight through the slit's middle, 3 m behind it.
        let x = (at + slit / 2.0) * (distance + 3.0) / distance;
        shapes.push(cuboid_shape(
            format!("cube {k}"),
            v(x - 0.15, 2.85, -3.0),
            v(x + 0.15, 3.15, -2.7),
        ));
        left = at + slit;
    }
    shapes.push(cuboid_shape("wall end".into(), v(left, 0.0, 0.0), v(half, 6.0, depth)));
    let eye = v(0.0, 3.0, depth + distance);
    // Frames 0 and 1 draw every cube (nothing was drawn before frame 0 to
    // hide them, and what frame 0 saw is drawn first in frame 1): the cubes
    // are tested against the wall alone from frame 2 on.
    let shots = (0..6)
        .map(|k| looking(eye + v(0.3 * pixel * f64::from(k), 0.0, 0.0), DVec3::NEG_Z))
        .collect();
    Draft {
        resolution: Some(size),
        ..Draft::new(shapes, shots)
    }
    .case(
        "slits",
        "cubes seen only through slits a pixel wide, at every offset against a pyramid's texels",
    )
}

/// A closed room with a doorway, one object whose box holds the eye; a
/// table inside, the town outside.
fn inside_leaf() -> StressCase {
    let (min, max, t) = (v(14.0, 0.0, -4.0), v(22.0, 4.0, 4.0), 0.2);
    let mut room = TriangleSoup::default();
    cuboid(&mut room, min, v(max.x, min.y + t, max.z)); // floor
    cuboid(&mut room, v(min.x, max.y - t, min.z), max); // ceiling
    cuboid(&mut room, min, v(min.x + t, max.y, max.z)); // -x wall
    cuboid(&mut room, v(max.x - t, min.y, min.z), max); // +x wall
    cuboid(&mut room, min, v(max.x, max.y, min.z + t)); // -z wall
    // The +z wall, around a doorway 2 m wide and 2.5 m high.
    cuboid(&mut room, v(min.x, min.y, max.z - t), v(17.0, max.y, max.z));
    cuboid(&mut room, v(19.0, min.y, max.z - t), v(max.x, max.y, max.z));
    cuboid(&mut room, v(17.0, 2.5, max.z - t), v(19.0, max.y, max.z));
    let mut shapes = town();
    shapes.push(Shape {
        name: "room".into(),
        soup: room,
    });
    shapes.push(cuboid_shape("table".into(), v(16.0, 0.2, -2.0), v(17.5, 1.0, -1.0)));
    let eye = v(18.0, EYE, 1.0);
    let shots = vec![
        looking(eye, DVec3::Z),
        looking(eye, v(0.3, -0.1, 1.0)),
        looking(eye, DVec3::NEG_Z),
        looking(eye, v(-1.0, -0.4, -1.0)),
        looking(eye, DVec3::Y),
        looking(v(18.0, EYE, 3.9), DVec3::Z),
    ];
    Draft::new(shapes, shots).case(
        "inside-leaf",
        "the eye inside a room object's box, looking out of its doorway and around",
    )
}

/// Boxes cut by the near plane: the eye closer to them than the near
/// distance. Two crates float far outside the town, so each is a leaf of its
/// own that does not hold the eye: their boxes must be judged visible
/// without a test (a query would rasterise only their clipped front faces).
fn near_crossing() -> StressCase {
    let mut shapes = town();
    shapes.push(cuboid_shape(
        "floating crate".into(),
        v(300.0, 50.0, 300.0),
        v(302.0, 52.0, 302.0),
    ));
    shapes.push(cuboid_shape(
        "far crate".into(),
        v(-302.0, 20.0, 300.0),
        v(-300.0, 22.0, 302.0),
    ));
    shapes.push(cuboid_shape(
        "near crate".into(),
        v(17.0, 0.0, 20.0),
        v(19.0, 2.0, 22.0),
    ));
    let shots = vec![
        // 0.05 from a crate's face, looking at it: the face lies before the
        // near plane, the rest of the crate beyond it.
        looking(v(301.0, 51.0, 299.95), DVec3::Z),
        // Exactly the near distance away.
        looking(v(301.0, 51.0, 299.9), DVec3::Z),
        // Into a corner, 0.02 from two faces.
        looking(v(-302.02, 21.0, 299.98), v(1.0, 0.1, 1.0)),
        // Over a crate's top edge, 0.02 above it.
        looking(v(-301.0, 22.02, 299.0), v(0.0, -0.3, 1.0)),
        // Street level: a crate 0.05 ahead, and a building wall (x = 24)
        // 0.03 to the side.
        looking(v(18.0, 1.0, 19.95), DVec3::Z),
        looking(v(23.97, EYE, 0.0), v(0.5, 0.0, 1.0)),
    ];
    Draft::new(shapes, shots).case(
        "near-crossing",
        "boxes crossing the near plane (the eye 0.02 to 0.1 from faces, near 0.1)",
    )
}

/// The eye exactly on faces, edges and corners of boxes.
fn on_face() -> StressCase {
    let mut shapes = town();
    shapes.push(cuboid_shape(
        "face crate".into(),
        v(17.0, 0.0, 40.0),
        v(19.0, 2.0, 42.0),
    ));
    let shots = vec![
        looking(v(18.0, 1.0, 42.0), DVec3::Z),
        looking(v(18.0, 1.0, 42.0), DVec3::NEG_Z),
        looking(v(18.0, 1.0, 42.0), DVec3::X),
        looking(v(18.0, 2.0, 41.0), v(0.0, 0.0, 1.0)),
        looking(v(19.0, 2.0, 42.0), v(1.0, -0.5, 1.0)),
        looking(v(17.0, 0.0, 40.0), v(-1.0, 0.3, -1.0)),
        // On a building's face (x = 24), looking into the street, into the
        // building and along the face.
        looking(v(24.0, EYE, 0.0), DVec3::NEG_X),
        looking(v(24.0, EYE, 0.0), DVec3::X),
        looking(v(24.0, EYE, 0.0), DVec3::Z),
    ];
    Draft::new(shapes, shots).case("on-face", "the eye exactly on box faces, edges and corners")
}

/// Near plane 1e-4 with millimetre crates centimetres away, and mountains
/// 1e5 away behind the town.
fn near_far() -> StressCase {
    let mut shapes = town();
    let mut rng = Rng::new(SEED ^ 1);
    for k in 0..24 {
        let angle = f64::from(k) / 24.0 * std::f64::consts::TAU;
        let centre = v(angle.sin(), 0.0, angle.cos()) * 1e5;
        let half = rng.range(2e3, 8e3);
        shapes.push(cuboid_shape(
            format!("mountain {k}"),
            centre - v(half, 0.0, half),
            centre + v(half, rng.range(1e3, 2e4), half),
        ));
    }
    for k in 0..3 {
        let base = v(18.0, EYE - 0.0005, 30.01 + 0.005 * f64::from(k));
        shapes.push(cuboid_shape(format!("speck {k}"), base, base + DVec3::splat(0.001)));
    }
    let shots = vec![
        looking(v(18.0, EYE, 30.0), DVec3::Z),
        looking(v(18.0, EYE, 30.0), v(0.0, 0.05, 1.0)),
        looking(v(18.0, 45.0, 30.0), v(0.2, -0.02, 1.0)),
        looking(v(18.0, 45.0, 30.0), v(1.0, -0.02, 0.0)),
        looking(v(18.0, 45.0, 30.0), v(-0.7, 0.0, -1.0)),
        looking(v(18.0, EYE, 29.995), v(0.02, 0.0, 1.0)),
    ];
    Draft {
        near: 1e-4,
        ..Draft::new(shapes, shots)
    }
    .case(
        "near-far",
        "near plane 1e-4, millimetre objects at 1 cm, mountains at 1e5",
    )
}

/// Boxes of zero thickness: horizontal and vertical planes, and slivers
/// (triangles 10 m long and 1 mm wide, whose box is flat and nearly a line),
/// some behind a wall, some beside it, one lying on the ground.
fn flat_boxes() -> StressCase {
    let mut shapes = town();
    shapes.push(cuboid_shape(
        "screen wall".into(),
        v(14.0, 0.0, 50.0),
        v(20.0, 6.0, 50.5),
    ));
    shapes.push(cuboid_shape(
        "floating sheet".into(),
        v(15.0, 3.0, 55.0),
        v(21.0, 3.0, 60.0),
    ));
    shapes.push(cuboid_shape(
        "ground sheet".into(),
        v(13.0, 0.0, 44.0),
        v(16.0, 0.0, 47.0),
    ));
    shapes.push(cuboid_shape(
        "hidden panel".into(),
        v(15.0, 1.0, 52.0),
        v(19.0, 4.0, 52.0),
    ));
    shapes.push(cuboid_shape(
        "edge panel".into(),
        v(19.5, 1.0, 53.0),
        v(21.5, 4.0, 53.0),
    ));
    shapes.push(cuboid_shape(
        "side panel".into(),
        v(22.0, 0.5, 51.0),
        v(22.0, 3.0, 56.0),
    ));
    for k in 0..4 {
        let y = 1.0 + 1.8 * f64::from(k);
        let z = 51.0 + f64::from(k);
        let mut soup = TriangleSoup::default();
        soup.append(&[v(12.5, y, z), v(22.5, y, z), v(17.5, y + 0.001, z)], [0, 1, 2]);
        shapes.push(Shape {
            name: format!("sliver {k}"),
            soup,
        });
    }
    let shots = vec![
        at(v(17.0, EYE, 40.0), v(17.0, 2.0, 55.0)),
        at(v(12.0, EYE, 40.0), v(18.0, 2.0, 55.0)),
        at(v(22.5, 2.0, 42.0), v(17.0, 2.0, 55.0)),
        at(v(17.0, 3.0, 40.0), v(17.0, 3.0, 60.0)),
        at(v(17.0, 10.0, 40.0), v(17.0, 0.0, 55.0)),
        at(v(26.0, 1.0, 53.0), v(12.0, 2.0, 53.0)),
    ];
    Draft::new(shapes, shots).case(
        "flat-boxes",
        "zero-thickness boxes (planes) and slivers 1 mm wide, hidden and half hidden",
    )
}

/// Coincident geometry: a duplicated building, a poster on a wall, crates
/// stacked face to face and standing on the ground.
fn coplanar() -> StressCase {
    let mut shapes = town();
    let twin = shapes
        .iter()
        .find(|s| s.name == "building 1,0")
        .map(|s| Shape {
            name: "building 1,0 twin".into(),
            soup: s.soup.clone(),
        })
        .expect("the town has building 1,0");
    shapes.push(twin);
    shapes.push(cuboid_shape("poster".into(), v(24.0, 1.0, -3.0), v(24.0, 4.0, 3.0)));
    shapes.push(cuboid_shape(
        "thin poster".into(),
        v(24.0, 5.0, -3.0),
        v(24.01, 6.0, 3.0),
    ));
    for k in 0..4 {
        let y = f64::from(k);
        shapes.push(cuboid_shape(
            format!("stack {k}"),
            v(20.0, y, 10.0),
            v(21.0, y + 1.0, 11.0),
        ));
    }
    // A crate exactly behind the poster's plane, inside the building.
    shapes.push(cuboid_shape(
        "behind poster".into(),
        v(24.0, 1.5, -1.0),
        v(25.0, 2.5, 1.0),
    ));
    let shots = vec![
        at(v(18.0, EYE, -10.0), v(24.0, 3.0, 0.0)),
        at(v(14.0, 3.0, 0.0), v(24.0, 3.0, 0.0)),
        at(v(18.0, 2.0, 6.0), v(20.5, 2.0, 10.5)),
        at(v(16.0, 20.0, -20.0), v(36.0, 10.0, 0.0)),
        at(v(20.5, 6.0, 10.5), v(20.5, 0.0, 10.5)),
    ];
    Draft::new(shapes, shots).case(
        "coplanar",
        "coincident surfaces: a duplicated building, posters on a wall, stacked crates",
    )
}

/// Looking straight down and straight up: the up vector is parallel to the
/// view direction.
fn vertical() -> StressCase {
    let shots = vec![
        looking(v(18.0, 150.0, 0.0), DVec3::NEG_Y),
        looking(v(0.0, 60.0, 0.0), DVec3::NEG_Y),
        looking(v(18.0, EYE, 0.0), DVec3::Y),
        looking(v(18.0, EYE, 18.0), DVec3::Y),
        looking(v(18.0, 0.5, 0.0), DVec3::NEG_Y),
        at(v(-18.0, 30.0, -18.0), v(-18.0, 0.0, -18.0)),
    ];
    Draft::new(town(), shots).case(
        "vertical",
        "straight down and straight up (up vector parallel to the view)",
    )
}

/// The narrowest field of view a path may take ([`FOV_RANGE`]), the eye
/// just before a wall 20 m long that hides a thinner one behind it (found
/// by a review: at 0.001° to 0.5°, llvmpipe and lavapipe leave columns of
/// such a wall at the view's edge undrawn, showing the wall behind).
fn narrowest_view() -> StressCase {
    let shapes = vec![
        cuboid_shape("wall".into(), v(-0.15, -0.15, 0.0), v(0.0, 6.15, 20.0)),
        cuboid_shape("behind".into(), v(0.0, 0.0, 9.925), v(2.263818, 3.0, 10.075)),
    ];
    let shots = [0.067, 1e-3, 1e-4]
        .map(|away| looking(v(-0.15 - away, 1.6, 10.0), DVec3::X))
        .to_vec();
    let draft = Draft {
        near: 5e-5,
        fov_deg: *FOV_RANGE.start(),
        ..Draft::new(shapes, shots)
    };
    draft.case(
        "fov-narrowest",
        "the narrowest field of view a path takes, the eye 0.1 mm to 67 mm before a wall hiding another",
    )
}

/// 400 small crates behind one large wall, a few of them peeking over it.
fn occluder_crowd() -> StressCase {
    let mut shapes = town();
    shapes.push(cuboid_shape(
        "great wall".into(),
        v(-30.0, 0.0, 60.0),
        v(30.0, 20.0, 61.0),
    ));
    let mut rng = Rng::new(SEED ^ 2);
    for k in 0..400 {
        let base = v(rng.range(-29.0, 29.0), rng.range(0.0, 20.3), rng.range(62.0, 75.0));
        shapes.push(cuboid_shape(format!("crowd {k}"), base, base + DVec3::splat(0.5)));
    }
    let shots = (0..6)
        .map(|k| {
            let x = -20.0 + 8.0 * f64::from(k);
            at(v(x, EYE + f64::from(k), 40.0), v(0.0, 12.0, 61.0))
        })
        .collect();
    Draft::new(shapes, shots).case(
        "occluder-crowd",
        "400 small objects behind one large occluder, some peeking over it",
    )
}

/// A new random place and direction every frame: nothing carries over from
/// one frame to the next (temporal coherence is useless).
fn teleport() -> StressCase {
    let mut rng = Rng::new(SEED ^ 3);
    let shots = (0..12)
        .map(|_| {
            let eye = v(rng.range(-95.0, 95.0), rng.range(0.3, 60.0), rng.range(-95.0, 95.0));
            let forward = v(rng.range(-1.0, 1.0), rng.range(-1.0, 0.5), rng.range(-1.0, 1.0));
            looking(eye, if forward.length() > 1e-3 { forward } else { DVec3::Z })
        })
        .collect();
    Draft::new(town(), shots).case("teleport", "a random place and direction every frame")
}

/// Buildings with plaques set flush into their walls (parts sharing a face
/// with their building, as CityJSON building parts do), seen from 1 km with
/// near 0.08. Depth there is 8e-5, where GL keeps only absolute precision:
/// a step of 2^-24 is 7e-4 of the depth, seven times the boxes' relative
/// growth. A plaque covers a few pixels and owns those where its rounding
/// beats the wall's; its box test must pass at one of them at least
/// (found on den-haag.obj: 36 objects missed over 60 frames on GL).
fn distant_plaques() -> StressCase {
    let mut rng = Rng::new(SEED ^ 4);
    let mut shapes = Vec::new();
    let (side, pitch) = (20.0, 30.0);
    for i in -4..4 {
        for j in -4..4 {
            let base = v(f64::from(i) * pitch, 0.0, f64::from(j) * pitch);
            let height = rng.range(10.0, 30.0);
            shapes.push(cuboid_shape(
                format!("building {i},{j}"),
                base,
                base + v(side, height, side),
            ));
            for k in 0..12 {
                let size = rng.range(1.0, 3.0);
                let low = base + v(rng.range(0.0, side - size), rng.range(0.0, height - size), 0.0);
                let low = v(low.x, low.y, base.z + rng.range(0.0, side - size));
                // Inside the building, one face on one of its four walls.
                let min = match rng.int(0, 3) {
                    0 => v(base.x, low.y, low.z),
                    1 => v(base.x + side - size, low.y, low.z),
                    2 => v(low.x, low.y, base.z),
                    _ => v(low.x, low.y, base.z + side - size),
                };
                shapes.push(cuboid_shape(
                    format!("plaque {i},{j},{k}"),
                    min,
                    min + DVec3::splat(size),
                ));
            }
        }
    }
    let shots = (0..8)
        .map(|k| {
            let angle = 0.4 * f64::from(k);
            at(v(1000.0 * angle.cos(), 300.0, 1000.0 * angle.sin()), v(0.0, 10.0, 0.0))
        })
        .collect();
    Draft {
        near: 0.08,
        ..Draft::new(shapes, shots)
    }
    .case(
        "distant-plaques",
        "parts flush with their buildings' walls, seen from 1 km with near 0.08",
    )
}

/// 2 000 single triangles whose planes hold the eye, between 105 and 750 m
/// away, behind a screen 95 m away that hides all of their boxes (600 m
/// wide and high: the boxes reach 2.5 times as far sideways as ahead). Each
/// projects to a line; rounded to f32 it becomes a sliver the rasteriser
/// may still sample, with its depth extrapolated anywhere, even NaN (found
/// on two-cylinder-engine.glb: a part in one pixel, 115 m in front of
/// where its triangle lies). The cameras only turn, so the triangles stay
/// edge-on.
fn edge_on() -> StressCase {
    let mut rng = Rng::new(SEED ^ 5);
    let mut shapes = vec![cuboid_shape(
        "screen".into(),
        v(-300.0, -300.0, -96.0),
        v(300.0, 300.0, -95.0),
    )];
    for k in 0..2000 {
        let mut ray = || v(rng.range(-0.35, 0.35), rng.range(-0.25, 0.25), -1.0) * rng.range(150.0, 250.0);
        let (a, b) = (ray(), ray());
        let c = a * rng.range(0.35, 1.5) + b * rng.range(0.35, 1.5);
        let mut soup = TriangleSoup::default();
        soup.append(&[a, b, c], [0, 1, 2]);
        shapes.push(Shape {
            name: format!("edge-on {k}"),
            soup,
        });
    }
    let shots = [v(0.0, 0.0, -1.0), v(0.1, 0.05, -1.0), v(-0.12, -0.04, -1.0)]
        .map(|forward| looking(DVec3::ZERO, forward))
        .to_vec();
    Draft::new(shapes, shots).case(
        "edge-on",
        "2000 triangles seen exactly edge-on behind a screen that hides their boxes",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_have_unique_names_and_baselines_that_exist() {
        let cases = all();
        for (i, c) in cases.iter().enumerate() {
            assert!(!c.cameras.is_empty(), "{}", c.name);
            assert!(cases[..i].iter().all(|d| d.name != c.name), "{} twice", c.name);
            if let Some(b) = &c.baseline {
                let base = cases[..i]
                    .iter()
                    .find(|d| d.name == b.case)
                    .expect("baseline runs first");
                assert_eq!(base.cameras.len(), c.cameras.len());
                assert_eq!(base.scene.objects.len(), c.scene.objects.len());
            }
        }
    }

    #[test]
    fn the_eye_is_where_each_case_says() {
        let cases = all();
        let case = |n: &str| cases.iter().find(|c| c.name == n).unwrap();
        let root = &case("inside-root").scene.bounds;
        assert!(case("inside-root").cameras.iter().all(|c| root.contains_point(c.eye)));
        let leaf = case("inside-leaf");
        let room = leaf.scene.objects.iter().find(|o| o.name == "room").unwrap();
        assert!(leaf.cameras.iter().all(|c| room.bounds.contains_point(c.eye)));
        let face = case("on-face");
        let crate_box = face
            .scene
            .objects
            .iter()
            .find(|o| o.name == "face crate")
            .unwrap()
            .bounds;
        let on_surface =
            |p: DVec3| crate_box.contains_point(p) && (p.cmpeq(crate_box.min).any() || p.cmpeq(crate_box.max).any());
        assert_eq!(face.cameras.iter().filter(|c| on_surface(c.eye)).count(), 6);
        let vertical = case("vertical");
        assert!(
            vertical
                .cameras
                .iter()
                .all(|c| c.forward().x.abs() < 1e-12 && c.forward().z.abs() < 1e-12)
        );
        // The offset cases moved the geometry, not just the cameras.
        let far = case("offset-1e7");
        assert!(far.scene.bounds.min.x > 9.9e6 && far.cameras[0].eye.x > 9.9e6);
    }
}
