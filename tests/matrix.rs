//! Benchmark matrices as CI runs them: a matrix split by `--shard` runs
//! exactly the runs of the whole, `occlu merge` puts shards and adapters
//! side by side in one report (and refuses what is not one run), and
//! `occlu compare` of merged folders gates as of single runs. The commands
//! are docs/ci/occlu-matrix.yml's, on tiny scenes.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{THREE_OBJECTS_OBJ, TINY_RUN, boxes_obj, occlu, own_stderr, stdout, write};
use glam::DVec3;
use occlu::report::Summary;
use occlu::report::merge::Merged;

/// A camera held at `eye` looking at the city's middle, as path JSON.
fn held_path(eye: [f64; 3]) -> String {
    format!(
        r#"{{"frames": 2, "keyframes": [{{"time": 0, "position": [{}, {}, {}], "target": [0, 1, 0]}}]}}"#,
        eye[0], eye[1], eye[2]
    )
}

/// Two model files × two paths, three modes: four runs.
fn two_by_two(dir: &Path) -> PathBuf {
    let block = |name: &str, min: [f64; 3], max: [f64; 3]| (name.to_string(), DVec3::from(min), DVec3::from(max));
    let town = [
        block("hall", [-5.0, 0.0, -5.0], [5.0, 8.0, 5.0]),
        block("shed", [8.0, 0.0, -3.0], [12.0, 4.0, 3.0]),
        block("tower", [-12.0, 0.0, 6.0], [-8.0, 20.0, 10.0]),
    ];
    let village = [
        block("barn", [-6.0, 0.0, -2.0], [2.0, 5.0, 4.0]),
        block("well", [4.0, 0.0, 4.0], [5.0, 1.0, 5.0]),
    ];
    write(dir, "town.obj", boxes_obj(&town));
    write(dir, "village.obj", boxes_obj(&village));
    write(dir, "street.json", held_path([-30.0, 2.0, -30.0]));
    write(dir, "above.json", held_path([30.0, 40.0, 30.0]));
    write(
        dir,
        "matrix.json",
        r#"{"models": ["town.obj", "village.obj"], "paths": ["street.json", "above.json"],
            "modes": ["dr", "vfc", "oracle"], "warmup": 0, "resolution": "64x48"}"#,
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `occlu bench --config MATRIX --backend B --out OUT EXTRA...`, which must succeed.
fn bench_matrix(matrix: &Path, backend: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["bench", "--config", s(matrix), "--backend", backend, "--out", s(out)];
    args.extend_from_slice(extra);
    let run = occlu(&args);
    assert!(run.status.success(), "{args:?}: {:?}", own_stderr(&run));
    run
}

/// The run folders in `dir`, by name.
fn run_folders(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .filter(|n| !n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// A row's mode, frame, objects and triangles drawn, boxes tested, round
/// trips and wrong pixels.
type Counters = (String, u32, u64, u64, u64, u64, Option<u64>);

/// What a run measured that does not depend on timing, row by row.
fn counters(run: &Path) -> Vec<Counters> {
    csv::Reader::from_path(run.join("frames.csv"))
        .unwrap()
        .deserialize::<occlu::measure::FrameStats>()
        .map(|r| {
            let r = r.unwrap();
            (
                r.mode,
                r.frame,
                r.objects_drawn,
                r.triangles_drawn,
                r.queries,
                r.query_batches,
                r.error_pixels,
            )
        })
        .collect()
}

fn summary(run: &Path) -> Summary {
    serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap()
}

fn merged(dir: &Path) -> Merged {
    serde_json::from_str(&std::fs::read_to_string(dir.join("merged.json")).unwrap()).unwrap()
}

/// Fails with exit 2 and one line of stderr holding every one of `needles`.
fn refused(args: &[&str], needles: &[&str]) {
    let out = occlu(args);
    let lines = own_stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {lines:?}");
    assert_eq!(lines.len(), 1, "{args:?}: one line expected, got {lines:?}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{}' lacks '{n}'", lines[0]);
    }
}

#[test]
fn three_shards_run_exactly_the_runs_of_the_whole_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let matrix = two_by_two(dir.path());
    let backend = &common::backends()[0];
    let whole = dir.path().join("whole");
    bench_matrix(&matrix, backend, &whole, &["--quiet"]);
    assert_eq!(
        run_folders(&whole),
        [
            "01-town-street",
            "02-town-above",
            "03-village-street",
            "04-village-above"
        ]
    );
    let mut sharded: BTreeMap<String, PathBuf> = BTreeMap::new();
    for k in 1..=3 {
        let out = dir.path().join(format!("shard{k}"));
        let run = bench_matrix(&matrix, backend, &out, &["--shard", &format!("{k}/3")]);
        let progress: Vec<String> = own_stderr(&run).into_iter().filter(|l| l.starts_with("run ")).collect();
        assert_eq!(progress.len(), run_folders(&out).len(), "a line per run: {progress:?}");
        for name in run_folders(&out) {
            let earlier = sharded.insert(name.clone(), out.join(&name));
            assert!(earlier.is_none(), "{name} ran on two shards");
        }
    }
    assert_eq!(sharded.keys().cloned().collect::<Vec<_>>(), run_folders(&whole));
    for (name, run) in &sharded {
        assert_eq!(counters(run), counters(&whole.join(name)), "{name}");
        assert_eq!(summary(run).run.as_deref(), Some(name.as_str()));
    }
    assert_eq!(
        run_folders(&dir.path().join("shard1")),
        ["01-town-street", "04-village-above"]
    );

    // A shard with no run says so and writes nothing.
    let idle = dir.path().join("idle");
    let run = bench_matrix(&matrix, backend, &idle, &["--shard", "5/5"]);
    assert!(
        own_stderr(&run)[0].contains("none of the matrix's 4 runs"),
        "{:?}",
        own_stderr(&run)
    );
    assert!(!idle.exists());
    for bad in ["0/3", "4/3", "a/b", "1/0"] {
        refused(
            &["bench", "--config", s(&matrix), "--shard", bad, "--out", s(&idle)],
            &[bad, "K/N"],
        );
    }
    // One run sharded is a matrix of one.
    let one = dir.path().join("one");
    let quick: Vec<&str> = ["bench"]
        .into_iter()
        .chain(TINY_RUN.iter().copied())
        .chain([
            "--resolution",
            "64x48",
            "--modes",
            "vfc",
            "--backend",
            backend,
            "--quiet",
            "--out",
            s(&one),
        ])
        .collect();
    let first: Vec<&str> = quick.iter().copied().chain(["--shard", "1/2"]).collect();
    assert!(occlu(&first).status.success());
    assert_eq!(run_folders(&one), ["01-city-blocks-1-generated"]);
    let second: Vec<&str> = quick.iter().copied().chain(["--shard", "2/2"]).collect();
    assert!(occlu(&second).status.success());
    assert_eq!(
        run_folders(&one),
        ["01-city-blocks-1-generated"],
        "shard 2/2 of one run is empty"
    );
    // A bad run fails every shard before any work, naming it.
    let bad = write(
        dir.path(),
        "bad.json",
        r#"{"scenes": ["city:blocks=1"], "runs": [{"modes": ["vfc"]}, {"modes": ["warp"]}]}"#,
    );
    refused(
        &["bench", "--config", s(&bad), "--shard", "1/2", "--out", s(&idle)],
        &["run 02-city-generated", "unknown mode 'warp'"],
    );
    assert!(!idle.exists());
}

#[test]
fn shards_and_a_gl_run_merge_into_one_report_that_compare_gates() {
    let dir = tempfile::tempdir().unwrap();
    let matrix = two_by_two(dir.path());
    let backends = common::backends();
    // As the workflow: three shards on one runner, the whole matrix on
    // another adapter (GL here) when there is one.
    let mut dirs = Vec::new();
    for k in 1..=3 {
        let out = dir.path().join(format!("shard{k}"));
        bench_matrix(&matrix, &backends[0], &out, &["--shard", &format!("{k}/3"), "--quiet"]);
        dirs.push(out);
    }
    for backend in &backends[1..] {
        let out = dir.path().join(backend);
        bench_matrix(&matrix, backend, &out, &["--quiet"]);
        dirs.push(out);
    }
    let out = dir.path().join("merged");
    let mut args = vec!["merge"];
    args.extend(dirs.iter().map(|d| s(d)));
    args.extend(["--out", s(&out)]);
    let run = occlu(&args);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert_eq!(stdout(&run), report, "merge prints its report");
    let m = merged(&out);
    assert_eq!(m.runs.len(), 4);
    for run in &m.runs {
        let mut kinds: Vec<String> = run.adapters.iter().map(|a| a.backend.to_lowercase()).collect();
        kinds.sort();
        let mut expected = backends.clone();
        expected.sort();
        assert_eq!(kinds, expected, "{}: one column per adapter", run.name);
        assert_eq!((run.resolution.to_string(), run.frames), ("64x48".into(), 2));
        for row in &run.modes {
            assert!(
                row.results.iter().all(Option::is_some),
                "{} ran on every adapter",
                row.mode
            );
        }
        let vfc = run.modes.iter().find(|r| r.mode == "vfc").unwrap();
        assert!(
            vfc.results
                .iter()
                .all(|r| r.as_ref().unwrap().ratio_to_oracle.is_some())
        );
        // Each number as its run's summary.json holds it, to the last bit.
        for (k, adapter) in run.adapters.iter().enumerate() {
            let own = summary(&out.join(&adapter.folder));
            let mean = own.modes.iter().find(|m| m.name == "vfc").unwrap().stats["frame_ms"].mean;
            assert_eq!(
                vfc.results[k].as_ref().unwrap().frame_ms,
                Some(mean),
                "{}",
                adapter.label()
            );
        }
        let chart = run.chart.as_deref().unwrap();
        assert!(out.join(chart).is_file(), "{chart}");
        assert!(report.contains(&format!("({chart})")));
        assert!(run.disagreements.is_empty(), "{:?}", run.disagreements);
        for a in &run.adapters {
            assert!(report.contains(&occlu::text::markdown(&a.label())));
            assert!(out.join(&a.folder).join("frames.csv").is_file());
            assert!(out.join(&a.folder).join("summary.json").is_file());
        }
    }
    assert!(report.contains("| vfc | frame ms (mean) |"));
    assert!(report.contains("|  | × oracle |"));
    // Every counter the cross-check compares is in the table.
    assert!(report.contains("|  | objects |"));

    // The base branch's merge against this one: the same results pass…
    let same = occlu(&["compare", s(&out), s(&out)]);
    assert!(same.status.success(), "{:?}", own_stderr(&same));
    assert!(stdout(&same).contains("01-town-street--"));
    // …and a merge that lacks runs the base had (asked for) fails.
    let partial = dir.path().join("partial");
    refused(
        &["merge", s(&dirs[0]), "--out", s(&partial)],
        &["a partial matrix", "2 of the matrix's 4 runs", "missing: run 02, 03"],
    );
    assert!(
        occlu(&["merge", s(&dirs[0]), "--out", s(&partial), "--allow-partial"])
            .status
            .success()
    );
    let missing = occlu(&["compare", s(&out), s(&partial)]);
    assert_eq!(missing.status.code(), Some(1), "{:?}", own_stderr(&missing));
    assert!(stdout(&missing).contains("MISSING"));
    let lenient = occlu(&["compare", s(&out), s(&partial), "--allow-missing"]);
    assert_eq!(lenient.status.code(), Some(0), "{:?}", own_stderr(&lenient));
    refused(
        &["compare", s(&out), s(&dirs[0].join("01-town-street"))],
        &["is a merged folder", "is not"],
    );
}

/// Copies a run folder with its summary.json edited by `edit` (frames.csv
/// as it was, so the folder still reads as a whole run).
fn edited_copy(from: &Path, to: &Path, edit: impl Fn(&mut serde_json::Value)) {
    std::fs::create_dir_all(to).unwrap();
    std::fs::copy(from.join("frames.csv"), to.join("frames.csv")).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(from.join("summary.json")).unwrap()).unwrap();
    edit(&mut json);
    std::fs::write(to.join("summary.json"), json.to_string()).unwrap();
}

