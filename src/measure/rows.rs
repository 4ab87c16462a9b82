//! The rows the result files hold: one per mode and frame (frames.csv),
//! one per object a mode got wrong in a frame (missed.csv).

use serde::ser::SerializeStruct;
use serde::{Deserialize, Serialize, Serializer};

use crate::cull::TraversalStats;

/// One row of frames.csv: one mode, one frame. Columns are in field order,
/// with the mode's counters ([`TraversalStats::COUNTERS`]) after the drawing
/// counters. Read by name, so files with fewer counters still read.
#[derive(Clone, Debug, PartialEq, Deserialize)]
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
    /// updates (coherent culling's ternary tree). 0 in static scenes and in files written before the
    /// column existed.
    #[serde(default)]
    pub maintenance_ms: f64,
    /// GPU time between the frame's first and last command (timestamp
    /// queries); empty where the adapter has none.
    pub gpu_ms: Option<f64>,
    pub objects_drawn: u64,
    pub triangles_drawn: u64,
    /// Occlusion queries issued.
    pub queries: u64,
    /// GPU→CPU round trips for query results.
    pub query_batches: u64,
    /// What the mode counted: nodes visited and culled, queries skipped and
    /// delayed, ... (a column each).
    #[serde(flatten)]
    pub traversal: TraversalStats,
    /// Time spent waiting for query results (within frame_ms).
    pub query_wait_ms: f64,
    /// GPU time spent rasterising query boxes (within gpu_ms); empty without
    /// timestamp queries or without queries.
    pub query_gpu_ms: Option<f64>,
    /// Part of query_gpu_ms spent building a depth pyramid to test boxes
    /// against (two-phase culling); empty for other modes, without timestamp queries, and
    /// in files written before the column existed.
    #[serde(default)]
    pub pyramid_gpu_ms: Option<f64>,
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
    /// For a mode that runs others (`auto`), the one that drew the frame;
    /// empty for other modes and in files written before the column
    /// existed.
    #[serde(default)]
    pub strategy: Option<String>,
    /// With `strategy`: whether it ran to be measured (a probe) rather than
    /// as the cheapest.
    #[serde(default)]
    pub probe: Option<bool>,
    /// Where the camera stood (world units, the scene's axes as loaded)
    /// and the unit direction it looked along, so that a frame's figures
    /// can be put on the path (`scripts/auto-trace` reads them for
    /// `auto`'s replay); empty in files written before the columns
    /// existed.
    #[serde(default)]
    pub eye_x: Option<f64>,
    #[serde(default)]
    pub eye_y: Option<f64>,
    #[serde(default)]
    pub eye_z: Option<f64>,
    #[serde(default)]
    pub forward_x: Option<f64>,
    #[serde(default)]
    pub forward_y: Option<f64>,
    #[serde(default)]
    pub forward_z: Option<f64>,
}

/// Flat, a column per field and per counter: CSV has no nesting (and the
/// csv crate cannot write serde's `flatten`).
impl Serialize for FrameStats {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut row = serializer.serialize_struct("FrameStats", 25 + TraversalStats::COUNTERS.len())?;
        row.serialize_field("mode", &self.mode)?;
        row.serialize_field("frame", &self.frame)?;
        row.serialize_field("frame_ms", &self.frame_ms)?;
        row.serialize_field("cpu_ms", &self.cpu_ms)?;
        row.serialize_field("maintenance_ms", &self.maintenance_ms)?;
        row.serialize_field("gpu_ms", &self.gpu_ms)?;
        row.serialize_field("objects_drawn", &self.objects_drawn)?;
        row.serialize_field("triangles_drawn", &self.triangles_drawn)?;
        row.serialize_field("queries", &self.queries)?;
        row.serialize_field("query_batches", &self.query_batches)?;
        for (name, count) in TraversalStats::COUNTERS.iter().zip(self.traversal.counts()) {
            row.serialize_field(name, &count)?;
        }
        row.serialize_field("query_wait_ms", &self.query_wait_ms)?;
        row.serialize_field("query_gpu_ms", &self.query_gpu_ms)?;
        row.serialize_field("pyramid_gpu_ms", &self.pyramid_gpu_ms)?;
        row.serialize_field("error_pixels", &self.error_pixels)?;
        row.serialize_field("max_depth_error", &self.max_depth_error)?;
        row.serialize_field("missed_objects", &self.missed_objects)?;
        row.serialize_field("visible_objects", &self.visible_objects)?;
        row.serialize_field("strategy", &self.strategy)?;
        row.serialize_field("probe", &self.probe)?;
        row.serialize_field("eye_x", &self.eye_x)?;
        row.serialize_field("eye_y", &self.eye_y)?;
        row.serialize_field("eye_z", &self.eye_z)?;
        row.serialize_field("forward_x", &self.forward_x)?;
        row.serialize_field("forward_y", &self.forward_y)?;
        row.serialize_field("forward_z", &self.forward_z)?;
        row.end()
    }
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

/// What a run's rows may hold at most: its frame's pixels (wrong pixels)
/// and its scene's objects (drawn, visible, missed) and triangles (drawn).
#[derive(Clone, Copy, Debug)]
pub struct RowLimits {
    pub pixels: u64,
    pub objects: u64,
    pub triangles: u64,
}

/// The longest time a row may hold, in milliseconds: no frame takes a day,
/// and a time beyond it is no measurement (1e308 ms would also overflow
/// the statistics' sums into an infinite mean).
const LONGEST_MS: f64 = 86_400_000.0;

