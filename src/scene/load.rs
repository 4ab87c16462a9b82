//! Loading a scene: a file by its format (OBJ, glTF) or a built-in one,
//! then choosing its up axis.

use std::path::Path;
use std::time::Instant;

use super::model::{Object, Scene, SceneBuilder};
use super::phases::timed;
use super::source::{LoadOptions, SceneError, SceneSpec, read_model_file};
use super::up::{Up, UpAxis, UpChoice};
use super::{builtin, gltf, obj};
use crate::auto_or::AutoOr;

/// Loads a scene from a file or builds a built-in one.
pub fn load(spec: &SceneSpec, options: &LoadOptions) -> Result<Scene, SceneError> {
    if options.cluster_triangles == 0 {
        return Err(SceneError::ZeroClusterSize);
    }
    match spec {
        SceneSpec::Builtin(name) => {
            let started = Instant::now();
            let mut scene = builtin::build(name, options)?;
            scene.up = choose(options.up, Source::Builtin, &scene);
            scene.in_metres = true;
            scene.phases.parse_is_the_rest_of(started.elapsed());
            Ok(scene)
        }
        SceneSpec::File(path) => load_file(path, options),
    }
}

fn load_file(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    // The format is checked before reading, so a wrong file is not read whole.
    loader_for(path)?;
    let (bytes, read_ms) = timed(|| read_model_file(path, options));
    let bytes = bytes.map_err(|error| SceneError::Io {
        path: path.into(),
        error,
    })?;
    let mut scene = load_bytes(path, &bytes, options)?;
    scene.phases.read_ms = read_ms;
    scene.files.insert(0, path.to_path_buf());
    Ok(scene)
}

/// Parses a model already in memory; `path` names it in errors, chooses the
/// format by its extension, and anchors a glTF's relative buffer URIs.
pub fn load_bytes(path: &Path, bytes: &[u8], options: &LoadOptions) -> Result<Scene, SceneError> {
    if options.cluster_triangles == 0 {
        return Err(SceneError::ZeroClusterSize);
    }
    let (loader, source) = loader_for(path)?;
    let started = Instant::now();
    let mut builder = SceneBuilder::new(path.display().to_string(), options.cluster_triangles);
    loader(path, bytes, options, &mut builder)?;
    let mut scene = builder
        .finish()
        .ok_or_else(|| SceneError::Empty { path: path.into() })?;
    scene.up = choose(options.up, source, &scene);
    scene.in_metres = source == Source::Gltf;
    scene.phases.parse_is_the_rest_of(started.elapsed());
    Ok(scene)
}

type Loader = fn(&Path, &[u8], &LoadOptions, &mut SceneBuilder) -> Result<(), SceneError>;

fn loader_for(path: &Path) -> Result<(Loader, Source), SceneError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => Ok((obj::load, Source::Obj)),
        Some("gltf") | Some("glb") => Ok((gltf::load, Source::Gltf)),
        _ => Err(SceneError::UnsupportedFormat { path: path.into() }),
    }
}

/// Where a scene came from, for the automatic choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Obj,
    Gltf,
    Builtin,
}

/// The up axis of `scene`, loaded from `source`, as `choice` asks.
pub fn choose(choice: UpChoice, source: Source, scene: &Scene) -> Up {
    match (choice, source) {
        (AutoOr::Given(axis), _) => Up {
            axis,
            why: "given by --up".into(),
        },
        (AutoOr::Auto, Source::Gltf) => Up {
            axis: UpAxis::Y,
            why: "auto: glTF is +Y up".into(),
        },
        (AutoOr::Auto, Source::Builtin) => Up {
            axis: UpAxis::Y,
            why: "auto: built-in scenes are +Y up".into(),
        },
        (AutoOr::Auto, Source::Obj) => match looks_z_up(scene) {
            Some(evidence) => Up {
                axis: UpAxis::Z,
                why: format!("auto: OBJ {evidence}"),
            },
            None => Up {
                axis: UpAxis::Y,
                why: "auto: OBJ, +Y as most OBJ exporters write (it does not look +Z up)".into(),
            },
        },
    }
}

/// Why a model looks +Z up, if it does: it is at least twice as flat in Z as
/// across both X and Y (a city, a site, a floor plan), and it stands on its
/// Z minimum. Standing is told by its objects: many start at the lowest Z
/// and end below the highest (buildings of different heights on a ground),
/// at least twice as many as the other way round. A Y-up model that is
/// merely thin in Z (a facade, a sign) has parts spanning its whole depth,
/// or as many at the back as at the front, and keeps +Y.
pub fn looks_z_up(scene: &Scene) -> Option<String> {
    let (b, e) = (scene.bounds, scene.bounds.extent());
    let across = e.x.min(e.y);
    if !(e.z > 0.0 && e.z * FLATNESS <= across) {
        return None;
    }
    let near = 0.1 * e.z;
    let at_bottom = |o: &Object| o.bounds.min.z - b.min.z <= near;
    let at_top = |o: &Object| b.max.z - o.bounds.max.z <= near;
    let standing = scene.objects.iter().filter(|o| at_bottom(o) && !at_top(o)).count();
    let hanging = scene.objects.iter().filter(|o| at_top(o) && !at_bottom(o)).count();
    (standing >= MIN_STANDING && standing >= 2 * hanging).then(|| {
        format!(
            "looks +Z up: {:.1}× flatter in Z than across, {standing} objects standing on its Z minimum ({hanging} hanging from its maximum)",
            across / e.z
        )
    })
}

/// How much flatter in the up axis than across a +Z-up model must be.
const FLATNESS: f64 = 2.0;

/// Objects standing on the ground that a +Z-up model needs at least.
const MIN_STANDING: usize = 3;
