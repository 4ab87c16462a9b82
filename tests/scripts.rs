//! The repository's scripts, run as a user runs them.

use std::path::Path;
use std::process::Command;

mod common;

const HEADER: &str = "mode,frame,frame_ms,objects_drawn,triangles_drawn,nodes_visited,nodes_culled_frustum,nodes_culled_occlusion,queries,query_batches,queries_skipped,queries_delayed,nodes_culled_adaptive,nodes_past_budget,error_pixels,missed_objects,visible_objects";

/// A result folder whose frames.csv holds `rows` after the header.
fn results(dir: &Path, name: &str, rows: &[&str]) -> std::path::PathBuf {
    let folder = dir.join(name);
    std::fs::create_dir(&folder).unwrap();
    common::write(&folder, "frames.csv", format!("{HEADER}\n{}\n", rows.join("\n")));
    folder
}

fn same_counters(folders: &[&Path]) -> (i32, String) {
    same_counters_of(&[], folders)
}

fn same_counters_of(flags: &[&str], folders: &[&Path]) -> (i32, String) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/same-counters");
    let out = Command::new(script).args(flags).args(folders).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap(), text)
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
