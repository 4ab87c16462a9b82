//! `occlu merge DIR... --out MERGED`: result folders from many machines in
//! one report.
//!
//! A DIR is a run's folder (it holds summary.json) or a folder of them (a
//! matrix's `--out`, one per shard or machine). Folders are one run when
//! summary.json names the same matrix run, or, for runs outside a matrix,
//! when they measured the same scene and path; one run's folders must agree
//! on scene (the geometry's fingerprint), path (the cameras'), resolution
//! and frames, or the merge is refused. Within a run each adapter (name and
//! backend) is a column beside the others, never averaged; two folders of
//! one run on one adapter are refused unless they are copies of one result.
//!
//! Counters that do not depend on the adapter (objects and triangles drawn,
//! boxes tested, wrong pixels) are compared between adapters of the same
//! backend: a difference is listed in the report and merged.json, as it
//! points at a bug in one backend's path. It does not fail the merge;
//! `occlu compare` of merged folders is the gate.
//!
//! MERGED gets merged.json (for machines), report.md, `charts/` (each
//! run's ratio to the oracle per adapter) and `runs/` (a copy of every
//! merged run folder, `RUN--ADAPTER-HASH`, the hash of the run's and the
//! adapter's full names so that names cut short never collide; `occlu
//! compare` of two merged folders pairs them by the run, adapter and
//! backend merged.json records, not by folder name).
//!
//! Analysis and report are apart: `read.rs` reads the folders, `group.rs`
//! groups and checks them into runs, `render.rs` draws report.md and the
//! charts; `write.rs` runs them in that order and writes the merged folder.
//! `merged.rs` holds what merged.json holds, `error.rs` why a merge is
//! refused.

mod error;
mod group;
mod merged;
mod read;
mod render;
mod write;

pub use error::MergeError;
pub(crate) use group::one_run;
pub use merged::{
    AdapterColumn, Disagreement, MERGED_SCHEMA_VERSION, Merged, MergedRun, MissingRuns, ModeResult, ModeRow,
    read_merged,
};
pub use render::render;
pub use write::merge;
