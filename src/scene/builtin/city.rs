//! `city`: a seeded procedural city in the spirit of the city models of
//! papers 002 (§5.1.2: "three-hundred buildings. Each building contains some
//! interior furniture, which is occluded at all times") and 003.
//!
//! A grid of `blocks`×`blocks` blocks, each holding 2×2 buildings of 2–14
//! floors. Every building is a closed shell (walls, floor bands, pilasters,
//! roof units) around one furniture object per floor, which the street can
//! never see; cars stand in the lanes, and `movers` more drive round the
//! blocks. Most triangles are furniture, so
//! depth complexity is high: direct rendering pays for all of it, view-frustum
//! culling for what lies in the frustum, and an exact occlusion culler for
//! little more than the street walls.
//!
//! Units are metres, +Y is up; the city starts near the origin and grows
//! towards +X and +Z.

use glam::{DAffine3, DQuat, DVec3};

use super::build::{Params, add, mesh, place, read_params};
use super::shapes::{cuboid, cylinder};
use crate::rng::Rng;
use crate::scene::motion::Route;
use crate::scene::{GeometryError, MeshGroup, SceneBuilder, TriangleSoup};

/// Movers beyond this are surely a mistake.
const MAX_MOVERS: u64 = 100_000;
/// Props: enough objects to measure culling cost per object at a game
/// level's instance count and beyond.
const MAX_PROPS: u64 = 1_000_000;
/// Side of a lot; a block holds 2×2 lots.
const LOT: f64 = 32.0;
const BLOCK: f64 = 2.0 * LOT;
const STREET: f64 = 16.0;
/// Distance between the starts of neighbouring blocks.
const PITCH: f64 = BLOCK + STREET;
const FLOOR_HEIGHT: f64 = 3.5;
/// Camera height of the street walk.
pub const EYE_HEIGHT: f64 = 1.7;
/// Moving cars keep this far from the centre line of a street: clear of the
/// walk's camera on the centre line and of the cars parked at ±4 m.
const DRIVING_LANE: f64 = 1.5;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CityParams {
    /// Blocks per side.
    pub blocks: u32,
    pub seed: u64,
    /// Cars driving round the blocks (001 §4's moving objects).
    pub movers: u32,
    /// Small street furniture (bollards, bins, lamp posts) on the
    /// pavements round the blocks: many objects of a few triangles each.
    pub props: u32,
}

impl Default for CityParams {
    /// 8×8 blocks: about 1.5 M triangles, a few hundred milliseconds of
    /// direct rendering per frame on llvmpipe.
    fn default() -> Self {
        CityParams {
            blocks: 8,
            seed: 1,
            movers: 0,
            props: 0,
        }
    }
}

impl CityParams {
    pub(super) fn from_params(params: &Params) -> Result<Self, String> {
        let d = CityParams::default();
        let (mut blocks, mut seed) = (u64::from(d.blocks), d.seed);
        let (mut movers, mut props) = (u64::from(d.movers), u64::from(d.props));
        read_params(
            params,
            &mut [
                ("blocks", &mut blocks, 1..=64),
                ("seed", &mut seed, 0..=u64::MAX),
                ("movers", &mut movers, 0..=MAX_MOVERS),
                ("props", &mut props, 0..=MAX_PROPS),
            ],
        )?;
        Ok(CityParams {
            blocks: blocks as u32,
            seed,
            movers: movers as u32,
            props: props as u32,
        })
    }

    /// The canonical spec, with every parameter spelled out (movers and
    /// props only when there are some, so specs without them read as
    /// before).
    pub fn spec(&self) -> String {
        let some = |key: &str, n: u32| if n > 0 { format!(",{key}={n}") } else { String::new() };
        format!(
            "city:blocks={},seed={}{}{}",
            self.blocks,
            self.seed,
            some("movers", self.movers),
            some("props", self.props)
        )
    }
}

/// Centre line of street `k` (0..=blocks), on either axis.
fn street(k: u32) -> f64 {
    f64::from(k) * PITCH - STREET / 2.0
}

