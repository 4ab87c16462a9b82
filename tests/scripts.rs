//! The repository's scripts, run as a user runs them.

use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

mod common;

const HEADER: &str = "mode,frame,frame_ms,objects_drawn,triangles_drawn,nodes_visited,nodes_culled_frustum,nodes_culled_occlusion,queries,query_batches,queries_skipped,queries_delayed,nodes_culled_adaptive,nodes_past_budget,error_pixels,missed_objects,visible_objects";

/// A result folder whose frames.csv holds `rows` after the header.
fn results(dir: &Path, name: &str, rows: &[&str]) -> std::path::PathBuf {
    let frames = format!("{HEADER}\n{}\n", rows.join("\n"));
    folder_of(dir, name, &[("frames.csv", &frames)])
}

fn same_counters(folders: &[&Path]) -> (i32, String) {
    same_counters_of(&[], folders)
}

fn same_counters_of(flags: &[&str], folders: &[&Path]) -> (i32, String) {
    let args: Vec<&OsStr> = flags
        .iter()
        .map(OsStr::new)
        .chain(folders.iter().map(|f| f.as_os_str()))
        .collect();
    let (code, out, err) = script("same-counters", &args);
    (code, out + &err)
}

/// Runs `scripts/NAME` with `args`: its exit status, standard output and
/// standard error.
fn script(name: &str, args: &[&OsStr]) -> (i32, String, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts").join(name);
    let out = Command::new(path).args(args).output().unwrap();
    let text = |bytes: &[u8]| String::from_utf8_lossy(bytes).to_string();
    (out.status.code().unwrap(), text(&out.stdout), text(&out.stderr))
}

#[test]
fn same_counters_passes_equal_counters_whatever_the_times_and_names_the_first_difference() {
    let dir = tempfile::tempdir().unwrap();
    let before = results(
        dir.path(),
        "before",
        &[
            "vfc,0,5.0,10,100,7,2,0,0,0,0,0,0,0,0,0,9",
            "vfc,1,5.0,11,110,7,2,0,0,0,0,0,0,0,0,0,9",
            "ac,0,3.0,4,40,7,2,3,3,1,0,0,0,0,5,1,9",
            "ac[threshold=50],0,3.0,4,40,7,2,3,3,1,0,0,0,0,5,1,9",
            "swr,0,3.0,4,40,7,2,3,0,0,0,0,0,0,5,1,9",
        ],
    );
    // Other times, and ac and swr (which decide by time) drawing otherwise.
    let retimed = results(
        dir.path(),
        "retimed",
        &[
            "vfc,0,9.0,10,100,7,2,0,0,0,0,0,0,0,0,0,9",
            "vfc,1,1.0,11,110,7,2,0,0,0,0,0,0,0,0,0,9",
            "ac,0,3.0,5,50,7,2,3,3,1,0,0,0,0,5,1,9",
            "ac[threshold=50],0,3.0,5,50,7,2,3,3,1,0,0,4,0,5,1,9",
            "swr,0,3.0,6,60,7,2,0,0,0,0,0,0,0,5,1,9",
        ],
    );
    let (code, text) = same_counters(&[&before, &before]);
    assert_eq!(code, 0, "a folder against itself: {text}");
    let (code, text) = same_counters(&[&before, &retimed]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("vfc      2 frames, every counter identical"), "{text}");
    assert!(!text.contains("ac"), "ac and its sweep are left out: {text}");
    assert!(!text.contains("swr"), "swr is left out: {text}");
    let (code, text) = same_counters_of(&["--modes", "ac"], &[&before, &retimed]);
    assert_eq!(code, 1, "{text}");
    assert!(
        text.contains("ac[threshold=50] 1 of 1 frames differ (first: frame 0: objects_drawn 4 -> 5)"),
        "{text}"
    );
    let changed = results(
        dir.path(),
        "changed",
        &[
            "vfc,0,5.0,10,100,7,2,0,0,0,0,0,0,0,0,0,9",
            "vfc,1,5.0,11,111,7,2,0,0,0,0,0,0,0,0,0,9",
        ],
    );
    let (code, text) = same_counters(&[&before, &changed]);
    assert_eq!(code, 1, "{text}");
    assert!(
        text.contains("vfc      1 of 2 frames differ (first: frame 1: triangles_drawn 110 -> 111)"),
        "{text}"
    );
    let short = results(dir.path(), "short", &["vfc,0,5.0,10,100,7,2,0,0,0,0,0,0,0,0,0,9"]);
    let (code, text) = same_counters(&[&before, &short]);
    assert_eq!(code, 1, "{text}");
    assert!(text.contains("frame 1 only before"), "{text}");
    let (code, text) = same_counters(&[&before, &dir.path().join("absent")]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("absent/frames.csv: no such file"), "{text}");
}

