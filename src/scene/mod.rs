//! The scene model and its loaders.
//!
//! A [`Scene`] is a list of objects drawn from one shared vertex/index store
//! (model.rs). Every loader (OBJ, glTF, built-in) feeds triangles through
//! one [`SceneBuilder`], which validates them (validate.rs), splits large
//! meshes into spatially coherent clusters (cluster.rs) and instantiates
//! them, so all sources obey the same rules. This file only declares and
//! re-exports.

pub mod builtin;
pub mod cameras;
mod closed;
mod cluster;
mod draco;
mod focus;
mod gltf;
mod gltf_json;
mod instancing;
mod load;
pub(crate) mod memory;
mod meshopt;
mod model;
pub mod motion;
mod obj;
mod phases;
mod source;
pub mod up;
mod validate;

#[cfg(test)]
pub(crate) use focus::fixtures;
pub use focus::{Focus, LeftOut};
pub use load::{load, load_bytes, looks_z_up};
pub use model::{DEFAULT_CLUSTER_TRIANGLES, Mesh, MeshGroup, Object, Part, Scene, SceneBuilder, TriangleSoup};
pub use phases::LoadPhases;
pub use source::{LoadOptions, SceneError, SceneSpec};
pub use validate::{GeometryError, MAX_COORDINATE, within_range};