pub fn generate(p: &CityParams, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    let mut rng = Rng::new(p.seed);
    let n = p.blocks;
    ground(n, builder)?;
    for bi in 0..n {
        for bj in 0..n {
            for lot in 0..4 {
                let origin = DVec3::new(
                    f64::from(bi) * PITCH + f64::from(lot % 2) * LOT,
                    0.0,
                    f64::from(bj) * PITCH + f64::from(lot / 2) * LOT,
                );
                building(&format!("b{bi}_{bj}_{lot}"), origin, &mut rng, builder)?;
            }
        }
    }
    let models = car_models(builder)?;
    parked_cars(n, &models, &mut rng, builder);
    // Their own generator: adding movers leaves the static city as it was.
    moving_cars(n, p.movers, &models, &mut Rng::new(p.seed ^ 0x6d6f_7665), builder);
    props(n, p.props, &mut Rng::new(p.seed ^ 0x7072_6f70), builder)?;
    let (m, mx) = (n / 2, (n / 2).max(1));
    let at = |x: f64, z: f64| DVec3::new(x, EYE_HEIGHT, z);
    builder.set_walk_hint(vec![
        at(street(0), street(m)),
        at(street(mx), street(m)),
        at(street(mx), street(n)),
    ]);
    Ok(())
}

/// Asphalt tiles (one per block and its streets) and raised sidewalks.
fn ground(n: u32, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    for i in 0..=n {
        for j in 0..=n {
            let lo = |k: u32| f64::from(k) * PITCH - STREET;
            let hi = |k: u32| {
                if k == n {
                    f64::from(k) * PITCH
                } else {
                    f64::from(k) * PITCH + BLOCK
                }
            };
            let mut soup = TriangleSoup::default();
            cuboid(&mut soup, DVec3::new(lo(i), -0.5, lo(j)), DVec3::new(hi(i), 0.0, hi(j)));
            if i < n && j < n {
                let o = DVec3::new(f64::from(i) * PITCH, 0.0, f64::from(j) * PITCH);
                cuboid(&mut soup, o, o + DVec3::new(BLOCK, 0.15, BLOCK));
            }
            add(builder, &format!("ground{i}_{j}"), &soup)?;
        }
    }
    Ok(())
}

/// A closed shell and one furniture object per floor.
fn building(name: &str, lot: DVec3, rng: &mut Rng, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    let min = lot + DVec3::new(rng.range(2.0, 4.0), 0.0, rng.range(2.0, 4.0));
    let max = lot + DVec3::new(LOT - rng.range(2.0, 4.0), 0.0, LOT - rng.range(2.0, 4.0));
    let floors = rng.int(2, 14);
    let height = f64::from(floors) * FLOOR_HEIGHT + 0.5;

    let mut shell = TriangleSoup::default();
    cuboid(&mut shell, min, DVec3::new(max.x, height, max.z));
    for f in 1..=floors {
        // A band around the building at every floor line.
        let y = f64::from(f) * FLOOR_HEIGHT;
        let out = DVec3::new(0.25, 0.0, 0.25);
        cuboid(
            &mut shell,
            DVec3::new(min.x, y - 0.15, min.z) - out,
            DVec3::new(max.x, y + 0.1, max.z) + out,
        );
    }
    pilasters(&mut shell, min, max, height);
    for _ in 0..rng.int(2, 5) {
        let c = DVec3::new(
            rng.range(min.x + 2.0, max.x - 4.0),
            height,
            rng.range(min.z + 2.0, max.z - 4.0),
        );
        cuboid(
            &mut shell,
            c,
            c + DVec3::new(rng.range(1.0, 2.5), rng.range(0.8, 2.0), rng.range(1.0, 2.5)),
        );
    }
    add(builder, &format!("{name}/shell"), &shell)?;

    for f in 0..floors {
        let y = f64::from(f) * FLOOR_HEIGHT;
        let mut room = TriangleSoup::default();
        cuboid(
            &mut room,
            DVec3::new(min.x + 0.3, y, min.z + 0.3),
            DVec3::new(max.x - 0.3, y + 0.2, max.z - 0.3),
        );
        for _ in 0..rng.int(1, 4) {
            let at = DVec3::new(
                rng.range(min.x + 2.0, max.x - 4.0),
                y + 0.2,
                rng.range(min.z + 2.0, max.z - 4.0),
            );
            workplace(&mut room, at, rng);
        }
        add(builder, &format!("{name}/floor{f}"), &room)?;
    }
    Ok(())
}

