//! `bench --trace FILE`: the run's timeline in the Trace Event format, the
//! JSON that Perfetto (ui.perfetto.dev) and `chrome://tracing` open.
//!
//! Each mode is a process with two tracks: `CPU`, where each recorded frame
//! is a slice (`frame N`, as long as its `frame_ms`) holding what the CPU
//! did in it (refit, culling, commands, waits for results, the wait for the
//! GPU), and `GPU`, where timestamps exist, where the frame's GPU work is a
//! slice holding its box tests (and in them a depth pyramid's build) and its drawing.
//! How the GPU's clock is placed on the CPU's is in the file's metadata
//! (`otherData`), with the adapter; without timestamps the GPU tracks are
//! absent and the metadata says so.

use serde::Serialize;
use serde_json::json;

use crate::gpu::AdapterReport;
use crate::measure::{FrameStats, FrameTimeline, Stretch};

const CPU_TRACK: u32 = 1;
const GPU_TRACK: u32 = 2;

/// One event of the file: a complete slice (`X`) or metadata (`M`).
#[derive(Serialize)]
struct Event {
    name: String,
    ph: &'static str,
    pid: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    tid: Option<u32>,
    /// Microseconds, to the nanosecond.
    #[serde(skip_serializing_if = "Option::is_none")]
    ts: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    dur: Option<f64>,
    #[serde(skip_serializing_if = "serde_json::Value::is_null")]
    args: serde_json::Value,
}

impl Event {
    fn metadata(name: &str, pid: u32, tid: Option<u32>, args: serde_json::Value) -> Event {
        Event {
            name: name.into(),
            ph: "M",
            pid,
            tid,
            ts: None,
            dur: None,
            args,
        }
    }

    /// A slice from `start_ns` to `end_ns` (whole nanoseconds from the
    /// run's start, so that slices rounded alike nest exactly).
    fn slice(name: String, pid: u32, tid: u32, start_ns: i64, end_ns: i64, args: serde_json::Value) -> Event {
        Event {
            name,
            ph: "X",
            pid,
            tid: Some(tid),
            ts: Some(start_ns as f64 / 1e3),
            dur: Some((end_ns - start_ns) as f64 / 1e3),
            args,
        }
    }
}

/// The trace of a run on `adapter`: `rows` (frames.csv's) and their
/// `timelines`, one for one, frame-major as the run recorded them; `run`
/// says in the metadata what ran (scene, path, frames, size).
pub fn trace_json(adapter: &AdapterReport, run: &str, rows: &[FrameStats], timelines: &[FrameTimeline]) -> String {
    debug_assert_eq!(rows.len(), timelines.len(), "a timeline per row");
    // The modes in the run's order: each frame's rows list them all.
    let mut modes: Vec<&str> = Vec::new();
    for row in rows {
        if !modes.contains(&row.mode.as_str()) {
            modes.push(&row.mode);
        }
    }
    let mut events = Vec::new();
    for (k, mode) in modes.iter().enumerate() {
        let pid = k as u32 + 1;
        events.push(Event::metadata("process_name", pid, None, json!({ "name": mode })));
        events.push(Event::metadata(
            "process_sort_index",
            pid,
            None,
            json!({ "sort_index": pid }),
        ));
        events.push(Event::metadata(
            "thread_name",
            pid,
            Some(CPU_TRACK),
            json!({ "name": "CPU" }),
        ));
        if adapter.timestamps {
            events.push(Event::metadata(
                "thread_name",
                pid,
                Some(GPU_TRACK),
                json!({ "name": "GPU" }),
            ));
        }
    }
    for (row, timeline) in rows.iter().zip(timelines) {
        let pid = modes
            .iter()
            .position(|&m| m == row.mode)
            .expect("every row's mode is listed") as u32
            + 1;
        let start = ns(timeline.start_ms);
        let at = |ms: f64| start + ns(ms);
        let args = json!({
            "frame": row.frame,
            "frame_ms": row.frame_ms,
            "cpu_ms": row.cpu_ms,
            "gpu_ms": row.gpu_ms,
            "triangles_drawn": row.triangles_drawn,
            "queries": row.queries,
            "round_trips": row.query_batches,
        });
        events.push(Event::slice(
            format!("frame {}", row.frame),
            pid,
            CPU_TRACK,
            start,
            at(row.frame_ms),
            args,
        ));
        let stretch = |s: &Stretch, tid| {
            Event::slice(
                s.work.name().into(),
                pid,
                tid,
                at(s.start_ms),
                at(s.end_ms),
                json!(null),
            )
        };
        events.extend(timeline.cpu.iter().map(|s| stretch(s, CPU_TRACK)));
        if let Some(frame) = &timeline.gpu_frame {
            events.push(Event::slice(
                format!("GPU frame {}", row.frame),
                pid,
                GPU_TRACK,
                at(frame.start),
                at(frame.end),
                json!({ "frame": row.frame, "gpu_ms": row.gpu_ms, "query_gpu_ms": row.query_gpu_ms, "pyramid_gpu_ms": row.pyramid_gpu_ms }),
            ));
            events.extend(timeline.gpu.iter().map(|s| stretch(s, GPU_TRACK)));
        }
    }
    let gpu = if adapter.timestamps {
        "GPU tracks from timestamp queries, on the GPU's clock; placed on the CPU's as late as its waits allow (the frame's GPU work ended before the CPU's wait for it returned, each batch of box tests before the wait for its results)"
    } else {
        "no GPU tracks: the adapter has no timestamp queries, so these are CPU spans only"
    };
    let file = json!({
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "otherData": {
            "tool": concat!(env!("CARGO_PKG_NAME"), " ", env!("CARGO_PKG_VERSION")),
            "run": run,
            "adapter": adapter.to_string(),
            "timestamps": adapter.timestamps,
            "cpu": "CPU tracks on the CPU's clock: each frame is as long as its frame_ms in frames.csv; culling is the mode's frame outside GPU operations",
            "gpu": gpu,
        },
    });
    serde_json::to_string(&file).expect("the trace serialises: strings and numbers") + "\n"
}

/// Milliseconds as whole nanoseconds.
fn ns(ms: f64) -> i64 {
    (ms * 1e6).round() as i64
}
