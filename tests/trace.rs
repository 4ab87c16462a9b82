//! `bench --trace FILE`: the run's timeline as Trace Event JSON, read back
//! event by event and held against the run's frames.csv, on every backend,
//! on a built-in scene and a model file, and without timestamps.

mod common;

use std::collections::BTreeMap;

use common::{occlu, own_stderr};
use occlu::measure::FrameStats;
use serde_json::Value;

/// A slice of the trace, in microseconds.
#[derive(Clone, Debug)]
struct Slice {
    name: String,
    pid: u64,
    tid: u64,
    start: f64,
    end: f64,
}

const CPU: u64 = 1;
const GPU: u64 = 2;
/// Half a nanosecond, in microseconds: the trace holds whole nanoseconds.
const EPS: f64 = 5e-4;

impl Slice {
    fn within(&self, outer: &Slice) -> bool {
        self.start >= outer.start - EPS && self.end <= outer.end + EPS
    }
    fn dur(&self) -> f64 {
        self.end - self.start
    }
}

/// Checks every event of `trace` and, per mode and frame of `rows`, the
/// slices of its frame: each track's parts lie in the frame, one after the
/// other, and add up to at most its `frame_ms`.
fn check_trace(trace: &Value, rows: &[FrameStats], timestamps: bool) {
    let events = trace["traceEvents"].as_array().expect("traceEvents is a list");
    let mut modes: BTreeMap<u64, String> = BTreeMap::new();
    let mut slices = Vec::new();
    for e in events {
        let name = e["name"].as_str().filter(|n| !n.is_empty()).expect("a name");
        let pid = e["pid"].as_u64().expect("a process id");
        match e["ph"].as_str() {
            Some("M") => {
                assert!(e["args"].is_object(), "metadata has args: {e}");
                match name {
                    "process_name" => {
                        modes.insert(pid, e["args"]["name"].as_str().expect("a mode").to_string());
                    }
                    "thread_name" => {
                        let tid = e["tid"].as_u64().expect("a thread id");
                        let want = if tid == CPU { "CPU" } else { "GPU" };
                        assert_eq!(e["args"]["name"], want, "{e}");
                        assert!(tid == CPU || timestamps, "a GPU track without timestamps: {e}");
                    }
                    "process_sort_index" => assert!(e["args"]["sort_index"].is_u64(), "{e}"),
                    other => panic!("unknown metadata {other}"),
                }
            }
            Some("X") => {
                let number = |key: &str| {
                    let v = e[key].as_f64().unwrap_or_else(|| panic!("{key} is a number: {e}"));
                    assert!(v.is_finite() && v >= 0.0, "{key} {v}: {e}");
                    v
                };
                let (ts, dur) = (number("ts"), number("dur"));
                let tid = e["tid"].as_u64().expect("a thread id");
                assert!(tid == CPU || tid == GPU, "{e}");
                slices.push(Slice {
                    name: name.to_string(),
                    pid,
                    tid,
                    start: ts,
                    end: ts + dur,
                });
            }
            other => panic!("unexpected phase {other:?}: {e}"),
        }
    }
    let row_modes: std::collections::BTreeSet<&str> = rows.iter().map(|r| r.mode.as_str()).collect();
    assert_eq!(
        modes
            .values()
            .map(String::as_str)
            .collect::<std::collections::BTreeSet<_>>(),
        row_modes,
        "a process per mode"
    );
    assert_eq!(trace["otherData"]["timestamps"], timestamps);
    if !timestamps {
        let gpu = trace["otherData"]["gpu"].as_str().unwrap();
        assert!(gpu.contains("CPU spans only"), "{gpu}");
    }

    let pid_of: BTreeMap<&str, u64> = modes.iter().map(|(&pid, m)| (m.as_str(), pid)).collect();
    let mut claimed = vec![false; slices.len()];
    for row in rows {
        let pid = pid_of[row.mode.as_str()];
        let frame_name = format!("frame {}", row.frame);
        let frames: Vec<&Slice> = slices
            .iter()
            .filter(|s| s.pid == pid && s.tid == CPU && s.name == frame_name)
            .collect();
        let [frame] = frames[..] else {
            panic!("{} {frame_name}: {} slices", row.mode, frames.len())
        };
        assert!(
            (frame.dur() - row.frame_ms * 1e3).abs() < 2.0 * EPS,
            "{} {frame_name} lasts {} µs, frames.csv says {} ms",
            row.mode,
            frame.dur(),
            row.frame_ms
        );
        let inside = |tid: u64, outer: &Slice| -> Vec<(usize, &Slice)> {
            slices
                .iter()
                .enumerate()
                .filter(|(_, s)| s.pid == pid && s.tid == tid && !s.name.starts_with("frame ") && s.within(outer))
                .collect()
        };
        let parts = |list: &[(usize, &Slice)], outer: &Slice| {
            let mut parts: Vec<&Slice> = list.iter().map(|&(_, s)| s).collect();
            parts.sort_by(|a, b| a.start.total_cmp(&b.start));
            for pair in parts.windows(2) {
                assert!(pair[0].end <= pair[1].start + EPS, "{}: overlapping {pair:?}", row.mode);
            }
            let sum: f64 = parts.iter().map(|s| s.dur()).sum();
            assert!(
                sum <= outer.dur() + EPS,
                "{} {frame_name}: parts add up to {sum} µs of {}",
                row.mode,
                outer.dur()
            );
            assert!(sum <= row.frame_ms * 1e3 + EPS);
            sum
        };
        let cpu = inside(CPU, frame);
        parts(&cpu, frame);
        let waits = cpu.iter().filter(|(_, s)| s.name == "wait for results").count() as u64;
        assert_eq!(
            waits, row.query_batches,
            "{} {frame_name}: a wait for each round trip",
            row.mode
        );
        for &(i, _) in &cpu {
            claimed[i] = true;
        }
        claimed[slices.iter().position(|s| std::ptr::eq(s, frame)).unwrap()] = true;

        let gpu_frames: Vec<(usize, &Slice)> = inside(GPU, frame)
            .into_iter()
            .filter(|(_, s)| s.name == format!("GPU {frame_name}"))
            .collect();
        if !timestamps {
            assert!(gpu_frames.is_empty() && row.gpu_ms.is_none());
            continue;
        }
        let [(g, gpu_frame)] = gpu_frames[..] else {
            panic!("{} {frame_name}: {} GPU frames", row.mode, gpu_frames.len())
        };
        claimed[g] = true;
        assert!(
            gpu_frame.dur() <= row.gpu_ms.unwrap() * 1e3 + EPS,
            "{gpu_frame:?} {row:?}"
        );
        let on_gpu: Vec<(usize, &Slice)> = inside(GPU, gpu_frame)
            .into_iter()
            .filter(|(_, s)| !s.name.starts_with("GPU frame"))
            .collect();
        let (pyramids, tops): (Vec<_>, Vec<_>) = on_gpu.iter().partition(|(_, s)| s.name == "pyramid");
        parts(&tops, gpu_frame);
        for &(i, s) in on_gpu.iter() {
            assert!(["box tests", "drawing", "pyramid"].contains(&s.name.as_str()), "{s:?}");
            claimed[i] = true;
        }
        for (_, p) in &pyramids {
            assert!(
                tops.iter().any(|(_, t)| t.name == "box tests" && p.within(t)),
                "{p:?} outside box tests"
            );
        }
        let tests: f64 = tops
            .iter()
            .filter(|(_, s)| s.name == "box tests")
            .map(|(_, s)| s.dur())
            .sum();
        let query_gpu_us = row.query_gpu_ms.unwrap_or(0.0) * 1e3;
        assert!(
            tests <= query_gpu_us + 1.0,
            "{} {frame_name}: box tests {tests} µs, query_gpu_ms {query_gpu_us} µs",
            row.mode
        );
    }
    let strays: Vec<&Slice> = slices
        .iter()
        .zip(&claimed)
        .filter(|(_, c)| !**c)
        .map(|(s, _)| s)
        .collect();
    assert!(strays.is_empty(), "slices outside every frame: {strays:?}");
}