/// Vertical pilasters every ~4 m along each facade.
fn pilasters(shell: &mut TriangleSoup, min: DVec3, max: DVec3, height: f64) {
    let (w, d) = (0.4, 0.3);
    let count = |len: f64| ((len / 4.0) as u32).max(1);
    let step_x = (max.x - min.x) / f64::from(count(max.x - min.x));
    for k in 0..=count(max.x - min.x) {
        let x = min.x + step_x * f64::from(k) - w / 2.0;
        cuboid(shell, DVec3::new(x, 0.0, min.z - d), DVec3::new(x + w, height, min.z));
        cuboid(shell, DVec3::new(x, 0.0, max.z), DVec3::new(x + w, height, max.z + d));
    }
    let step_z = (max.z - min.z) / f64::from(count(max.z - min.z));
    for k in 0..=count(max.z - min.z) {
        let z = min.z + step_z * f64::from(k) - w / 2.0;
        cuboid(shell, DVec3::new(min.x - d, 0.0, z), DVec3::new(min.x, height, z + w));
        cuboid(shell, DVec3::new(max.x, 0.0, z), DVec3::new(max.x + d, height, z + w));
    }
}

/// A desk with a lamp and two chairs, `at` its floor-level corner.
fn workplace(room: &mut TriangleSoup, at: DVec3, rng: &mut Rng) {
    let (w, d, h) = (rng.range(1.4, 2.0), 0.8, 0.75);
    table(room, at, w, d, h);
    cylinder(room, at + DVec3::new(0.2, h, 0.2), DVec3::Y, 0.08, 0.5, 12);
    for side in [0.3, w - 0.8] {
        let seat = at + DVec3::new(side, 0.0, d + 0.2);
        table(room, seat, 0.5, 0.5, 0.45);
        cuboid(
            room,
            seat + DVec3::new(0.0, 0.45, 0.45),
            seat + DVec3::new(0.5, 0.95, 0.5),
        );
    }
}

/// A top on four legs: 5 boxes.
fn table(room: &mut TriangleSoup, at: DVec3, w: f64, d: f64, h: f64) {
    let leg = 0.06;
    cuboid(room, at + DVec3::new(0.0, h - 0.04, 0.0), at + DVec3::new(w, h, d));
    for (x, z) in [(0.0, 0.0), (w - leg, 0.0), (0.0, d - leg), (w - leg, d - leg)] {
        cuboid(
            room,
            at + DVec3::new(x, 0.0, z),
            at + DVec3::new(x + leg, h - 0.04, z + leg),
        );
    }
}

/// Three car models.
fn car_models(builder: &mut SceneBuilder) -> Result<Vec<MeshGroup>, GeometryError> {
    [(4.4, 1.8, 1.5), (3.6, 1.6, 1.45), (5.2, 2.0, 2.2)]
        .iter()
        .enumerate()
        .map(|(k, &(length, width, height))| mesh(builder, &format!("car{k}"), &car(length, width, height)))
        .collect()
}

/// Cars of the given models parked along every street segment.
fn parked_cars(n: u32, models: &[MeshGroup], rng: &mut Rng, builder: &mut SceneBuilder) {
    let slot = 8.0;
    for along_x in [true, false] {
        for line in 0..=n {
            for segment in 0..n {
                let start = f64::from(segment) * PITCH;
                let mut slots: Vec<u32> = (0..(BLOCK / slot) as u32).collect();
                for _ in 0..rng.int(0, 4) {
                    let s = slots.swap_remove(rng.int(0, slots.len() as u32 - 1) as usize);
                    let lane = if rng.next_u64() & 1 == 0 { -4.0 } else { 4.0 };
                    let along = start + (f64::from(s) + 0.5) * slot;
                    let across = street(line) + lane;
                    let (x, z, yaw) = if along_x {
                        (along, across, if lane > 0.0 { 0.0 } else { std::f64::consts::PI })
                    } else {
                        (
                            across,
                            along,
                            if lane > 0.0 {
                                -std::f64::consts::FRAC_PI_2
                            } else {
                                std::f64::consts::FRAC_PI_2
                            },
                        )
                    };
                    let model = rng.int(0, models.len() as u32 - 1) as usize;
                    let transform =
                        DAffine3::from_rotation_translation(DQuat::from_rotation_y(yaw), DVec3::new(x, 0.0, z));
                    let name = format!("car{}_{line}_{segment}_{s}", if along_x { "x" } else { "z" });
                    place(builder, &name, &models[model], transform);
                }
            }
        }
    }
}

