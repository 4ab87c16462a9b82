//! Culling modes: one file (or directory) per mode, each behind the
//! [`Culler`] trait (culler.rs).
//!
//! A mode owns its state between frames (temporal coherence lives inside the
//! mode) and touches the GPU only through [`crate::gpu::FrameCtx`], which
//! counts what it draws and queries. To add a mode: write `cull/NAME.rs`
//! implementing [`Culler`] and declaring its entry (`MODE`: summary,
//! parameters, needs, what it carries between frames, whether `auto` may
//! run it, constructor), add a line to `modes!` (mode.rs: its
//! [`ModeId`] and name), and point [`ModeId::info`] at its entry
//! (registry.rs).
//!
//! This file only declares and re-exports: the modes import what they use
//! from the files that define it, so no file imports one that imports it
//! back.

mod ac;
mod auto;
mod chc;
mod culler;
mod dr;
pub mod gpu_walk;
mod mode;
pub mod occupancy;
mod omq;
mod oracle;
#[cfg(test)]
mod recording;
mod registry;
mod sq;
mod swr;
pub mod traversal;
mod vfc;

pub use ac::{AcParams, AdaptiveCulling, EyeDistance, Threshold};
pub use auto::{AutoCulling, AutoParams};
pub use chc::{ChcParams, CoherentCulling};
pub use culler::{CellDepths, Culler, FrameInput, Labeled, Pick, PreviousFrame, TraversalStats};
pub use dr::DirectRendering;
pub use gpu_walk::depths::{Depth, DepthRange};
pub use gpu_walk::hiz::{BoxesTested, HizParams, hierarchical_depth_culling};
pub use gpu_walk::ioc::iterative_occlusion_culling;
pub use gpu_walk::roc::raster_occlusion_culling;
pub use gpu_walk::{GpuCulling, VisibleLists, Walked};
pub use mode::{BuildCuller, Candidacy, Carries, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
pub use omq::{OccupancyMapQueries, OmqParams};
pub use oracle::Oracle;
pub use registry::{create, modes, parse_modes};
pub use sq::SingleQueries;
pub use swr::{SoftwareOcclusionCulling, SwrParams};
pub use vfc::FrustumCulling;
