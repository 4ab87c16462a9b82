//! `office`: a seeded interior, an office floor of rooms on a large ground
//! plane, in the spirit of 001's architectural walkthroughs (§1: "most of
//! the scene is hidden behind walls" once inside).
//!
//! `rooms` × `rooms` rooms of 8 m × 8 m, walls 3 m high, each wall between
//! two rooms with a doorway in its middle (all doorways of a row in line,
//! so a view down a row reaches several rooms), and one doorway in from
//! outside at the first room. Each room holds a desk, a shelf of boxes and
//! a few balls. The floor stands on a ground plane five times as wide,
//! whose bounds, not the floor's, are the scene's: what a scene's size
//! decides (a view's reach in `auto`) meets rooms on large ground planes.
//! The walk enters through the outside doorway and goes from room to room
//! through the doorways of the first two rows: at a doorway the eye faces
//! a wall or looks through a door, and then into a room where the walls
//! hide most of the floor.
//!
//! Units are metres, +Y is up; the rooms lie in [0, side]² with side =
//! 8 m × `rooms`.

use glam::DVec3;

use super::build::{Params, add, read_params};
use super::city::EYE_HEIGHT;
use super::shapes::{cuboid, sphere};
use crate::rng::Rng;
use crate::scene::{GeometryError, SceneBuilder, TriangleSoup};

/// A room's side.
const ROOM: f64 = 8.0;
/// Walls' height and thickness.
const WALL_HEIGHT: f64 = 3.0;
const WALL: f64 = 0.2;
/// A doorway's width and height.
const DOOR_WIDTH: f64 = 1.2;
const DOOR_HEIGHT: f64 = 2.2;
/// The ground plane's side over the floor's.
const GROUND: f64 = 5.0;
/// Balls in a room, and the segments around each.
const BALLS: u32 = 3;
const BALL_SEGMENTS: u32 = 16;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OfficeParams {
    pub rooms: u32,
    pub seed: u64,
}

impl Default for OfficeParams {
    /// 10 × 10 rooms: 721 objects and 109 000 triangles, a walk through
    /// 20 of them.
    fn default() -> Self {
        OfficeParams { rooms: 10, seed: 1 }
    }
}

impl OfficeParams {
    pub(super) fn from_params(params: &Params) -> Result<Self, String> {
        let d = OfficeParams::default();
        let (mut rooms, mut seed) = (u64::from(d.rooms), d.seed);
        read_params(
            params,
            // Two rows at least: the walk goes back along the second.
            &mut [("rooms", &mut rooms, 2..=64), ("seed", &mut seed, 0..=u64::MAX)],
        )?;
        Ok(OfficeParams {
            rooms: rooms as u32,
            seed,
        })
    }

    /// The canonical spec, with every parameter spelled out.
    pub fn spec(&self) -> String {
        format!("office:rooms={},seed={}", self.rooms, self.seed)
    }

    /// Side of the square the rooms stand on.
    pub fn side(&self) -> f64 {
        f64::from(self.rooms) * ROOM
    }
}

pub fn generate(p: &OfficeParams, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    let (n, side) = (p.rooms, p.side());
    let mut ground = TriangleSoup::default();
    let reach = side * (GROUND - 1.0) / 2.0;
    cuboid(
        &mut ground,
        DVec3::new(-reach, -0.1, -reach),
        DVec3::new(side + reach, 0.0, side + reach),
    );
    add(builder, "ground", &ground)?;
    // At each line between rooms (and the floor's edges), a wall per room
    // along x (at z = line · ROOM) and one along z (at x = line · ROOM). A
    // wall between two rooms has a doorway, as has the first room's wall
    // to the outside at x = 0.
    for line in 0..=n {
        for room in 0..n {
            let (across, along) = (f64::from(line) * ROOM, f64::from(room) * ROOM);
            let between = (1..n).contains(&line);
            let along_x = wall(across, along, between, |v| DVec3::new(v.y, v.z, v.x));
            add(builder, &format!("wall_x{line}_{room}"), &along_x)?;
            let entrance = line == 0 && room == 0;
            let along_z = wall(across, along, between || entrance, |v| DVec3::new(v.x, v.z, v.y));
            add(builder, &format!("wall_z{line}_{room}"), &along_z)?;
        }
    }
    let mut rng = Rng::new(p.seed);
    for row in 0..n {
        for column in 0..n {
            let corner = DVec3::new(f64::from(column) * ROOM, 0.0, f64::from(row) * ROOM);
            furnish(builder, &format!("{row}_{column}"), corner, &mut rng)?;
        }
    }
    builder.set_walk_hint(walk(n));
    Ok(())
}

/// A wall across at `across`, along one room from `along`, with a doorway
/// in its middle where `door`, as one mesh: its boxes made in (across,
/// along, up) coordinates and placed by `to_scene` (which swaps axes
/// only, so a box stays a box).
fn wall(across: f64, along: f64, door: bool, to_scene: impl Fn(DVec3) -> DVec3) -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    let mut span = |a: f64, b: f64, low: f64, high: f64| {
        let corners = [
            DVec3::new(across - WALL / 2.0, a, low),
            DVec3::new(across + WALL / 2.0, b, high),
        ]
        .map(&to_scene);
        cuboid(&mut soup, corners[0].min(corners[1]), corners[0].max(corners[1]));
    };
    let middle = along + ROOM / 2.0;
    if door {
        span(along, middle - DOOR_WIDTH / 2.0, 0.0, WALL_HEIGHT);
        span(middle + DOOR_WIDTH / 2.0, along + ROOM, 0.0, WALL_HEIGHT);
        span(
            middle - DOOR_WIDTH / 2.0,
            middle + DOOR_WIDTH / 2.0,
            DOOR_HEIGHT,
            WALL_HEIGHT,
        );
    } else {
        span(along, along + ROOM, 0.0, WALL_HEIGHT);
    }
    soup
}