/// `count` props on the pavements: each on a random side of a random block,
/// 0.4–1 m inside its kerb, where no building stands (a shell's pilasters
/// keep 1.7 m from a lot's edge) and no car drives or parks. Three shared meshes,
/// so the scene grows in objects, not in meshes.
fn props(n: u32, count: u32, rng: &mut Rng, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    if count == 0 {
        return Ok(());
    }
    let models: Vec<MeshGroup> = [("bollard", 0.25, 1.0), ("bin", 0.6, 0.9), ("lamp", 0.2, 4.5)]
        .iter()
        .map(|&(name, side, height)| {
            let mut soup = TriangleSoup::default();
            cuboid(
                &mut soup,
                DVec3::new(-side / 2.0, 0.0, -side / 2.0),
                DVec3::new(side / 2.0, height, side / 2.0),
            );
            mesh(builder, name, &soup)
        })
        .collect::<Result<_, _>>()?;
    for k in 0..count {
        let block = DVec3::new(
            f64::from(rng.int(0, n - 1)) * PITCH,
            0.15,
            f64::from(rng.int(0, n - 1)) * PITCH,
        );
        let along = rng.range(0.5, BLOCK - 0.5);
        let inside = rng.range(0.4, 1.0);
        let at = match rng.int(0, 3) {
            0 => DVec3::new(along, 0.0, inside),
            1 => DVec3::new(along, 0.0, BLOCK - inside),
            2 => DVec3::new(inside, 0.0, along),
            _ => DVec3::new(BLOCK - inside, 0.0, along),
        };
        let model = &models[rng.int(0, models.len() as u32 - 1) as usize];
        place(
            builder,
            &format!("prop{k}"),
            model,
            DAffine3::from_translation(block + at),
        );
    }
    Ok(())
}

/// `count` cars driving round blocks at 0.3–0.6 m a frame (9–18 m/s at 30
/// frames a second), each on a loop just inside the centre lines of the
/// streets round its block, half of them clockwise.
fn moving_cars(n: u32, count: u32, models: &[MeshGroup], rng: &mut Rng, builder: &mut SceneBuilder) {
    for k in 0..count {
        let (bi, bj) = (rng.int(0, n - 1), rng.int(0, n - 1));
        let (x0, z0) = (f64::from(bi) * PITCH, f64::from(bj) * PITCH);
        let edge = STREET / 2.0 - DRIVING_LANE;
        let (lo, hi) = (-edge, BLOCK + edge);
        let mut corners = vec![
            DVec3::new(x0 + lo, 0.0, z0 + lo),
            DVec3::new(x0 + hi, 0.0, z0 + lo),
            DVec3::new(x0 + hi, 0.0, z0 + hi),
            DVec3::new(x0 + lo, 0.0, z0 + hi),
        ];
        if rng.next_u64() & 1 == 0 {
            corners.reverse();
        }
        let route = Route::closed(corners).expect("a block's loop has length");
        let (speed, start) = (rng.range(0.3, 0.6), rng.range(0.0, route.length()));
        let model = &models[rng.int(0, models.len() as u32 - 1) as usize];
        builder
            .add_mover(&format!("mover{k}"), model, &route, speed, start)
            .expect("the streets lie well within the renderable range");
    }
}

/// A car along +X centred on the origin: body, cabin and four wheels.
fn car(length: f64, width: f64, height: f64) -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    let r = 0.33;
    let (l2, w2) = (length / 2.0, width / 2.0);
    cuboid(
        &mut soup,
        DVec3::new(-l2, r * 0.8, -w2),
        DVec3::new(l2, height * 0.55, w2),
    );
    cuboid(
        &mut soup,
        DVec3::new(-l2 * 0.55, height * 0.55, -w2 * 0.9),
        DVec3::new(l2 * 0.45, height, w2 * 0.9),
    );
    for (x, z) in [
        (-l2 * 0.65, -w2),
        (l2 * 0.65, -w2),
        (-l2 * 0.65, w2 - 0.25),
        (l2 * 0.65, w2 - 0.25),
    ] {
        cylinder(&mut soup, DVec3::new(x, r, z), DVec3::Z, r, 0.25, 16);
    }
    soup
}

#[cfg(test)]
mod tests {
    use super::{BLOCK, PITCH};
    use crate::scene::{LoadOptions, SceneSpec, load};

    #[test]
    fn default_city_is_about_a_million_triangles_and_deterministic() {
        let spec = SceneSpec::Builtin("city".into());
        let a = load(&spec, &LoadOptions::default()).unwrap();
        let tris = a.triangles();
        assert!((1_000_000..=1_600_000).contains(&tris), "{tris} triangles");
        assert_eq!(a.source, "builtin:city:blocks=8,seed=1");
        let b = load(&spec, &LoadOptions::default()).unwrap();
        assert_eq!(a.vertices, b.vertices);
        assert_eq!(a.objects.len(), b.objects.len());
    }