/// `scripts/auto-trace` of `folder` into `trace`: its exit status and
/// standard error.
fn auto_trace(folder: &Path, trace: &Path) -> (i32, String) {
    let (code, out, err) = script(
        "auto-trace",
        &[folder.as_os_str(), OsStr::new("a test run"), trace.as_os_str()],
    );
    assert_eq!(out, "", "it writes the trace, not standard output");
    (code, err)
}

/// A folder `name` in `dir` holding `files` (name, contents).
fn folder_of(dir: &Path, name: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
    let folder = dir.join(name);
    std::fs::create_dir(&folder).unwrap();
    for (file, contents) in files {
        common::write(&folder, file, contents);
    }
    folder
}

/// A result folder as a bench writes it for auto-trace: a summary.json
/// holding `summary`, and a frames.csv of `rows` (mode, frame, frame_ms,
/// triangles_drawn, then where the camera stood and looked).
fn traced_run(dir: &Path, name: &str, summary: &str, rows: &[&str]) -> std::path::PathBuf {
    let header = "mode,frame,frame_ms,triangles_drawn,eye_x,eye_y,eye_z,forward_x,forward_y,forward_z";
    let frames = format!("{header}\n{}\n", rows.join("\n"));
    folder_of(dir, name, &[("frames.csv", &frames), ("summary.json", summary)])
}

/// A summary.json's scene, as a bench writes it (pretty, each number on a
/// line of its own, as serde_json prints them): bounds 3 × 4 × 12, a
/// diagonal of 13.
const SUMMARY: &str = "{\n  \"scene\": {\n    \"bounds_min\": [\n      -1,\n      0.5,\n      -1.2e1\n    ],\n    \"bounds_max\": [\n      2,\n      4.5,\n      0\n    ]\n  }\n}\n";

/// [`SUMMARY`] with `swr` among its modes, with `rests` as its parameter
/// (pretty, as a bench writes it).
fn summary_with_swr(rests: bool) -> String {
    let mode = format!(
        "  \"modes\": [\n    {{\n      \"name\": \"swr\",\n      \"conservative\": true,\n      \"parameters\": {{\n        \"layers\": 4,\n        \"rests\": {rests},\n        \"threads\": 0\n      }},\n      \"frames\": 1\n    }}\n  ],\n"
    );
    SUMMARY.replacen("{\n", &format!("{{\n{mode}"), 1)
}

#[test]
fn auto_trace_takes_swr_only_from_a_run_whose_buffer_never_rested() {
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace.csv");
    let rows = ["vfc,0,5.0,100,1,2,3,0,0,-1", "swr,0,3.0,40,1,2,3,0,0,-1"];
    let header = "frame,eye_x,eye_y,eye_z,forward_x,forward_y,forward_z,vfc_ms,vfc_triangles";
    let rested = "auto-trace: swr left out: its buffer rested in this run (record it with --param swr.rests=false)\n";
    for (rests, expected, note) in [
        (
            false,
            format!("{header},swr_ms,swr_triangles\n0,1,2,3,0,0,-1,5.000,100,3.000,40\n"),
            "",
        ),
        (true, format!("{header}\n0,1,2,3,0,0,-1,5.000,100\n"), rested),
    ] {
        let run = traced_run(dir.path(), &format!("rests-{rests}"), &summary_with_swr(rests), &rows);
        let (code, err) = auto_trace(&run, &trace);
        assert_eq!(code, 0, "{err}");
        assert_eq!(err, note, "swr.rests={rests}");
        let text = std::fs::read_to_string(&trace).unwrap();
        assert_eq!(
            text.lines().skip(2).collect::<Vec<_>>().join("\n") + "\n",
            expected,
            "swr.rests={rests}"
        );
    }
}

