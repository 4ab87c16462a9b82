//! `forest`: a seeded scene with little occlusion, in the spirit of 002's
//! forest (§5: culling "does not pay off" where much of the scene is
//! visible) and 001's scattered teapots.
//!
//! `trees` trees stand at random on a square of ground, each a thin trunk
//! and a crown of a few separate blobs with gaps between them, so the view
//! reaches far between and through them: most objects in the frustum are
//! visible, and an occlusion test mostly confirms what frustum culling
//! already drew. A lane along the middle stays clear for the walk.
//!
//! Units are metres, +Y is up; the forest lies in [0, side]² with side
//! growing with the square root of the tree count (one tree per ~64 m²).

use glam::DVec3;

use super::build::{Params, add, read_params};
use super::city::EYE_HEIGHT;
use super::shapes::{cuboid, cylinder};
use crate::rng::Rng;
use crate::scene::{GeometryError, SceneBuilder, TriangleSoup};

/// Ground per tree: one tree per 8 m × 8 m on average.
const AREA_PER_TREE: f64 = 64.0;
/// Half-width of the clear lane the walk follows.
const LANE: f64 = 2.5;
/// Ground tiles per side.
const TILES: u32 = 4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForestParams {
    pub trees: u32,
    pub seed: u64,
}

impl Default for ForestParams {
    /// 2 000 trees: about as many objects as the default city, with a
    /// third of its triangles.
    fn default() -> Self {
        ForestParams { trees: 2000, seed: 1 }
    }
}

impl ForestParams {
    pub(super) fn from_params(params: &Params) -> Result<Self, String> {
        let d = ForestParams::default();
        let (mut trees, mut seed) = (u64::from(d.trees), d.seed);
        read_params(
            params,
            &mut [("trees", &mut trees, 1..=200_000), ("seed", &mut seed, 0..=u64::MAX)],
        )?;
        Ok(ForestParams {
            trees: trees as u32,
            seed,
        })
    }

    /// The canonical spec, with every parameter spelled out.
    pub fn spec(&self) -> String {
        format!("forest:trees={},seed={}", self.trees, self.seed)
    }

    /// Side of the square the trees stand on.
    pub fn side(&self) -> f64 {
        (f64::from(self.trees) * AREA_PER_TREE).sqrt().max(4.0 * LANE)
    }
}

pub fn generate(p: &ForestParams, builder: &mut SceneBuilder) -> Result<(), GeometryError> {
    let mut rng = Rng::new(p.seed);
    let side = p.side();
    let tile = side / f64::from(TILES);
    for i in 0..TILES {
        for j in 0..TILES {
            let mut soup = TriangleSoup::default();
            let lo = DVec3::new(f64::from(i) * tile, -0.5, f64::from(j) * tile);
            cuboid(&mut soup, lo, lo + DVec3::new(tile, 0.5, tile));
            add(builder, &format!("ground{i}_{j}"), &soup)?;
        }
    }
    let middle = side / 2.0;
    for t in 0..p.trees {
        // Resample positions in the lane (the crown's reach included).
        let at = loop {
            let (x, z) = (rng.range(0.0, side), rng.range(0.0, side));
            if (z - middle).abs() > LANE + 2.0 {
                break DVec3::new(x, 0.0, z);
            }
        };
        add(builder, &format!("tree{t}"), &tree(at, &mut rng))?;
    }
    let at = |x: f64| DVec3::new(x, EYE_HEIGHT, middle);
    builder.set_walk_hint(vec![at(0.0), at(side)]);
    Ok(())
}

/// A trunk and 3-6 separate crown blobs around and above it.
fn tree(base: DVec3, rng: &mut Rng) -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    let height = rng.range(4.0, 9.0);
    cylinder(&mut soup, base, DVec3::Y, rng.range(0.12, 0.3), height, 8);
    for _ in 0..rng.int(3, 6) {
        let centre = base + DVec3::new(rng.range(-1.6, 1.6), height * rng.range(0.6, 1.0), rng.range(-1.6, 1.6));
        let radius = rng.range(0.4, 0.9);
        cylinder(
            &mut soup,
            centre - DVec3::Y * radius,
            DVec3::Y,
            radius,
            2.0 * radius,
            12,
        );
    }
    soup
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LoadOptions, SceneSpec, load};

    fn forest(spec: &str) -> crate::scene::Scene {
        load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default()).unwrap()
    }

    #[test]
    fn trees_stand_on_the_ground_clear_of_the_walk_lane() {
        let p = ForestParams { trees: 300, seed: 4 };
        let scene = forest(&p.spec());
        let tiles = (TILES * TILES) as usize;
        assert_eq!(scene.objects.len(), tiles + 300);
        let (side, middle) = (p.side(), p.side() / 2.0);
        for tree in &scene.objects[tiles..] {
            let b = tree.bounds;
            assert!(b.min.y >= 0.0 && b.max.y < 11.0, "{}: {b:?}", tree.name);
            assert!(
                b.min.z > middle + LANE || b.max.z < middle - LANE,
                "{} stands in the lane",
                tree.name
            );
            let centre = (b.min + b.max) / 2.0;
            assert!((-2.0..side + 2.0).contains(&centre.x) && (-2.0..side + 2.0).contains(&centre.z));
        }
        let walk = scene.walk_hint.as_ref().unwrap();
        assert!(walk.iter().all(|w| w.z == middle && w.y == EYE_HEIGHT));
    }

    #[test]
    fn a_spec_gives_the_same_forest_and_bad_specs_are_errors() {
        let a = forest("forest:trees=50,seed=9");
        let b = forest("forest:trees=50,seed=9");
        assert_eq!(a.vertices, b.vertices);
        assert_ne!(a.vertices, forest("forest:trees=50,seed=10").vertices);
        let msg = |spec: &str| {
            load(&SceneSpec::Builtin(spec.into()), &LoadOptions::default())
                .unwrap_err()
                .to_string()
        };
        assert!(msg("forest:trees=0").contains("must be in"));
        assert!(msg("forest:blocks=2").contains("unknown parameter 'blocks'"));
    }
}