    #[test]
    fn furniture_lies_inside_its_shell() {
        let s = load(
            &SceneSpec::Builtin("city:blocks=2,seed=3".into()),
            &LoadOptions::default(),
        )
        .unwrap();
        let shell = |name: &str| {
            let building = name.split('/').next().unwrap();
            s.objects
                .iter()
                .find(|o| o.name == format!("{building}/shell"))
                .unwrap()
                .bounds
        };
        let floors: Vec<_> = s.objects.iter().filter(|o| o.name.contains("/floor")).collect();
        assert!(floors.len() >= 16 * 2);
        for f in floors {
            assert!(shell(&f.name).contains(&f.bounds), "{} pokes out of its shell", f.name);
        }
        assert!(s.objects.iter().any(|o| o.name.starts_with("carx")));
        assert!(s.walk_hint.as_ref().is_some_and(|w| w.len() == 3));
    }

    #[test]
    fn props_stand_on_the_pavements_and_leave_the_city_alone() {
        let load_spec = |spec: &str| load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap();
        let city = load_spec("city:blocks=2");
        let with = load_spec("city:blocks=2,props=5000");
        assert_eq!(with.source, "builtin:city:blocks=2,seed=1,props=5000");
        assert_eq!(with.objects.len(), city.objects.len() + 5000);
        let props: Vec<_> = with.objects.iter().filter(|o| o.name.starts_with("prop")).collect();
        assert_eq!(props.len(), 5000);
        for (a, b) in city.objects.iter().zip(&with.objects) {
            assert_eq!((&a.name, a.bounds), (&b.name, b.bounds), "the city is as it was");
        }
        // On a pavement: clear of every building shell and of the streets.
        let shells: Vec<_> = city.objects.iter().filter(|o| o.name.ends_with("/shell")).collect();
        for p in &props {
            let on_block = |x: f64| (x % PITCH) >= 0.0 && (x % PITCH) <= BLOCK;
            assert!(
                on_block(p.bounds.min.x) && on_block(p.bounds.max.x),
                "{}: {:?}",
                p.name,
                p.bounds
            );
            assert!(
                on_block(p.bounds.min.z) && on_block(p.bounds.max.z),
                "{}: {:?}",
                p.name,
                p.bounds
            );
            for s in &shells {
                let apart = (0..3).any(|k| p.bounds.max[k] <= s.bounds.min[k] || p.bounds.min[k] >= s.bounds.max[k]);
                assert!(apart, "{} stands in {}", p.name, s.name);
            }
        }
        let mesh_count = |s: &crate::scene::Scene| s.meshes.len();
        assert_eq!(mesh_count(&with), mesh_count(&city) + 3, "props share three meshes");
    }

    #[test]
    fn movers_drive_round_their_blocks_and_leave_the_static_city_alone() {
        let load_spec = |spec: &str| load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap();
        let still = load_spec("city:blocks=2");
        let mut moving = load_spec("city:blocks=2,movers=12");
        assert_eq!(moving.source, "builtin:city:blocks=2,seed=1,movers=12");
        assert!(still.movers.is_empty());
        assert_eq!(moving.movers.len(), 12, "one object per car model");
        let fixed = still.objects.len();
        assert_eq!(moving.objects.len(), fixed + 12);
        for (a, b) in still.objects.iter().zip(&moving.objects) {
            assert_eq!((&a.name, a.bounds), (&b.name, b.bounds), "the static city is unchanged");
        }
        let streets = moving.bounds;
        let mut moved = Vec::new();
        for frame in [0, 1, 57, 400] {
            moved.clear();
            moving.pose(frame, &mut moved);
            for m in &moving.movers {
                let o = &moving.objects[m.object as usize];
                assert!(streets.contains(&o.bounds), "{} left the city at frame {frame}", o.name);
                assert!(
                    o.bounds.min.y >= 0.0 && o.bounds.max.y < 3.0,
                    "{} is on the road",
                    o.name
                );
            }
            if frame > 0 {
                assert_eq!(moved.len(), 12, "every car moves every frame");
            }
        }
        let mut again = Vec::new();
        moving.pose(400, &mut again);
        assert!(again.is_empty(), "posing the same frame twice moves nothing");
    }
}
