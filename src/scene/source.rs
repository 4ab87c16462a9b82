//! Where a scene comes from ([`SceneSpec`]), how it is read
//! ([`LoadOptions`]), and what can go wrong ([`SceneError`]).

use std::path::{Path, PathBuf};

use super::model::DEFAULT_CLUSTER_TRIANGLES;
use super::up::UpChoice;
use super::validate::GeometryError;
use crate::auto_or::AutoOr;

/// Where a scene comes from, as the command line names it.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSpec {
    File(PathBuf),
    /// A built-in procedural scene, `NAME[:key=value,...]`.
    Builtin(String),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// Meshes with more triangles than this are split into clusters.
    pub cluster_triangles: u32,
    /// Largest model or glTF buffer file read, in bytes.
    pub max_file_size: u64,
    /// glTF buffers may lie anywhere, not only in the model's folder. Off by
    /// default: a model from elsewhere must not make occlu read other files.
    pub external_buffers: bool,
    /// The scene's up axis, or how to choose it.
    pub up: UpChoice,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            cluster_triangles: DEFAULT_CLUSTER_TRIANGLES,
            max_file_size: crate::input::MODEL_LIMIT,
            external_buffers: false,
            up: AutoOr::Auto,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    // Fields are named `error`, not `source`: each message already says
    // everything, and a `source` would be printed a second time by error
    // chains.
    #[error("{}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
    #[error("{}: unsupported model format (supported: .obj, .gltf, .glb)", path.display())]
    UnsupportedFormat { path: PathBuf },
    #[error("{}: {message}", path.display())]
    Parse { path: PathBuf, message: String },
    #[error("{}: {error}", path.display())]
    Geometry { path: PathBuf, error: GeometryError },
    #[error("{}: the model has no triangles to render", path.display())]
    Empty { path: PathBuf },
    #[error("built-in scene '{spec}': {message}")]
    Builtin { spec: String, message: String },
    #[error("--cluster-triangles must be at least 1")]
    ZeroClusterSize,
}

/// Reads a model or glTF buffer file of at most `options.max_file_size`
/// bytes; past it, the message names the flag that raises the limit.
pub(super) fn read_model_file(path: &Path, options: &LoadOptions) -> std::io::Result<Vec<u8>> {
    crate::input::read_file(path, options.max_file_size).map_err(|e| {
        if e.kind() == std::io::ErrorKind::FileTooLarge {
            std::io::Error::new(e.kind(), format!("{e} (--max-file-size raises it)"))
        } else {
            e
        }
    })
}
