//! occlu: a benchmark and flythrough tool for occlusion culling.
//!
//! The data flows one way, one module per step (docs/ARCHITECTURE.md):
//! [`scene`] loads or generates a [`scene::Scene`], [`hierarchy`] builds the
//! bounding-volume tree, [`camera`] turns a path into cameras, [`gpu`] holds
//! the device, the scene's buffers and the per-frame operations, [`cull`]
//! holds one file per culling mode, [`measure`] computes error and
//! statistics, [`report`] writes the result files and charts (and merges
//! many runs' into one report), [`session`] renders one frame in every
//! mode, timed, [`bench`] runs the whole flow, [`matrix`] lists the runs of
//! a matrix configuration and shards them, [`picture`] renders one frame to
//! look at, [`animation`] many frames of many modes, and [`stress`] runs the
//! numerically hard cases.

pub mod animation;
pub mod auto_or;
pub mod balanced_order;
pub mod bench;
pub mod bounds;
pub mod camera;
pub mod config;
pub mod cull;
pub mod export;
pub mod gpu;
pub mod hierarchy;
pub mod input;
pub mod matrix;
pub mod measure;
pub mod object_set;
mod parallel;
pub mod picture;
pub mod raycast;
pub mod report;
pub mod rng;
pub mod scene;
pub mod session;
pub mod stress;
pub mod text;
pub mod world;
