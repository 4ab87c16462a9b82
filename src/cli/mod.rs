//! The `occlu` command line's parts, one job each: its arguments, its
//! output, its signals, its progress, and the commands' handlers by group.

pub mod args;
pub mod bench;
pub mod inputs;
pub mod output;
pub mod pictures;
pub mod progress;
pub mod results;
pub mod runtime_folder;
pub mod scene;
pub mod signals;
pub mod stress;
