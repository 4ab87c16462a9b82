//! What every built-in scene is built with: named integer parameters, a
//! seeded random source, and adding generated meshes to the builder.

use glam::DAffine3;

use crate::scene::{GeometryError, MeshGroup, SceneBuilder, TriangleSoup};

/// Adds `soup` as a mesh and one object of it, untransformed.
pub(super) fn add(builder: &mut SceneBuilder, name: &str, soup: &TriangleSoup) -> Result<(), GeometryError> {
    let group = mesh(builder, name, soup)?;
    place(builder, name, &group, DAffine3::IDENTITY);
    Ok(())
}

pub(super) fn place(builder: &mut SceneBuilder, name: &str, group: &MeshGroup, transform: DAffine3) {
    builder
        .add_object(name, group, transform)
        .expect("built-in scenes lie well within the renderable range");
}

/// Adds `soup` as a mesh: procedural geometry is finite and indexed in
/// range, so it fails only where the scene asked for passes what the
/// memory available holds.
pub(super) fn mesh(builder: &mut SceneBuilder, name: &str, soup: &TriangleSoup) -> Result<MeshGroup, GeometryError> {
    builder.add_mesh(name, &soup.positions, &soup.indices)
}

pub(super) type Params<'a> = Vec<(&'a str, &'a str)>;

/// Reads integer parameters by name, rejecting unknown keys and bad values.
pub(super) fn read_params(
    params: &Params,
    keys: &mut [(&str, &mut u64, std::ops::RangeInclusive<u64>)],
) -> Result<(), String> {
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