impl FrameStats {
    /// What in this row no run can have measured, if anything: a time that
    /// is not a number from 0 to a day (NaN, infinite, negative, 1e308),
    /// a depth error outside depth's 0 to 1, more wrong pixels than the
    /// frame has, more objects or triangles than the scene has, more
    /// objects missed than the frame shows, a camera that is not finite
    /// (no path has one). frames.csv is read back by `compare` and
    /// `merge`, and a value like these would pass their verdicts as
    /// "better" or "within noise", or put a frame nowhere on the path.
    pub fn implausible(&self, limits: RowLimits) -> Option<String> {
        let measures = [
            ("frame_ms", Some(self.frame_ms), LONGEST_MS),
            ("cpu_ms", Some(self.cpu_ms), LONGEST_MS),
            ("maintenance_ms", Some(self.maintenance_ms), LONGEST_MS),
            ("gpu_ms", self.gpu_ms, LONGEST_MS),
            ("query_wait_ms", Some(self.query_wait_ms), LONGEST_MS),
            ("query_gpu_ms", self.query_gpu_ms, LONGEST_MS),
            ("pyramid_gpu_ms", self.pyramid_gpu_ms, LONGEST_MS),
            ("max_depth_error", self.max_depth_error, 1.0),
        ];
        let outside = |(column, value, most): (&str, Option<f64>, f64)| {
            value.filter(|v| !(0.0..=most).contains(v)).map(|v| {
                format!(
                    "{column} is {}, not a number from 0 to {}",
                    crate::text::number(v),
                    crate::text::number(most)
                )
            })
        };
        if let Some(fault) = measures.into_iter().find_map(outside) {
            return Some(fault);
        }
        let camera = [
            ("eye_x", self.eye_x),
            ("eye_y", self.eye_y),
            ("eye_z", self.eye_z),
            ("forward_x", self.forward_x),
            ("forward_y", self.forward_y),
            ("forward_z", self.forward_z),
        ];
        let not_finite = |(column, value): (&str, Option<f64>)| {
            value
                .filter(|v| !v.is_finite())
                .map(|v| format!("{column} is {}, not a finite number", crate::text::number(v)))
        };
        if let Some(fault) = camera.into_iter().find_map(not_finite) {
            return Some(fault);
        }
        let counts = [
            ("error_pixels", self.error_pixels, limits.pixels, "pixels in the frame"),
            (
                "objects_drawn",
                Some(self.objects_drawn),
                limits.objects,
                "objects in the scene",
            ),
            (
                "triangles_drawn",
                Some(self.triangles_drawn),
                limits.triangles,
                "triangles in the scene",
            ),
            (
                "visible_objects",
                self.visible_objects,
                limits.objects,
                "objects in the scene",
            ),
            (
                "missed_objects",
                self.missed_objects,
                limits.objects,
                "objects in the scene",
            ),
        ];
        let beyond = counts.into_iter().find_map(|(column, value, most, what)| {
            value
                .filter(|&v| v > most)
                .map(|v| format!("{column} is {v}, more than the {most} {what}"))
        });
        beyond.or_else(|| match (self.missed_objects, self.visible_objects) {
            (Some(missed), Some(visible)) if missed > visible => Some(format!(
                "missed_objects is {missed}, more than the {visible} visible_objects of its frame"
            )),
            _ => None,
        })
    }

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
            queries: 0,
            query_batches: 0,
            traversal: TraversalStats::default(),
            query_wait_ms: 0.0,
            query_gpu_ms: None,
            pyramid_gpu_ms: None,
            error_pixels: None,
            max_depth_error: None,
            missed_objects: None,
            visible_objects: None,
            strategy: None,
            probe: None,
            eye_x: None,
            eye_y: None,
            eye_z: None,
            forward_x: None,
            forward_y: None,
            forward_z: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_counter_is_a_column_written_and_read_back_by_name() {
        let names = TraversalStats::COUNTERS;
        let values: Vec<u64> = (100..).take(names.len()).collect();
        let line = |cells: &[String]| cells.join(",");
        // The counters read by name from a file of their columns alone.
        let numbers: Vec<String> = values.iter().map(u64::to_string).collect();
        let file = format!("{}\n{}\n", names.join(","), line(&numbers));
        let traversal: TraversalStats = csv::Reader::from_reader(file.as_bytes())
            .deserialize()
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(traversal.counts().collect::<Vec<_>>(), values);
        let row = FrameStats {
            traversal,
            gpu_ms: Some(1.5),
            objects_drawn: 3,
            ..FrameStats::blank("vfc")
        };
        let mut writer = csv::Writer::from_writer(Vec::new());
        writer.serialize(&row).unwrap();
        let written = String::from_utf8(writer.into_inner().unwrap()).unwrap();
        let (head, body) = written.split_once('\n').unwrap();
        let columns: Vec<String> = head.split(',').map(String::from).collect();
        let cells: Vec<String> = body.trim_end().split(',').map(String::from).collect();
        for (name, value) in names.iter().zip(&values) {
            let at = columns.iter().position(|c| c == name);
            assert_eq!(
                at.map(|k| cells[k].as_str()),
                Some(value.to_string().as_str()),
                "{name}: {head}"
            );
        }
        let read = |text: &str| -> FrameStats {
            csv::Reader::from_reader(text.as_bytes())
                .deserialize()
                .next()
                .unwrap()
                .unwrap()
        };
        assert_eq!(read(&written), row);
        // A file written before a counter existed still reads, as 0.
        let last = columns.iter().position(|c| c == names[names.len() - 1]).unwrap();
        let without = |v: &[String]| line(&[&v[..last], &v[last + 1..]].concat());
        let older = read(&format!("{}\n{}\n", without(&columns), without(&cells)));
        assert_eq!(older.traversal.counts().last(), Some(0));
        assert_eq!(older.traversal.counts().next(), Some(values[0]));
    }
}
