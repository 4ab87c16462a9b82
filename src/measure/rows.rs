//! The rows the result files hold: one per mode and frame (frames.csv),
//! one per object a mode got wrong in a frame (missed.csv).

use serde::{Deserialize, Serialize};

/// One row of frames.csv: one mode, one frame. Columns are in field order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    pub mode: String,
    pub frame: u32,
    /// Wall time from the start of the mode's frame on the CPU until the GPU
    /// finished it.
    pub frame_ms: f64,
    /// Time the mode spent deciding what to draw: its frame minus the time
    /// inside GPU operations.
    pub cpu_ms: f64,
    /// Part of cpu_ms spent keeping a spatial structure current with moved
    /// objects: the refit of the shared hierarchy, or a mode's own tree
    /// updates (chc). 0 in static scenes and in files written before the
    /// column existed.
    #[serde(default)]
    pub maintenance_ms: f64,
    /// GPU time between the frame's first and last command (timestamp
    /// queries); empty where the adapter has none.
    pub gpu_ms: Option<f64>,
    pub objects_drawn: u64,
    pub triangles_drawn: u64,
    pub nodes_visited: u64,
    pub nodes_culled_frustum: u64,
    pub nodes_culled_occlusion: u64,
    /// Occlusion queries issued.
    pub queries: u64,
    /// GPU→CPU round trips for query results.
    pub query_batches: u64,
    /// Queries made unnecessary: by the Occupancy Map (omq), by last
    /// frame's visibility (chc).
    pub queries_skipped: u64,
    /// Queries held back until a nearer overlapping query was answered
    /// (chc); 0 in files written before the column existed.
    #[serde(default)]
    pub queries_delayed: u64,
    /// Visible nodes treated as occluded for their small contribution (ac).
    pub nodes_culled_adaptive: u64,
    /// Nodes only frustum-culled because the culling budget ran out (ac).
    pub nodes_past_budget: u64,
    /// Time spent waiting for query results (within frame_ms).
    pub query_wait_ms: f64,
    /// GPU time spent rasterising query boxes (within gpu_ms); empty without
    /// timestamp queries or without queries.
    pub query_gpu_ms: Option<f64>,
    /// Pixels whose depth differs from the reference; empty with --no-error.
    pub error_pixels: Option<u64>,
    /// The largest |depth − reference depth| of the frame, in reverse-Z
    /// depth (`near / distance`); 0 without wrong pixels, empty with
    /// --no-error (and in files written before the column existed).
    #[serde(default)]
    pub max_depth_error: Option<f64>,
    /// Objects visible in the reference that the mode did not draw.
    pub missed_objects: Option<u64>,
    /// Objects visible in the reference frame (the oracle's draw count).
    pub visible_objects: Option<u64>,
}

/// One row of missed.csv: an object a mode got wrong in one frame, so a
/// user can find it. Written for every object the reference shows that the
/// mode did not draw, and for every object that owns pixels whose depth the
/// mode got wrong.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MissedObject {
    pub mode: String,
    pub frame: u32,
    /// Index of the object in the scene (as `occlu info --json` lists them).
    pub object: u32,
    pub name: String,
    /// Whether the mode drew it (its pixels are wrong all the same).
    pub drawn: bool,
    /// Pixels it owns in the reference whose depth the mode got wrong.
    pub wrong_pixels: u64,
    /// The first of them, row-major from the top left; empty when there is
    /// none (a missed object hidden by a coplanar twin of equal depth).
    pub first_x: Option<u32>,
    pub first_y: Option<u32>,
}

impl FrameStats {
    /// Drawing time: GPU time outside box tests where timestamps exist, else
    /// the frame minus culling CPU time and waits for test results.
    pub fn render_ms(&self) -> f64 {
        match self.gpu_ms {
            Some(gpu) => gpu - self.query_gpu_ms.unwrap_or(0.0),
            None => self.frame_ms - self.cpu_ms - self.query_wait_ms,
        }
    }
}

#[cfg(test)]
impl FrameStats {
    /// A row of `mode` with every counter zero and every optional column
    /// empty, for tests of what reads rows.
    pub(crate) fn blank(mode: &str) -> FrameStats {
        FrameStats {
            mode: mode.into(),
            frame: 0,
            frame_ms: 0.0,
            cpu_ms: 0.0,
            maintenance_ms: 0.0,
            gpu_ms: None,
            objects_drawn: 0,
            triangles_drawn: 0,
            nodes_visited: 0,
            nodes_culled_frustum: 0,
            nodes_culled_occlusion: 0,
            queries: 0,
            query_batches: 0,
            queries_skipped: 0,
            queries_delayed: 0,
            nodes_culled_adaptive: 0,
            nodes_past_budget: 0,
            query_wait_ms: 0.0,
            query_gpu_ms: None,
            error_pixels: None,
            max_depth_error: None,
            missed_objects: None,
            visible_objects: None,
        }
    }
}
