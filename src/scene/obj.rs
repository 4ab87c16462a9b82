//! Wavefront OBJ through tobj: each `o`/`g` becomes an object; materials,
//! normals and texture coordinates are not needed and not loaded.

use std::io::Cursor;
use std::path::Path;

use glam::{DAffine3, DVec3};

use super::model::SceneBuilder;
use super::source::{LoadOptions, SceneError};

/// Loads an OBJ model. The options on reading further files do not apply:
/// an OBJ file's geometry is all in it, and its material files are not read.
pub fn load(path: &Path, bytes: &[u8], _: &LoadOptions, builder: &mut SceneBuilder) -> Result<(), SceneError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials never affect visibility: refuse to open .mtl files at all.
    let (models, _materials) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    })
    .map_err(|e| SceneError::Parse {
        path: path.into(),
        message: format!("invalid OBJ: {e}"),
    })?;

    // tobj starts a new model at every `usemtl` too: consecutive models with
    // the same name are one `o`/`g` and are merged back. Two separate `o a`
    // statements stay two objects.
    let mut names: Vec<String> = Vec::new();
    let mut meshes: Vec<(Vec<DVec3>, Vec<u32>)> = Vec::new();
    for model in models {
        let name = if model.name.is_empty() {
            "(unnamed)".to_string()
        } else {
            model.name
        };
        if names.last() != Some(&name) {
            names.push(name);
            meshes.push(Default::default());
        }
        let (positions, indices) = meshes.last_mut().expect("pushed above");
        let base = positions.len() as u32;
        positions.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0], p[1], p[2])),
        );
        indices.extend(model.mesh.indices.iter().map(|&i| base + i));
    }
    for (name, (positions, indices)) in names.iter().zip(&meshes) {
        let geometry = |error| SceneError::Geometry {
            path: path.into(),
            error,
        };
        let group = builder.add_mesh(name, positions, indices).map_err(geometry)?;
        builder.add_object(name, &group, DAffine3::IDENTITY).map_err(geometry)?;
    }
    let skipped = count_line_and_point_elements(bytes);
    if skipped > 0 {
        builder.warn(format!(
            "ignored {skipped} line/point elements ('l'/'p'): only faces are rendered"
        ));
    }
    Ok(())
}

/// Lines and points draw no depth in a triangle renderer; they are counted so
/// that skipping them is reported, not silent.
fn count_line_and_point_elements(bytes: &[u8]) -> usize {
    bytes
        .split(|&b| b == b'\n')
        .filter(|line| {
            let line = line.trim_ascii_start();
            (line.starts_with(b"l") || line.starts_with(b"p")) && line.get(1).is_some_and(|c| c.is_ascii_whitespace())
        })
        .count()
}