#[test]
fn auto_trace_keeps_the_replayed_candidates_and_the_camera_frame_by_frame_and_refuses_a_run_it_cannot_trace() {
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace.csv");
    // Interleaved as a bench writes them; swr, auto and a sweep left out.
    let run = traced_run(
        dir.path(),
        "run",
        SUMMARY,
        &[
            "roc,0,4.25,30,1,2,3,6.9e-18,-0.0,-1",
            "vfc,0,5.0,100,1,2,3,6.9e-18,-0.0,-1",
            "swr,0,3.0,40,1,2,3,0,0,-1",
            "auto,0,4.5,30,1,2,3,0,0,-1",
            "vfc,1,6.0,110,1.5,2,3,0.6,0,-0.8",
            "roc,1,4.125,41,1.5,2,3,0.6,0,-0.8",
            "roc[start=2],1,4.0,30,1.5,2,3,0.6,0,-0.8",
        ],
    );
    let (code, err) = auto_trace(&run, &trace);
    assert_eq!(code, 0, "{err}");
    let expected = "# a test run\n# diagonal 13\nframe,eye_x,eye_y,eye_z,forward_x,forward_y,forward_z,vfc_ms,vfc_triangles,roc_ms,roc_triangles\n0,1,2,3,6.9e-18,-0.0,-1,5.000,100,4.250,30\n1,1.5,2,3,0.6,0,-0.8,6.000,110,4.125,41\n";
    assert_eq!(std::fs::read_to_string(&trace).unwrap(), expected);
    // Runs it cannot trace leave the trace as it was.
    let vfc = |frame: u32| format!("vfc,{frame},5.0,100,1,2,3,0,0,-1");
    let refused = [
        (
            "no-vfc",
            SUMMARY,
            vec!["roc,0,4.25,30,1,2,3,0,0,-1".to_string()],
            "no vfc",
        ),
        (
            "gap",
            SUMMARY,
            vec![vfc(0), vfc(1), "roc,1,4.0,30,1,2,3,0,0,-1".into()],
            "no frame 0 of roc",
        ),
        ("twice", SUMMARY, vec![vfc(0), vfc(0)], "frame 0 of vfc twice"),
        (
            "zero",
            SUMMARY,
            vec![vfc(0), "roc,0,0,30,1,2,3,0,0,-1".into()],
            "frame_ms above 0",
        ),
        ("short", SUMMARY, vec![vfc(0), "roc,1,4.0,3".into()], "has 4 fields"),
        (
            "camera",
            SUMMARY,
            vec!["vfc,0,5.0,100,1,2,NaN,0,0,-1".into()],
            "eye_z must be a number",
        ),
        (
            "bounds",
            "{\"scene\": {}}",
            vec![vfc(0)],
            "summary.json: no scene bounds_min",
        ),
        (
            "flat",
            "{\"bounds_min\": [0, 0], \"bounds_max\": [1, 1, 1]}",
            vec![vfc(0)],
            "scene bounds_min is not three numbers",
        ),
    ];
    for (name, summary, rows, why) in refused {
        let rows: Vec<&str> = rows.iter().map(String::as_str).collect();
        let (code, err) = auto_trace(&traced_run(dir.path(), name, summary, &rows), &trace);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(why), "{name}: {err}");
        assert_eq!(std::fs::read_to_string(&trace).unwrap(), expected, "{name}");
    }
    // A run of an occlu that wrote no camera, and folders that are no run.
    let old = format!("{HEADER}\nvfc,0,5.0,10,100,7,2,0,0,0,0,0,0,0,0,0,9\n");
    let not_runs = [
        (
            "old",
            vec![("frames.csv", old.as_str()), ("summary.json", SUMMARY)],
            "no eye_x column",
        ),
        (
            "other",
            vec![("frames.csv", "a,b\n1,2\n"), ("summary.json", SUMMARY)],
            "not a frames.csv",
        ),
        (
            "unsummed",
            vec![("frames.csv", "a,b\n1,2\n")],
            "summary.json: no such file",
        ),
        ("absent", vec![], "absent/frames.csv: no such file"),
    ];
    for (name, files, why) in not_runs {
        let folder = match files.is_empty() {
            true => dir.path().join(name),
            false => folder_of(dir.path(), name, &files),
        };
        let (code, err) = auto_trace(&folder, &trace);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(why), "{name}: {err}");
        assert_eq!(std::fs::read_to_string(&trace).unwrap(), expected, "{name}");
    }
    let (code, _, err) = script("auto-trace", &[run.as_os_str()]);
    assert_eq!(code, 2);
    assert!(err.contains("usage"), "{err}");
    assert_eq!(std::fs::read_to_string(&trace).unwrap(), expected);
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        !left.iter().any(|n| n.to_string_lossy().starts_with("trace.csv.")),
        "no temporary file left: {left:?}"
    );
}