#[test]
fn merge_refuses_what_is_not_one_run_and_flags_counters_one_backend_disagrees_on() {
    let dir = tempfile::tempdir().unwrap();
    let backend = &common::backends()[0];
    // One matrix, run on two machines whose model files differ: the same
    // path, other content.
    let matrix = write(
        dir.path(),
        "m.json",
        r#"{"models": ["model.obj"], "modes": ["dr", "vfc"], "frames": 2, "warmup": 0, "resolution": "64x48"}"#,
    );
    let mut outs = Vec::new();
    for (machine, obj) in [
        ("a", THREE_OBJECTS_OBJ.to_string()),
        ("b", THREE_OBJECTS_OBJ.replace("v 0 0 0", "v 0 0 0.5")),
    ] {
        write(dir.path(), "model.obj", obj);
        let out = dir.path().join(format!("out-{machine}"));
        bench_matrix(&matrix, backend, &out, &["--quiet"]);
        outs.push(out);
    }
    assert_ne!(
        summary(&outs[0].join("01-model-generated")).scene.facts.geometry,
        summary(&outs[1].join("01-model-generated")).scene.facts.geometry
    );
    let merged_out = dir.path().join("merged");
    refused(
        &["merge", s(&outs[0]), s(&outs[1]), "--out", s(&merged_out)],
        &[
            "run 01-model-generated",
            "different scenes",
            "out-a/01-model-generated",
            "out-b/01-model-generated",
        ],
    );
    assert!(!merged_out.exists(), "nothing written");

    // Runs outside a matrix are one run by scene and path: a different
    // resolution is refused; a different result on one adapter is
    // ambiguous; the same folder twice counts once.
    let quick = |out: &Path, resolution: &str| {
        let args: Vec<&str> = ["bench"]
            .into_iter()
            .chain(TINY_RUN.iter().copied())
            .chain(["--modes", "dr,vfc,oracle", "--resolution", resolution])
            .chain(["--backend", backend, "--quiet", "--out", s(out)])
            .collect();
        assert!(occlu(&args).status.success());
    };
    let (small, wide, again) = (
        dir.path().join("small"),
        dir.path().join("wide"),
        dir.path().join("again"),
    );
    quick(&small, "64x48");
    quick(&wide, "96x48");
    quick(&again, "64x48");
    refused(
        &["merge", s(&small), s(&wide), "--out", s(&merged_out)],
        &["different resolutions", "64x48 vs 96x48", "small", "wide"],
    );
    refused(
        &["merge", s(&small), s(&again), "--out", s(&merged_out)],
        &["ambiguous", "small", "again"],
    );
    let twice = occlu(&["merge", s(&small), s(&small), "--out", s(&merged_out)]);
    assert!(twice.status.success(), "{:?}", own_stderr(&twice));
    assert_eq!(merged(&merged_out).runs[0].adapters.len(), 1);

    // Another adapter of the same backend that drew other triangles is
    // flagged, in the report and merged.json, without failing the merge;
    // one of another backend may differ. A summary.json from before the
    // fingerprints (no run, geometry, cameras) still merges.
    // (Merge reads statistics from frames.csv, as compare does.)
    let more_triangles = dir.path().join("more-triangles");
    common::tampered_copy(&small, &more_triangles, &|r| {
        if r.mode == "vfc" {
            r.triangles_drawn += 12;
        }
    });
    let same_backend = dir.path().join("other-gpu");
    edited_copy(&more_triangles, &same_backend, |j| {
        j["adapter"]["name"] = "Other GPU".into();
    });
    // One of that backend at another sub-pixel precision does other work
    // (its box tests' margins): its triangles are not held against the
    // others'.
    let coarse = dir.path().join("coarse-gpu");
    edited_copy(&more_triangles, &coarse, |j| {
        j["adapter"]["name"] = "Coarse GPU".into();
        j["adapter"]["subpixel_bits"] = (j["adapter"]["subpixel_bits"].as_u64().unwrap() - 4).into();
    });
    let other_backend = dir.path().join("other-backend");
    edited_copy(&same_backend, &other_backend, |j| {
        j["adapter"]["backend"] = "Metal".into()
    });
    let old = dir.path().join("old");
    edited_copy(&small, &old, |j| {
        j["adapter"]["name"] = "Old GPU".into();
        j["adapter"]["backend"] = "Dx12".into();
        let summary = j.as_object_mut().unwrap();
        summary.remove("run");
        summary["scene"].as_object_mut().unwrap().remove("geometry");
        summary["path"].as_object_mut().unwrap().remove("cameras");
        summary["error_measured"] = false.into();
    });
    let run = occlu(&[
        "merge",
        s(&small),
        s(&same_backend),
        s(&coarse),
        s(&other_backend),
        s(&old),
        "--out",
        s(&merged_out),
    ]);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let m = merged(&merged_out);
    assert_eq!(m.runs.len(), 1);
    assert_eq!(m.runs[0].adapters.len(), 5);
    let flagged: Vec<(&str, &str, &str)> = m.runs[0]
        .disagreements
        .iter()
        .map(|d| (d.mode.as_str(), d.counter.as_str(), d.backend.as_str()))
        .collect();
    assert_eq!(
        flagged,
        [("vfc", "triangles_drawn", summary(&small).adapter.backend.as_str())]
    );
    let named: Vec<&str> = m.runs[0].disagreements[0]
        .values
        .iter()
        .map(|(a, _)| a.as_str())
        .collect();
    assert!(
        named.contains(&"Other GPU") && !named.contains(&"Coarse GPU"),
        "{named:?}"
    );
    let warnings: Vec<String> = own_stderr(&run)
        .into_iter()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("vfc triangles_drawn differs"));
    let report = std::fs::read_to_string(merged_out.join("report.md")).unwrap();
    assert!(report.contains("vfc triangles\\_drawn differs between"), "{report}");
    assert!(
        report.contains("Wrong pixels not measured on Old GPU (Dx12) (run with --no-error)."),
        "{report}"
    );

    // Input that is no result: one line, exit 2.
    let not_a_run = dir.path().join("empty");
    std::fs::create_dir(&not_a_run).unwrap();
    refused(
        &["merge", s(&not_a_run), "--out", s(&merged_out)],
        &["not a result folder"],
    );
    refused(
        &["merge", s(&dir.path().join("absent")), "--out", s(&merged_out)],
        &["absent"],
    );
    let broken = dir.path().join("broken");
    edited_copy(&small, &broken, |j| *j = serde_json::json!({"schema_version": 1}));
    refused(
        &["merge", s(&broken), "--out", s(&merged_out)],
        &["broken", "not an occlu summary"],
    );
    refused(&["merge", "--out", s(&merged_out)], &["no result folders"]);
}