fn read_trace(path: &std::path::Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).expect("the trace is JSON")
}

#[test]
fn a_trace_holds_every_frame_of_every_mode_and_its_parts_within_it() {
    let dir = tempfile::tempdir().unwrap();
    let town = common::write(dir.path(), "town.obj", common::boxes_obj(&common::town(false)));
    let town = town.to_str().unwrap();
    let scenes: [&[&str]; 2] = [&["--scene", "city:blocks=1", "--movers", "4"], &[town]];
    for backend in common::backends() {
        for scene in scenes {
            let out = dir.path().join(format!("run-{backend}"));
            let trace = dir.path().join(format!("trace-{backend}.json"));
            let mut args = vec!["bench", "--backend", &backend, "--quiet"];
            args.extend_from_slice(scene);
            let (out_s, trace_s) = (out.to_str().unwrap(), trace.to_str().unwrap());
            args.extend_from_slice(&[
                "--modes",
                "vfc,sq,chc,roc,hiz,swr,auto",
                "--frames",
                "3",
                "--warmup",
                "1",
                "--resolution",
                "96x72",
                "--out",
                out_s,
                "--trace",
                trace_s,
            ]);
            let run = occlu(&args);
            assert!(run.status.success(), "{backend} {scene:?}: {:?}", own_stderr(&run));
            let (summary, rows) = occlu::report::read_results(&out).unwrap();
            assert_eq!(rows.len(), 3 * summary.modes.len());
            check_trace(&read_trace(&trace), &rows, summary.adapter.timestamps);
        }
    }
}

#[test]
fn without_timestamps_a_trace_holds_the_cpu_alone_and_says_so() {
    let mut gpu = common::gpus().remove(0);
    gpu.timestamps = false;
    gpu.adapter.timestamps = false;
    let (scene, hierarchy, path) = common::small_city(3);
    let params = occlu::cull::ModeParams::default();
    let mut cullers: Vec<Box<dyn occlu::cull::Culler>> = ["vfc", "sq", "roc"]
        .iter()
        .map(|m| occlu::cull::create(m, &scene, &params).unwrap())
        .collect();
    let output = common::run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, common::SMALL);
    let trace = occlu::report::trace_json(&gpu.adapter, "three frames", &output.rows, &output.timelines);
    let trace: Value = serde_json::from_str(&trace).unwrap();
    check_trace(&trace, &output.rows, false);
}
