//! Per-frame figures, the error measure, and summary statistics.

mod reference;
mod rows;
mod summary;

pub use reference::{DepthError, ErrorMeter, ObjectError};
pub use rows::{FrameStats, MissedObject, RowLimits};
pub use summary::{Distribution, ModeDescription, ModeSummary, StrategyShare, summarize};