/// A matrix of `scenes` (JSON list) in `name`, 3 frames at 64x48, vfc and
/// the oracle.
/// A tiny matrix of one run benched in `dir/full` on the first backend:
/// that folder and the run's.
fn matrix_of_one(dir: &Path) -> (PathBuf, PathBuf) {
    let matrix = tiny_matrix(dir, "m.json", r#"["city:blocks=1"]"#);
    let full = dir.join("full");
    bench_matrix(&matrix, &common::backends()[0], &full, &["--quiet"]);
    let run = full.join("01-city-blocks-1-generated");
    (full, run)
}

fn tiny_matrix(dir: &Path, name: &str, scenes: &str) -> PathBuf {
    write(
        dir,
        name,
        format!(
            r#"{{"scenes": {scenes}, "modes": ["vfc", "oracle"], "frames": 3, "warmup": 0, "resolution": "64x48"}}"#
        ),
    )
}

#[test]
fn a_bad_run_fails_every_shard_up_front_and_a_failing_run_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let backend = &common::backends()[0];
    std::fs::create_dir(dir.path().join("adir")).unwrap();
    let out = dir.path().join("out");
    // A built-in scene that does not parse, or a model that is a folder:
    // every shard refuses before any run, so none writes anything.
    let bad_scene = tiny_matrix(dir.path(), "scene.json", r#"["city:blocks=1", "nonesuch"]"#);
    let bad_model = write(dir.path(), "model.json", r#"{"models": ["adir"], "modes": ["vfc"]}"#);
    for shard in ["1/2", "2/2"] {
        let args = [
            "bench",
            "--config",
            s(&bad_scene),
            "--backend",
            backend,
            "--out",
            s(&out),
        ];
        let sharded: Vec<&str> = args.iter().copied().chain(["--shard", shard]).collect();
        refused(&sharded, &["run 02-nonesuch-generated", "unknown scene 'nonesuch'"]);
        assert!(!out.exists(), "shard {shard} wrote nothing");
    }
    refused(
        &["bench", "--config", s(&bad_model), "--out", s(&out)],
        &["run 01-adir-generated", "not a file"],
    );
    assert!(!out.exists());
    // A model that only fails when loaded fails its run, which leaves no
    // run folder (a folder with only a lock reads as a run still going).
    write(dir.path(), "garbage.obj", "garbage\n");
    let garbage = write(
        dir.path(),
        "garbage.json",
        r#"{"models": ["garbage.obj"], "modes": ["vfc"], "frames": 3, "warmup": 0, "resolution": "64x48"}"#,
    );
    refused(
        &[
            "bench",
            "--config",
            s(&garbage),
            "--backend",
            backend,
            "--out",
            s(&out),
            "--quiet",
        ],
        &["garbage.obj"],
    );
    assert!(!out.join("01-garbage-generated").exists());
    // It ends itself, not the matrix: the runs after it run, their table
    // is printed, and the exit status is the failed run's.
    let mixed = write(
        dir.path(),
        "mixed.json",
        r#"{"models": ["garbage.obj"], "scenes": ["city:blocks=1"], "modes": ["vfc"], "frames": 3, "warmup": 0, "resolution": "64x48"}"#,
    );
    let mixed_out = dir.path().join("mixed");
    let run = occlu(&[
        "bench",
        "--config",
        s(&mixed),
        "--backend",
        backend,
        "--out",
        s(&mixed_out),
        "--quiet",
    ]);
    assert_eq!(run.status.code(), Some(2), "{:?}", own_stderr(&run));
    let said = own_stderr(&run);
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(
        said[0].contains("1 of this shard's 2 runs failed (01-garbage-generated") && said[0].contains("garbage.obj"),
        "{said:?}"
    );
    assert_eq!(run_folders(&mixed_out), ["02-city-blocks-1-generated"]);
    assert!(
        stdout(&run).contains("| 02-city-blocks-1-generated |"),
        "{}",
        stdout(&run)
    );
    // A shard with no run prints an empty list for --json.
    let one = tiny_matrix(dir.path(), "one.json", r#"["city:blocks=1"]"#);
    let idle = bench_matrix(&one, backend, &out, &["--shard", "2/2", "--json"]);
    assert_eq!(stdout(&idle), "[]\n");
    // Nor is a matrix past MAX_RUNS planned.
    let scenes: Vec<String> = (0..101).map(|k| format!("\"city:seed={k}\"")).collect();
    let paths: Vec<String> = (0..100).map(|k| format!("\"p{k}.json\"")).collect();
    let huge = write(
        dir.path(),
        "huge.json",
        format!(
            r#"{{"scenes": [{}], "paths": [{}]}}"#,
            scenes.join(","),
            paths.join(",")
        ),
    );
    refused(
        &["bench", "--config", s(&huge), "--out", s(&out)],
        &["10100 runs", "more than the 10000"],
    );
}

#[test]
fn merge_refuses_to_write_over_its_input_or_a_partial_matrix_and_takes_odd_names() {
    let dir = tempfile::tempdir().unwrap();
    let (full, run) = matrix_of_one(dir.path());
    let report = std::fs::read_to_string(run.join("report.md")).unwrap();
    // Named through a folder the merge would make and `..` out of it, too:
    // the system puts it where that leads.
    let through_missing = dir.path().join("missing/../full/01-city-blocks-1-generated");
    for out in [
        &run,
        &run.join("merged"),
        &full,
        &dir.path().to_path_buf(),
        &through_missing,
        &run.join("x/.."),
    ] {
        refused(
            &["merge", s(&run), "--out", s(out)],
            &["write over what it reads", "choose another --out"],
        );
    }
    refused(&["merge", s(&full), "--out", s(&run)], &["write over what it reads"]);
    assert_eq!(std::fs::read_to_string(run.join("report.md")).unwrap(), report);
    assert!(!run.join("merged").exists());

    // A folder of the matrix without a run is a run that failed: refused,
    // named; hidden folders (staging) are passed over.
    let partial = dir.path().join("partial");
    std::fs::create_dir_all(partial.join("02-forest-generated")).unwrap();
    std::fs::create_dir_all(partial.join(".occlu-staging-1")).unwrap();
    let out = dir.path().join("merged");
    let copy = |to: &Path| {
        std::fs::create_dir_all(to).unwrap();
        for f in ["summary.json", "frames.csv"] {
            std::fs::copy(run.join(f), to.join(f)).unwrap();
        }
    };
    copy(&partial.join("01-city-blocks-1-generated"));
    refused(
        &["merge", s(&partial), "--out", s(&out)],
        &["02-forest-generated", "without summary.json"],
    );
    std::fs::remove_dir(partial.join("02-forest-generated")).unwrap();
    // A folder that holds another run is refused as --out, however named.
    for out in [
        partial.join("01-city-blocks-1-generated"),
        dir.path().join("gone/../partial/01-city-blocks-1-generated"),
    ] {
        refused(
            &["merge", s(&run), "--out", s(&out)],
            &["holds a bench run", "choose another --out"],
        );
    }
    assert!(!dir.path().join("gone").exists());
    let merged_ok = occlu(&["merge", s(&partial), "--out", s(&out)]);
    assert!(merged_ok.status.success(), "{:?}", own_stderr(&merged_ok));
    // A link to a folder where the merge writes one (its charts/) is
    // replaced as the folder would be.
    let elsewhere = dir.path().join("elsewhere");
    std::fs::rename(out.join("charts"), &elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("charts")).unwrap();
    let again = occlu(&["merge", s(&partial), "--out", s(&out)]);
    assert!(again.status.success(), "{:?}", own_stderr(&again));
    assert!(out.join("charts").is_dir() && !out.join("charts").is_symlink());
    assert!(stdout(&merged_ok).starts_with("# occlu: merged results\n\n1 run on 1 adapter."));
    // A merged folder given to merge says what it is.
    refused(
        &["merge", s(&out), "--out", s(&dir.path().join("again"))],
        &["a merged folder", "runs/"],
    );

    // A folder whose name is not UTF-8 merges; merged.json names it as
    // best it can.
    use std::os::unix::ffi::OsStrExt as _;
    let odd = dir.path().join(std::ffi::OsStr::from_bytes(b"nu\xff"));
    copy(&odd);
    let odd_out = dir.path().join("odd-merged");
    let merged_odd = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .arg("merge")
        .arg(&odd)
        .args(["--out", s(&odd_out)])
        .output()
        .unwrap();
    assert!(merged_odd.status.success(), "{:?}", own_stderr(&merged_odd));
    assert!(merged(&odd_out).runs[0].adapters[0].merged_from.ends_with("nu\u{fffd}"));

    // The same folder twice, once inside its matrix folder, counts once,
    // even from before summary.json fingerprinted frames.csv.
    let old = dir.path().join("old");
    edited_copy(&run, &old.join("01-city-blocks-1-generated"), |j| {
        j.as_object_mut().unwrap().remove("frames_csv");
    });
    let twice = occlu(&[
        "merge",
        s(&old),
        s(&old.join("01-city-blocks-1-generated")),
        s(&old.join("01-city-blocks-1-generated/../01-city-blocks-1-generated")),
        "--out",
        s(&out),
    ]);
    assert!(twice.status.success(), "{:?}", own_stderr(&twice));
    assert_eq!(merged(&out).runs[0].adapters.len(), 1);
}

#[test]
fn merge_refuses_runs_of_two_matrices_and_names_a_frame_count_that_differs() {
    let dir = tempfile::tempdir().unwrap();
    let backend = &common::backends()[0];
    // Run 01 of a matrix of one and of a matrix of two: the same name, not
    // one run of one matrix.
    let one = tiny_matrix(dir.path(), "one.json", r#"["city:blocks=1"]"#);
    let two = tiny_matrix(dir.path(), "two.json", r#"["city:blocks=1", "city:blocks=1,seed=2"]"#);
    let (a, b, c) = (dir.path().join("a"), dir.path().join("b"), dir.path().join("c"));
    bench_matrix(&one, backend, &a, &["--quiet"]);
    bench_matrix(&two, backend, &b, &["--quiet", "--shard", "1/2"]);
    bench_matrix(&one, backend, &c, &["--quiet", "--frames", "2"]);
    let first = |d: &Path| d.join("01-city-blocks-1-generated");
    assert!(summary(&first(&a)).matrix.is_some());
    let out = dir.path().join("merged");
    refused(
        &["merge", s(&first(&a)), s(&first(&b)), "--out", s(&out)],
        &["different matrices", "a matrix of 1 run", "a matrix of 2 runs"],
    );
    refused(
        &["merge", s(&a), s(&c), "--out", s(&out)],
        &["different frame counts", "3 vs 2"],
    );
    // Nor do runs with other warmup merge into one table.
    let d = dir.path().join("d");
    bench_matrix(&one, backend, &d, &["--quiet", "--warmup", "1"]);
    refused(
        &["merge", s(&a), s(&d), "--out", s(&out)],
        &["different warmup frames", "0 vs 1"],
    );
    assert!(!out.exists());
}

#[test]
fn compare_of_merged_folders_pairs_a_run_that_what_else_was_merged_renamed() {
    let dir = tempfile::tempdir().unwrap();
    let (_, run) = matrix_of_one(dir.path());
    // Two runs outside a matrix of one scene and a path of one name, with
    // other cameras: merged together, each name takes its contents' tag.
    let single_named = |folder: &str, path: &str, cameras: &str| {
        let to = dir.path().join(folder).join("run");
        edited_copy(&run, &to, |j| {
            j["run"] = serde_json::Value::Null;
            j["matrix"] = serde_json::Value::Null;
            j["path"]["source"] = path.into();
            j["path"]["cameras"]["fnv1a"] = cameras.into();
        });
        to
    };
    let single = |folder: &str, cameras: &str| single_named(folder, "path.json", cameras);
    let (first, second) = (single("p1", "00000000000000a1"), single("p2", "00000000000000b2"));
    let (base, new) = (dir.path().join("base"), dir.path().join("new"));
    assert!(occlu(&["merge", s(&first), "--out", s(&base)]).status.success());
    let merged_new = occlu(&["merge", s(&first), s(&second), "--out", s(&new)]);
    assert!(merged_new.status.success(), "{:?}", own_stderr(&merged_new));
    let names: Vec<String> = merged(&new).runs.iter().map(|r| r.name.clone()).collect();
    assert!(names.iter().all(|n| n.contains("path.json #")), "{names:?}");
    assert!(!merged(&base).runs[0].name.contains('#'));
    // The base's run is the new merge's run of the same contents, not
    // missing; the other is the new merge's only.
    let compared = occlu(&["compare", s(&base), s(&new)]);
    assert_eq!(compared.status.code(), Some(0), "{:?}", own_stderr(&compared));
    assert!(!stdout(&compared).contains("MISSING"), "{}", stdout(&compared));
    assert_eq!(
        stdout(&compared).matches("in the new merge only").count(),
        1,
        "{}",
        stdout(&compared)
    );
    // The other way round: the tagged run of those contents pairs with the
    // untagged one, the other is missing.
    let back = occlu(&["compare", s(&new), s(&base)]);
    assert_eq!(back.status.code(), Some(1), "{:?}", own_stderr(&back));
    assert_eq!(stdout(&back).matches("MISSING").count(), 1, "{}", stdout(&back));
    // A run of that name whose contents match neither is missing.
    let other = dir.path().join("other");
    assert!(
        occlu(&["merge", s(&single("p3", "00000000000000c3")), "--out", s(&other)])
            .status
            .success()
    );
    let unmatched = occlu(&["compare", s(&other), s(&new)]);
    assert_eq!(unmatched.status.code(), Some(1), "{:?}", own_stderr(&unmatched));
    assert_eq!(
        stdout(&unmatched).matches("MISSING").count(),
        1,
        "{}",
        stdout(&unmatched)
    );
    // The path of those contents named another way (given as an absolute
    // path in another checkout) is that run too, as merge would take it.
    let elsewhere = dir.path().join("elsewhere");
    let moved = single_named("p4", "/ci/checkout/path.json", "00000000000000a1");
    assert!(occlu(&["merge", s(&moved), "--out", s(&elsewhere)]).status.success());
    let paired = occlu(&["compare", s(&elsewhere), s(&new)]);
    assert_eq!(paired.status.code(), Some(0), "{}", stdout(&paired));
    assert!(!stdout(&paired).contains("MISSING"), "{}", stdout(&paired));
    // A new run that pairs with a base run by name pairs with no other: a
    // base run of its contents under another name is missing, not the
    // same run compared twice.
    let (two, one) = (dir.path().join("two"), dir.path().join("one"));
    let first = single_named("q1", "path.json", "00000000000000a1");
    let second = single_named("q2", "p2.json", "00000000000000b2");
    assert!(
        occlu(&["merge", s(&first), s(&second), "--out", s(&two)])
            .status
            .success()
    );
    let moved = single_named("q3", "path.json", "00000000000000b2");
    assert!(occlu(&["merge", s(&moved), "--out", s(&one)]).status.success());
    let once = occlu(&["compare", s(&two), s(&one)]);
    assert_eq!(once.status.code(), Some(1), "{}", stdout(&once));
    assert_eq!(stdout(&once).matches("MISSING").count(), 1, "{}", stdout(&once));
}

#[test]
fn compare_of_merged_folders_pairs_runs_by_adapter_not_by_folder_name_and_trusts_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let (_, run) = matrix_of_one(dir.path());
    // One adapter by two backends, with a name longer than a folder's slug:
    // the base ran Vulkan only, the new merge GL and Vulkan.
    let long = "NVIDIA GeForce RTX 4090 Laptop GPU/PCIe/SSE2 (rev a1)";
    let on = |backend: &'static str| {
        let to = dir.path().join(backend).join("01-city-blocks-1-generated");
        edited_copy(&run, &to, |j| {
            j["adapter"]["name"] = long.into();
            j["adapter"]["backend"] = backend.into();
        });
        to
    };
    let (vulkan, gl) = (on("Vulkan"), on("Gl"));
    let (base, new) = (dir.path().join("base"), dir.path().join("new"));
    assert!(occlu(&["merge", s(&vulkan), "--out", s(&base)]).status.success());
    assert!(occlu(&["merge", s(&gl), s(&vulkan), "--out", s(&new)]).status.success());
    let folders: Vec<String> = merged(&new).runs[0].adapters.iter().map(|a| a.folder.clone()).collect();
    assert_ne!(folders[0], folders[1]);
    let compared = occlu(&["compare", s(&base), s(&new)]);
    assert!(compared.status.success(), "{:?}", own_stderr(&compared));
    assert!(stdout(&compared).contains("in the new merge only"));
    // A folder in merged.json that is not one in its runs/ is refused.
    for folder in [
        ".",
        "../full",
        "runs/..",
        "runs/../../full/01-city-blocks-1-generated",
        "runs",
    ] {
        let edited = dir.path().join("edited");
        let _ = std::fs::remove_dir_all(&edited);
        std::fs::create_dir(&edited).unwrap();
        let mut m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(new.join("merged.json")).unwrap()).unwrap();
        for a in m["runs"][0]["adapters"].as_array_mut().unwrap() {
            a["folder"] = folder.into();
        }
        std::fs::write(edited.join("merged.json"), m.to_string()).unwrap();
        refused(
            &["compare", s(&base), s(&edited)],
            &["is not a folder in its runs/", folder],
        );
    }
}

#[test]
fn a_matrix_and_a_single_run_or_another_matrix_never_share_an_out() {
    let dir = tempfile::tempdir().unwrap();
    let backend = &common::backends()[0];
    let matrix = tiny_matrix(dir.path(), "m.json", r#"["city:blocks=1"]"#);
    let single = |out: &Path| {
        let args = [
            &[
                "bench",
                "--backend",
                backend.as_str(),
                "--modes",
                "vfc",
                "--resolution",
                "64x48",
                "-q",
                "--out",
                s(out),
            ][..],
            TINY_RUN,
        ]
        .concat();
        occlu(&args)
    };
    // `config`'s matrix into `out`, refused saying `needles`.
    let matrix_into = |config: &Path, out: &Path, needles: &[&str]| {
        refused(
            &["bench", "--config", s(config), "--backend", backend, "--out", s(out)],
            needles,
        )
    };
    // A single run's folder takes no matrix: merge would read the run alone.
    let one = dir.path().join("one");
    assert!(single(&one).status.success());
    matrix_into(
        &matrix,
        &one,
        &["summary.json", "is a single run's result in the matrix's --out"],
    );
    // A matrix's folder takes no single run, which would hide its runs.
    let many = dir.path().join("many");
    bench_matrix(&matrix, backend, &many, &["--quiet"]);
    let out = single(&many);
    assert_eq!(out.status.code(), Some(2), "{:?}", own_stderr(&out));
    assert!(own_stderr(&out)[0].contains("is a matrix's run folder in --out"));
    assert!(!many.join("summary.json").exists());
    // The same matrix runs there again; another (a run added in front
    // renames the rest) is refused, as merge would count both.
    bench_matrix(&matrix, backend, &many, &["--quiet"]);
    let grown = tiny_matrix(dir.path(), "grown.json", r#"["city:blocks=2", "city:blocks=1"]"#);
    matrix_into(
        &grown,
        &many,
        &["01-city-blocks-1-generated", "is a run of another matrix"],
    );
    assert_eq!(run_folders(&many), ["01-city-blocks-1-generated"]);
    // A single run's folder inside another's --out is no matrix's: a
    // single run may stand beside it, a matrix may not.
    let nest = dir.path().join("nest");
    assert!(single(&nest.join("baseline")).status.success());
    assert!(single(&nest).status.success());
    let mixed = dir.path().join("mixed");
    assert!(single(&mixed.join("baseline")).status.success());
    matrix_into(
        &matrix,
        &mixed,
        &["baseline", "is a single run's folder in the matrix's --out"],
    );
    // Nor does a merged folder take one.
    let merged_out = dir.path().join("merged");
    assert!(occlu(&["merge", s(&many), "--out", s(&merged_out)]).status.success());
    matrix_into(&matrix, &merged_out, &["merged.json", "holds a merged result"]);
}
