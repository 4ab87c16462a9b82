//! Built-in procedural scenes, named on the command line as
//! `NAME[:key=value,...]`, e.g. `city:blocks=4,seed=7`. Generation is seeded
//! and deterministic, so every run of a spec gives the same scene.

mod city;
mod forest;
pub(crate) mod shapes;

use glam::DAffine3;

use super::{LoadOptions, MeshGroup, Scene, SceneBuilder, SceneError, TriangleSoup};

pub use city::{CityParams, EYE_HEIGHT};
pub use forest::ForestParams;

/// The scenes `--scene` accepts, with a one-line description each.
pub const SCENES: &[(&str, &str)] = &[
    (
        "city",
        "grid of closed buildings with furniture inside and cars in the streets: heavy occlusion (params: blocks, seed, movers)",
    ),
    (
        "forest",
        "scattered trees with see-through crowns: little occlusion, where culling must not cost more than it saves (params: trees, seed)",
    ),
];

/// Builds the scene a spec names.
pub fn build(spec: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
    let (name, params) = parse_spec(spec)?;
    let error = |message: String| SceneError::Builtin {
        spec: spec.to_string(),
        message,
    };
    match name {
        "city" => {
            let p = CityParams::from_params(&params).map_err(error)?;
            let mut builder = SceneBuilder::new(format!("builtin:{}", p.spec()), options.cluster_triangles);
            city::generate(&p, &mut builder);
            builder.finish().ok_or_else(|| error("generated no geometry".into()))
        }
        "forest" => {
            let p = ForestParams::from_params(&params).map_err(error)?;
            let mut builder = SceneBuilder::new(format!("builtin:{}", p.spec()), options.cluster_triangles);
            forest::generate(&p, &mut builder);
            builder.finish().ok_or_else(|| error("generated no geometry".into()))
        }
        other => Err(error(format!(
            "unknown scene '{other}' (built-in scenes: {})",
            SCENES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// Adds `soup` as a mesh and one object of it, untransformed.
fn add(builder: &mut SceneBuilder, name: &str, soup: &TriangleSoup) {
    let group = mesh(builder, name, soup);
    place(builder, name, &group, DAffine3::IDENTITY);
}

fn place(builder: &mut SceneBuilder, name: &str, group: &MeshGroup, transform: DAffine3) {
    builder
        .add_object(name, group, transform)
        .expect("built-in scenes lie well within the renderable range");
}

fn mesh(builder: &mut SceneBuilder, name: &str, soup: &TriangleSoup) -> MeshGroup {
    builder
        .add_mesh(name, &soup.positions, &soup.indices)
        .expect("procedural geometry is finite and indexed in range")
}

/// `spec` with `movers=N` added to its parameters (`--movers`).
pub fn with_movers(spec: &str, movers: u32) -> String {
    let separator = if spec.contains(':') { ',' } else { ':' };
    format!("{spec}{separator}movers={movers}")
}

type Params<'a> = Vec<(&'a str, &'a str)>;

fn parse_spec(spec: &str) -> Result<(&str, Params<'_>), SceneError> {
    let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let params = rest
        .split(',')
        .filter(|kv| !kv.is_empty())
        .map(|kv| {
            kv.split_once('=').ok_or_else(|| SceneError::Builtin {
                spec: spec.to_string(),
                message: format!("parameter '{kv}' is not key=value"),
            })
        })
        .collect::<Result<_, _>>()?;
    Ok((name, params))
}

/// Reads integer parameters by name, rejecting unknown keys and bad values.
fn read_params(params: &Params, keys: &mut [(&str, &mut u64, std::ops::RangeInclusive<u64>)]) -> Result<(), String> {
    for (i, &(key, value)) in params.iter().enumerate() {
        if params[..i].iter().any(|&(k, _)| k == key) {
            return Err(format!("parameter '{key}' is given twice"));
        }
        let Some((_, slot, range)) = keys.iter_mut().find(|(k, _, _)| *k == key) else {
            let known: Vec<&str> = keys.iter().map(|(k, _, _)| *k).collect();
            return Err(format!("unknown parameter '{key}' (known: {})", known.join(", ")));
        };
        let v: u64 = value
            .parse()
            .map_err(|_| format!("parameter '{key}' must be a whole number, got '{value}'"))?;
        if !range.contains(&v) {
            return Err(format!(
                "parameter '{key}' must be in {}..={}, got {v}",
                range.start(),
                range.end()
            ));
        }
        **slot = v;
    }
    Ok(())
}

/// A small seeded generator (SplitMix64): scenes must be reproducible from
/// their spec alone, on every platform.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in lo..=hi.
    pub fn int(&mut self, lo: u32, hi: u32) -> u32 {
        lo + (self.next_u64() % u64::from(hi - lo + 1)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_scene_and_bad_params_are_clear_errors() {
        let o = LoadOptions::default();
        let msg = |s: &str| build(s, &o).err().unwrap().to_string();
        assert!(msg("desert").contains("unknown scene 'desert' (built-in scenes: city, forest)"));
        assert!(msg("city:size=3").contains("unknown parameter 'size'"));
        assert!(msg("city:blocks=x").contains("whole number"));
        assert!(msg("city:blocks=0").contains("must be in"));
        assert!(msg("city:blocks").contains("not key=value"));
        assert!(msg("city:blocks=1,blocks=2").contains("'blocks' is given twice"));
        assert!(msg(&with_movers("city:movers=2", 3)).contains("'movers' is given twice"));
        assert!(msg("city:movers=100001").contains("must be in"));
    }

    #[test]
    fn rng_is_deterministic_and_in_range() {
        let (mut a, mut b) = (Rng::new(5), Rng::new(5));
        for _ in 0..1000 {
            let x = a.range(2.0, 3.0);
            assert_eq!(x, b.range(2.0, 3.0));
            assert!((2.0..3.0).contains(&x));
            let i = a.int(3, 5);
            assert_eq!(i, b.int(3, 5));
            assert!((3..=5).contains(&i));
        }
    }
}
