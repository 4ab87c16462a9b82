//! Culling modes: one file (or directory) per mode, each behind the
//! [`Culler`] trait (culler.rs), and one line per mode in `mode_table!`.
//!
//! A mode owns its state between frames (temporal coherence lives inside the
//! mode) and touches the GPU only through [`crate::gpu::FrameCtx`], which
//! counts what it draws and queries. To add a mode: write `cull/NAME.rs` (or
//! a folder) implementing [`Culler`] and declaring its entry (`MODE`:
//! summary, chart colour, parameters, needs, what it carries between frames,
//! whether `auto` may run it, constructor), and add its line to the table
//! below.
//!
//! This file only declares and re-exports: the modes import what they use
//! from the files that define it, so no file imports one that imports it
//! back.

/// Every mode, one line each, in the order `all` runs them and `--help`
/// lists them: its [`ModeId`] variant, its name on the command line and in
/// result files, and the module that declares its entry (`MODE`). A module
/// of one segment is the mode's own, declared by this table; the GPU walks
/// share `gpu_walk`, declared below.
///
/// The table is handed to the macro `$then`, which makes one thing of it:
/// the module declarations (here), the enum and its names (mode.rs), the
/// entries' lookup (registry.rs). So the three cannot disagree, and a mode
/// is named outside its own folder only here.
macro_rules! mode_table {
    ($then:ident) => {
        $then! {
            Dr => "dr", dr;
            Vfc => "vfc", vfc;
            Sq => "sq", sq;
            Omq => "omq", omq;
            Ac => "ac", ac;
            Chc => "chc", chc;
            Roc => "roc", gpu_walk::roc;
            Ioc => "ioc", gpu_walk::ioc;
            Hiz => "hiz", gpu_walk::hiz;
            Swr => "swr", swr;
            Auto => "auto", auto;
            Oracle => "oracle", oracle;
        }
    };
}

/// Declares the modules of the table's modes that have one of their own.
macro_rules! declare_mode_modules {
    () => {};
    ($id:ident => $name:literal, $module:ident; $($rest:tt)*) => {
        mod $module;
        declare_mode_modules! { $($rest)* }
    };
    ($id:ident => $name:literal, $shared:ident :: $module:ident; $($rest:tt)*) => {
        declare_mode_modules! { $($rest)* }
    };
}

mode_table!(declare_mode_modules);

mod culler;
pub mod gpu_walk;
mod last_frame;
mod mode;
pub mod occupancy;
#[cfg(test)]
mod recording;
mod registry;
pub mod traversal;

pub use ac::{AcParams, AdaptiveCulling, EyeDistance, Threshold};
pub use auto::{AutoCulling, AutoParams, FULL_CALIBRATION_WARM_UPS};
pub use chc::{ChcParams, CoherentCulling};
pub use culler::{Culler, FrameInput, Labeled, OccluderDepths, Pick, PreviousFrame, TraversalStats};
pub use dr::DirectRendering;
pub use gpu_walk::depths::{Depth, DepthRange};
pub use gpu_walk::hiz::{BoxesTested, HizParams, hierarchical_depth_culling};
pub use gpu_walk::ioc::iterative_occlusion_culling;
pub use gpu_walk::roc::raster_occlusion_culling;
pub use gpu_walk::{GpuCulling, VisibleLists, Walked};
pub use mode::{BuildCuller, Candidacy, Carries, CountKind, ModeError, ModeId, ModeInfo, ModeParams, Needs, ParamInfo};
pub use omq::{OccupancyMapQueries, OmqParams};
pub use oracle::Oracle;
pub use registry::{Unrunnable, auto_candidates, create, modes, parse_modes, unrunnable};
pub use sq::SingleQueries;
pub use swr::{SoftwareOcclusionCulling, SwrParams};
pub use vfc::FrustumCulling;