/// A room's furniture, its lowest corner at `corner`: a desk, a shelf of
/// boxes along the far wall, and balls at random above the floor, in the
/// corner the walk
/// does not cross (it runs through the room's centre along x, and along z
/// from the centre on in the rooms where it turns).
fn furnish(builder: &mut SceneBuilder, name: &str, corner: DVec3, rng: &mut Rng) -> Result<(), GeometryError> {
    let at = |x: f64, y: f64, z: f64| corner + DVec3::new(x, y, z);
    let mut desk = TriangleSoup::default();
    cuboid(&mut desk, at(1.0, 0.7, 1.0), at(3.0, 0.75, 2.0));
    for (x, z) in [(1.05, 1.05), (2.9, 1.05), (1.05, 1.9), (2.9, 1.9)] {
        cuboid(&mut desk, at(x, 0.0, z), at(x + 0.05, 0.7, z + 0.05));
    }
    add(builder, &format!("desk{name}"), &desk)?;
    let mut shelf = TriangleSoup::default();
    for level in 0..6 {
        let y = 0.3 * f64::from(level);
        for slot in 0..4 {
            let z = 1.0 + 0.5 * f64::from(slot);
            cuboid(&mut shelf, at(ROOM - 1.2, y, z), at(ROOM - 0.6, y + 0.25, z + 0.4));
        }
    }
    add(builder, &format!("shelf{name}"), &shelf)?;
    for k in 0..BALLS {
        let mut ball = TriangleSoup::default();
        let centre = at(rng.range(5.5, 7.0), rng.range(0.7, 2.0), rng.range(5.5, 7.0));
        sphere(&mut ball, centre, rng.range(0.3, 0.7), BALL_SEGMENTS);
        add(builder, &format!("ball{name}_{k}"), &ball)?;
    }
    Ok(())
}

/// In through the outside doorway, then from room centre to room centre
/// along the first row and back along the second, at eye height.
fn walk(n: u32) -> Vec<DVec3> {
    let centre = |row: u32, column: u32| {
        DVec3::new(
            (f64::from(column) + 0.5) * ROOM,
            EYE_HEIGHT,
            (f64::from(row) + 0.5) * ROOM,
        )
    };
    let outside = DVec3::new(-ROOM, EYE_HEIGHT, ROOM / 2.0);
    let first = (0..n).map(|column| centre(0, column));
    let second = (0..n).rev().map(|column| centre(1, column));
    std::iter::once(outside).chain(first).chain(second).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raycast::RayCaster;
    use crate::scene::{LoadOptions, SceneSpec, load};

    fn office(spec: &str) -> crate::scene::Scene {
        load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap()
    }

    #[test]
    fn the_walk_passes_through_doorways_and_the_walls_hide_the_rooms_beside() {
        let scene = office("office:rooms=4,seed=3");
        let caster = RayCaster::new(&scene);
        let walk = scene.walk_hint.as_ref().unwrap();
        assert_eq!(walk.len(), 1 + 2 * 4);
        // Every step of the walk is clear: through the doorways, past the
        // furniture.
        for step in walk.windows(2) {
            let (from, to) = (step[0], step[1]);
            let hit = caster.first_hit(from, (to - from).normalize(), from.distance(to));
            let met = hit.map(|h| &scene.objects[h.object as usize].name);
            assert_eq!(met, None, "{from} to {to}");
        }
        // From the first room's centre, the next row's first room lies
        // behind the wall between them, beside its doorway.
        let from = walk[1];
        let to = DVec3::new(0.5, EYE_HEIGHT, 1.5 * ROOM + 3.0);
        let hit = caster.first_hit(from, (to - from).normalize(), from.distance(to));
        let met = hit.map(|h| scene.objects[h.object as usize].name.as_str());
        assert_eq!(met, Some("wall_x1_0"));
    }

    #[test]
    fn its_bounds_are_the_large_ground_planes_and_a_spec_gives_the_same_office() {
        let p = OfficeParams { rooms: 3, seed: 2 };
        let scene = office(&p.spec());
        // The ground, 2 · (3 + 1) walls each way, and 5 pieces of
        // furniture in each of 9 rooms.
        assert_eq!(scene.objects.len(), 1 + 2 * 4 * 3 + 9 * (2 + BALLS as usize));
        let bounds = scene
            .objects
            .iter()
            .fold(scene.objects[0].bounds, |b, o| b.union(o.bounds));
        assert!((bounds.max.x - bounds.min.x - GROUND * p.side()).abs() < 1e-9);
        assert!((bounds.max.y - WALL_HEIGHT).abs() < 1e-9);
        // Nothing but the ground reaches below the floor.
        assert!(scene.objects[1..].iter().all(|o| o.bounds.min.y >= 0.0));
        let again = office("office:rooms=3,seed=2");
        assert_eq!(scene.vertices, again.vertices);
        assert_ne!(scene.vertices, office("office:rooms=3,seed=3").vertices);
        let msg = |spec: &str| {
            load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default())
                .unwrap_err()
                .to_string()
        };
        assert!(msg("office:rooms=1").contains("must be in"));
        assert!(msg("office:blocks=2").contains("unknown parameter 'blocks'"));
    }
}
