//! Where a load's time went, phase by phase ([`LoadPhases`]): what `occlu
//! info` prints and the load benchmark measures.

use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

/// Milliseconds each phase of loading one scene took. Validation, the
/// closed-solid test and clustering are summed over the scene's meshes
/// (a mesh instanced many times is done once); `parse` is the rest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LoadPhases {
    /// Reading the model file (0 for a built-in scene).
    pub read_ms: f64,
    /// Parsing the file (or generating a built-in scene), decoding its
    /// buffers, walking its nodes, placing objects and choosing the up axis.
    pub parse_ms: f64,
    /// Checking positions and indices, dropping degenerate triangles.
    pub validate_ms: f64,
    /// Whether each mesh is a closed solid.
    pub closed_ms: f64,
    /// Cutting meshes into clusters and storing their vertices.
    pub cluster_ms: f64,
}

impl LoadPhases {
    /// Sets `parse_ms` to what of `elapsed` (the load after reading) the
    /// measured phases do not account for.
    pub(super) fn parse_is_the_rest_of(&mut self, elapsed: Duration) {
        let measured = self.validate_ms + self.closed_ms + self.cluster_ms;
        self.parse_ms = (ms(elapsed) - measured).max(0.0);
    }
}

/// What `work` returns, and the milliseconds it took.
pub(super) fn timed<T>(work: impl FnOnce() -> T) -> (T, f64) {
    let started = Instant::now();
    let result = work();
    (result, ms(started.elapsed()))
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
