//! Per-frame figures, the error measure, summary statistics, and each
//! frame's timeline.

mod reference;
mod rows;
mod summary;
mod timeline;

pub use reference::{DepthError, ErrorMeter, ObjectError};
pub use rows::{FrameStats, MissedObject, RowLimits};
pub use summary::{Distribution, LEAST_PAIRS, ModeDescription, ModeSummary, PairedRatio, StrategyShare, summarize};
pub use timeline::{CpuClock, FrameTimeline, GpuClock, Stretch, Work};
