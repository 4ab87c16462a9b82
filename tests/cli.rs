//! The command line as a user meets it: bad input gets one clear line and a
//! non-zero exit; a small bench writes its three result files.

mod common;

use common::{THREE_OBJECTS_OBJ, TINY_RUN, cannot_run, occlu, own_stderr, said_one_line, stdout, tampered_copy, write};

/// Runs occlu and checks it fails with exit code `code` and one line of
/// stderr that contains every one of `needles`.
fn fails_with(args: &[&str], code: i32, needles: &[&str]) {
    said_one_line(&occlu(args), code, needles, &format!("{args:?}"));
}

/// A tiny run at 64×48 into `out`, with `extra`.
fn bench_args<'a>(extra: &[&'a str], out: &'a str) -> Vec<&'a str> {
    let mut a = vec!["bench"];
    a.extend_from_slice(TINY_RUN);
    a.extend_from_slice(&["--resolution", "64x48", "--out", out]);
    a.extend_from_slice(extra);
    a
}

#[test]
fn bad_input_gets_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let out = d("out");
    let malformed_obj = write(dir.path(), "bad.obj", "v 0 0 x\nf 1 2 3\n");
    let nan_obj = write(dir.path(), "nan.obj", "o n\nv 0 0 0\nv NaN 1 0\nv 0 1 0\nf 1 2 3\n");
    let malformed_gltf = write(dir.path(), "bad.gltf", "{ not json");
    let bad_path = write(
        dir.path(),
        "p.json",
        r#"{"frames": 3, "keyframes": [{"time": 0, "position": [0, 0]}]}"#,
    );
    let good_obj = write(dir.path(), "ok.obj", THREE_OBJECTS_OBJ);
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();

    fails_with(
        &["bench", &d("missing.obj"), "--out", &out],
        2,
        &["missing.obj", "No such file"],
    );
    fails_with(
        &["bench", &s(&malformed_obj), "--out", &out],
        2,
        &["bad.obj", "invalid OBJ"],
    );
    fails_with(
        &["bench", &s(&nan_obj), "--out", &out],
        2,
        &["nan.obj", "mesh 'n': vertex 1", "non-finite"],
    );
    fails_with(
        &["bench", &s(&malformed_gltf), "--out", &out],
        2,
        &["bad.gltf", "invalid glTF"],
    );
    fails_with(
        &bench_args(&["--path", &s(&bad_path)], &out),
        2,
        &["p.json", "invalid camera path JSON"],
    );
    fails_with(
        &bench_args(&["--modes", "dr,warp"], &out),
        2,
        &[
            "unknown mode 'warp'",
            "dr, vfc, sq, omq, ac, chc, roc, ioc, hiz, swr, auto, oracle",
        ],
    );
    fails_with(
        &["bench", &s(&good_obj), "--frames", "0", "--out", &out],
        2,
        &["--frames", "0 is not in 1..=100000"],
    );
    fails_with(
        &["bench", "--resolution", "800x0", "--out", &out],
        2,
        &["resolution must be WIDTHxHEIGHT"],
    );
    fails_with(&["bench", "--resolution", "big", "--out", &out], 2, &["'big'"]);
    fails_with(
        &["bench", "--scene", "moon", "--out", &out],
        2,
        &["unknown scene 'moon'"],
    );
    fails_with(
        &["bench", &s(&good_obj), "--movers", "3", "--out", &out],
        2,
        &["--movers", "MODEL"],
    );
    fails_with(
        &["bench", "--scene", "city:movers=2", "--movers", "3", "--out", &out],
        2,
        &["'movers' is given twice"],
    );
    fails_with(&["bench", "--movers", "lots", "--out", &out], 2, &["'lots'"]);
    fails_with(
        &bench_args(&["--param", "omq.bogus=1"], &out),
        2,
        &["unknown parameter 'omq.bogus'", "omq.factor"],
    );
    fails_with(
        &bench_args(&["--param", "omq.om=wide"], &out),
        2,
        &["parameter 'omq.om'", "'wide'"],
    );
    fails_with(
        &bench_args(
            &["--modes", "ioc", "--param", "ioc.start=5", "--param", "ioc.bottom=2"],
            &out,
        ),
        2,
        &["parameter 'ioc.start'", "below the bottom depth 2"],
    );
    fails_with(
        &bench_args(&["--modes", "ioc", "--param", "ioc.bottom=-1"], &out),
        2,
        &["parameter 'ioc.bottom'", "'auto' or a depth"],
    );
    fails_with(&["bench", "--backend", "glide"], 2, &["invalid value 'glide'"]);
    fails_with(&["bench", "--bogus-flag"], 2, &["--bogus-flag"]);
    fails_with(
        &["bench", &s(&good_obj), "--scene", "city"],
        2,
        &["cannot be used with"],
    );
    fails_with(&["info", &d("absent.glb")], 2, &["absent.glb"]);
    fails_with(
        &[
            "path",
            "gen",
            "--scene",
            "city:blocks=1",
            "--frames",
            "0",
            "-o",
            &d("x.json"),
        ],
        2,
        &["--frames", "0 is not in 1..=100000"],
    );
    for file in ["frames.csv", "summary.json", "report.md"] {
        assert!(
            !dir.path().join("out").join(file).exists(),
            "failed runs write no {file}"
        );
    }
    // Each error is said once, not repeated by its cause.
    let missing = own_stderr(&occlu(&["info", &d("missing.obj")]));
    assert_eq!(missing[0].matches("No such file").count(), 1, "{missing:?}");
    fails_with(
        &["bench", "--warmup", "4294967295", "--out", &out],
        2,
        &["--warmup", "4294967295 is not in 0..=10000"],
    );
    fails_with(
        &["info", "--cluster-triangles", "99999999999"],
        2,
        &["99999999999 is not in 1..=4294967295"],
    );
    // An unwritable output directory is refused before any work.
    let blocker = write(dir.path(), "blocker", "a file, not a directory");
    let blocked = format!("{}/sub", blocker.display());
    let started = std::time::Instant::now();
    fails_with(&["bench", "--out", &blocked], 2, &["blocker"]);
    assert!(started.elapsed().as_secs() < 5, "refused before loading the city");
    // So is the output of a command that loads a model and plans a path,
    // before the model is read (this one does not exist: its error would
    // name it).
    let absent = d("absent.obj");
    for command in [&["path", "gen"][..], &["render", "--frame", "0", "--mode", "vfc"][..]] {
        let file = format!("{blocked}/out.png");
        let said = own_stderr(&occlu(&[command, &[absent.as_str(), "-o", &file]].concat())).join(" ");
        assert!(
            said.contains("blocker") && !said.contains("absent.obj"),
            "{command:?}: {said}"
        );
    }
    fails_with(
        &["stress", "--cases", "bogus"],
        2,
        &["unknown stress case 'bogus'", "teleport"],
    );
    fails_with(&["stress", "--modes", "dr,nope"], 2, &["unknown mode 'nope'"]);
    fails_with(&["stress", "--resolution", "0x3"], 2, &["resolution"]);
    // A parameter is checked against the modes and parsed before a case runs.
    fails_with(
        &["stress", "--modes", "vfc", "--param", "hiz.texels=2"],
        2,
        &["'hiz' is not being run"],
    );
    fails_with(
        &["stress", "--modes", "hiz", "--param", "hiz.texels=17"],
        2,
        &["within 2 to 16"],
    );
    fails_with(&["stress", "--out", &blocked], 2, &["blocker"]);
    // A name with a newline in a file stays on the error's one line.
    let newline_path = write(
        dir.path(),
        "nl.json",
        "{\"frames\": 2, \"keyframes\": [], \"bad\\nfield\": 1}",
    );
    fails_with(
        &["bench", "--path", &s(&newline_path), "--out", &out],
        2,
        &["bad\\nfield"],
    );
}

#[test]
fn a_depth_pyramid_beyond_the_adapter_is_refused_in_one_line() {
    // 8192×4096: its depth is 128 MiB, wgpu's default limit for one
    // storage binding; hiz's pyramid over it is 4/3 of that. An adapter
    // that binds more runs it.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    for backend in common::gpus().iter().map(|g| g.adapter.backend.clone()) {
        let args = [
            "bench",
            "--scene",
            "city:blocks=1",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--no-error",
            "--resolution",
            "8192x4096",
            "--modes",
            "hiz",
            "--backend",
            &backend,
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ];
        let run = occlu(&args);
        if !run.status.success() {
            said_one_line(
                &run,
                2,
                &["hiz's depth pyramid", "a smaller --resolution fits"],
                &backend,
            );
        }
    }
}

#[test]
fn stress_lists_its_cases() {
    let out = occlu(&["stress", "--list"]);
    assert!(out.status.success());
    let text = stdout(&out);
    for case in ["inside-leaf", "near-crossing", "offset-1e7", "fov-1 ", "teleport"] {
        assert!(text.contains(case), "--list lacks {case}: {text}");
    }
}

#[test]
fn auto_runs_frustum_culling_alone_in_a_scene_of_one_object() {
    // One object cannot be hidden behind another: no occlusion culler may
    // pay, so none is a candidate and no frame probes one.
    let dir = tempfile::tempdir().unwrap();
    let cube = write(
        dir.path(),
        "cube.obj",
        "o cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
    );
    let out = dir.path().join("run");
    let args = [
        "bench",
        cube.to_str().unwrap(),
        "--modes",
        "auto",
        "--frames",
        "6",
        "--warmup",
        "1",
        "--resolution",
        "64x48",
        "--no-error",
        "--out",
        out.to_str().unwrap(),
    ];
    let result = occlu(&args);
    assert!(result.status.success(), "{:?}", own_stderr(&result));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["modes"][0]["parameters"]["candidates"],
        serde_json::json!(["vfc"])
    );
    let picks = frames_columns(&out, &["strategy", "probe"]);
    assert_eq!(picks, vec![vec!["vfc".to_string(), "false".to_string()]; 6]);
}

/// Per row of the frames.csv in `run`, its cells of `columns` (by name).
fn frames_columns(run: &std::path::Path, columns: &[&str]) -> Vec<Vec<String>> {
    let frames = std::fs::read_to_string(run.join("frames.csv")).unwrap();
    let mut lines = frames.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at: Vec<usize> = columns
        .iter()
        .map(|name| header.iter().position(|c| c == name).unwrap())
        .collect();
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            at.iter().map(|&k| cells[k].to_string()).collect()
        })
        .collect()
}

#[test]
fn frames_csv_says_where_each_frames_camera_stood_and_looked() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "two.json",
        r#"{"frames": 2, "keyframes": [
            {"time": 0, "position": [0, 0, 5], "target": [0, 0, 0]},
            {"time": 1, "position": [4, 3, 0], "target": [0, 0, 0]}]}"#,
    );
    let out = dir.path().join("run");
    let args = [
        "bench",
        "--scene",
        "city:blocks=1",
        "--path",
        path.to_str().unwrap(),
        "--modes",
        "vfc,dr",
        "--warmup",
        "0",
        "--resolution",
        "64x48",
        "--no-error",
        "--out",
        out.to_str().unwrap(),
    ];
    let result = occlu(&args);
    assert!(result.status.success(), "{:?}", own_stderr(&result));
    let columns = [
        "frame",
        "eye_x",
        "eye_y",
        "eye_z",
        "forward_x",
        "forward_y",
        "forward_z",
    ];
    let rows = frames_columns(&out, &columns);
    for row in &rows {
        let cells: Vec<f64> = row.iter().map(|c| c.parse().unwrap()).collect();
        // The keyframes' positions, looking at the origin.
        let expected = match cells[0] as u32 {
            0 => [0.0, 0.0, 0.0, 5.0, 0.0, 0.0, -1.0],
            _ => [1.0, 4.0, 3.0, 0.0, -0.8, -0.6, 0.0],
        };
        for (got, want) in cells.iter().zip(expected) {
            assert!((got - want).abs() < 1e-9, "{cells:?}, not {expected:?}");
        }
    }
    assert_eq!(rows.len(), 4, "two frames of two modes");
}

#[test]
fn bench_writes_the_three_result_files_with_the_adapter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.to_str().unwrap();
    let result = occlu(&bench_args(&[], out_s));
    assert!(result.status.success(), "{:?}", own_stderr(&result));
    assert!(stdout(&result).contains("| vfc |"));

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["schema_version"], 1);
    assert!(!summary["adapter"]["name"].as_str().unwrap().is_empty());
    assert!(!summary["adapter"]["backend"].as_str().unwrap().is_empty());
    let modes: Vec<&str> = summary["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        modes,
        [
            "dr", "vfc", "sq", "omq", "ac", "chc", "roc", "ioc", "hiz", "swr", "auto", "oracle"
        ]
    );
    for m in summary["modes"].as_array().unwrap() {
        assert_eq!(m["frames"], 2);
        if m["conservative"] == true {
            assert_eq!(m["error_pixels_total"], 0, "{}", m["name"]);
            assert_eq!(m["missed_objects_total"], 0, "{}", m["name"]);
        }
    }

    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    for column in [
        "mode",
        "frame",
        "frame_ms",
        "cpu_ms",
        "gpu_ms",
        "objects_drawn",
        "triangles_drawn",
        "nodes_visited",
        "nodes_culled_frustum",
        "nodes_culled_occlusion",
        "queries",
        "query_batches",
        "queries_skipped",
        "queries_delayed",
        "maintenance_ms",
        "error_pixels",
        "missed_objects",
    ] {
        assert!(header.split(',').any(|c| c == column), "frames.csv lacks {column}");
    }
    assert_eq!(lines.count(), 24, "2 frames × 12 modes");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| oracle |") && report.contains("Adapter:"));
    // auto's rows name the candidate that drew each frame, and whether it
    // was a probe; report.md counts them per strategy.
    let auto = summary["modes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "auto")
        .unwrap();
    let candidates: Vec<&str> = auto["parameters"]["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert!(
        candidates.contains(&"vfc") && candidates.contains(&"swr"),
        "{candidates:?}"
    );
    let rows: Vec<occlu::measure::FrameStats> = csv::Reader::from_path(out.join("frames.csv"))
        .unwrap()
        .deserialize()
        .map(Result::unwrap)
        .collect();
    for r in &rows {
        match r.mode.as_str() {
            "auto" => assert!(
                r.strategy.as_deref().is_some_and(|s| candidates.contains(&s)) && r.probe.is_some(),
                "{r:?}"
            ),
            _ => assert_eq!((&r.strategy, r.probe), (&None, None), "{r:?}"),
        }
    }
    let strategies = auto["strategies"].as_array().unwrap();
    let frames: u64 = strategies.iter().map(|s| s["frames"].as_u64().unwrap()).sum();
    assert_eq!(frames, 2);
    assert!(report.contains("## auto's strategies"));
    for s in strategies {
        let row = format!(
            "| {} | {} | {} |",
            s["strategy"].as_str().unwrap(),
            s["frames"],
            s["probes"]
        );
        assert!(report.contains(&row), "report.md lacks {row}");
    }
    // The verdict: the fastest conservative mode but auto and the oracle,
    // and auto's time over its.
    let mean = |m: &serde_json::Value| m["stats"]["frame_ms"]["mean"].as_f64().unwrap();
    let fastest = summary["modes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["conservative"] == true && m["name"] != "auto" && m["name"] != "oracle")
        .min_by(|a, b| mean(a).total_cmp(&mean(b)))
        .unwrap();
    let verdict = &summary["verdict"];
    assert_eq!(verdict["fastest"], fastest["name"]);
    let auto_ratio = mean(auto) / mean(fastest);
    assert_eq!(verdict["auto_ratio"].as_f64(), Some(auto_ratio));
    // Two frames are too few for an interval: none is given, for auto or
    // for the next fastest mode.
    assert!(verdict["auto_interval"].is_null(), "{verdict}");
    assert!(verdict["runner_up"].is_null(), "{verdict}");
    let first = format!("**Fastest conservative mode: {}**", fastest["name"].as_str().unwrap());
    assert!(report.lines().take(8).any(|l| l.starts_with(&first)), "{report}");
    // The cost split, where the adapter has timestamps: hiz's pyramid is
    // part of its box tests, and drawing is the rest of its GPU time.
    let hiz = &summary["modes"][8];
    let mean = |col: &str| hiz["stats"][col]["mean"].as_f64();
    assert_eq!(report.contains("## Cost split"), mean("gpu_ms").is_some());
    if let (Some(tests), Some(pyramid)) = (mean("query_gpu_ms"), mean("pyramid_gpu_ms")) {
        let row = report.lines().filter(|l| l.starts_with("| hiz |")).nth(1).unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[4], format!("{tests:.2}"), "{row}");
        assert_eq!(cells[5], format!("{pyramid:.2}"), "{row}");
        assert!(pyramid <= tests, "{row}");
        // Drawing is each frame's GPU time less its box tests, averaged
        // from frames.csv (a frame without tests has an empty cell).
        let hiz_rows: Vec<&occlu::measure::FrameStats> = rows.iter().filter(|r| r.mode == "hiz").collect();
        let drawing: f64 = hiz_rows
            .iter()
            .map(|r| r.gpu_ms.unwrap() - r.query_gpu_ms.unwrap_or(0.0))
            .sum::<f64>()
            / hiz_rows.len() as f64;
        let shown: f64 = cells[6].parse().unwrap();
        assert!((shown - drawing).abs() <= 0.0051, "{row}: drawing {drawing}");
    }
    for chart in occlu::report::charts::CHARTS {
        assert!(report.contains(&format!("]({chart})")), "report.md links {chart}");
        let (width, height, colours) = png_colours(&out.join(chart));
        assert_eq!((width, height), (1200, 700), "{chart}");
        assert!(
            colours.len() > 50,
            "{chart} has only {} colours: is it blank?",
            colours.len()
        );
    }
    // The data is drawn, not only axes: the lines of vfc and the oracle.
    let (_, _, lines) = png_colours(&out.join("frame_time.png"));
    assert!(
        lines.contains(&[31, 119, 180]) && lines.contains(&[20, 20, 20]),
        "mode lines missing"
    );
    // `occlu plot` draws them again from the files alone, and its verdict
    // from frames.csv, not from summary.json's copy.
    for chart in occlu::report::charts::CHARTS {
        std::fs::remove_file(out.join(chart)).unwrap();
    }
    let summary_path = out.join("summary.json");
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
    let fastest = summary["verdict"]["fastest"].as_str().unwrap().to_string();
    summary["verdict"]["fastest"] = "tampered".into();
    std::fs::write(&summary_path, summary.to_string()).unwrap();
    let plot = occlu(&["plot", out_s]);
    assert!(plot.status.success(), "{:?}", own_stderr(&plot));
    assert!(occlu::report::charts::CHARTS.iter().all(|c| out.join(c).exists()));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains(&format!("**Fastest conservative mode: {fastest}**")),
        "{report}"
    );
    // A folder where a chart goes is refused before any file is replaced:
    // the folder's set of files stays one run's.
    use std::os::unix::fs::MetadataExt as _;
    let [first, .., last] = occlu::report::charts::CHARTS;
    std::fs::remove_file(out.join(last)).unwrap();
    std::fs::create_dir(out.join(last)).unwrap();
    let inode = |name: &str| std::fs::metadata(out.join(name)).unwrap().ino();
    let before = [inode(first), inode("report.md")];
    fails_with(&["plot", out_s], 2, &[last, "is a folder where occlu writes a file"]);
    assert_eq!([inode(first), inode("report.md")], before, "nothing replaced");
}

#[test]
fn config_files_drive_a_run_and_flags_override_them() {
    let dir = tempfile::tempdir().unwrap();
    let config = write(
        dir.path(),
        "c.json",
        r#"{"scene": "city:blocks=1", "frames": 5, "warmup": 0, "resolution": "32x32", "modes": ["vfc"], "out": "from-config", "error": false}"#,
    );
    let result = occlu(&["bench", "--config", config.to_str().unwrap(), "--frames", "1"]);
    assert!(result.status.success(), "{:?}", own_stderr(&result));
    let out = dir.path().join("from-config");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"], 1, "the flag wins over the file");
    assert_eq!(summary["resolution"], "32x32");
    assert_eq!(summary["error_measured"], false);
    assert_eq!(summary["modes"][0]["error_pixels_total"], serde_json::Value::Null);
}

#[test]
fn generated_paths_round_trip_through_bench() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("orbit.json");
    let generated = occlu(&[
        "path",
        "gen",
        "--scene",
        "city:blocks=1",
        "--kind",
        "orbit",
        "--frames",
        "4",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert!(generated.status.success(), "{:?}", own_stderr(&generated));
    let file: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(file["frames"], 4);
    assert_eq!(file["keyframes"].as_array().unwrap().len(), 25);

    let out = dir.path().join("run");
    let mut args = vec![
        "bench",
        "--scene",
        "city:blocks=1",
        "--resolution",
        "48x32",
        "--warmup",
        "0",
    ];
    args.extend_from_slice(&[
        "--path",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--modes",
        "vfc",
    ]);
    let run = occlu(&args);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4);
}

#[test]
fn help_explains_modes_and_scenes() {
    let out = occlu(&["--help"]);
    assert!(out.status.success());
    let text = stdout(&out);
    for needle in ["bench", "info", "path", "vfc", "oracle", "city", "Exit status"] {
        assert!(text.contains(needle), "--help lacks {needle}");
    }
}

#[test]
fn every_command_that_writes_takes_out_and_output_alike() {
    let commands: [&[&str]; 7] = [
        &["bench"],
        &["stress"],
        &["merge"],
        &["render"],
        &["flythrough"],
        &["export"],
        &["path", "gen"],
    ];
    for command in commands {
        let out = occlu(&[command, &["--help"]].concat());
        assert!(out.status.success(), "{command:?}");
        let text = stdout(&out);
        for spelling in ["--out ", "--output "] {
            let said = text.contains(spelling) || text.contains(&format!("alias: {}", spelling.trim_end()));
            assert!(said, "{command:?} --help lacks {spelling}");
        }
    }
}

/// Width, height and distinct colours of an RGB PNG.
fn png_colours(path: &std::path::Path) -> (u32, u32, std::collections::HashSet<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let colours = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width, info.height, colours)
}

#[test]
fn compare_passes_a_run_against_itself_and_names_regressions() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base");
    // Enough warm frames for a stable median and MAD.
    let run = occlu(&[
        "bench",
        "--scene",
        "city:blocks=1",
        "--frames",
        "8",
        "--warmup",
        "2",
        "--resolution",
        "64x48",
        "--modes",
        "vfc,omq,swr",
        "--out",
        base.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    // Frame times of a test run depend on the load of the machine; the
    // verdicts under test must not. The base gets steady, known times.
    let steady = dir.path().join("steady");
    tampered_copy(&base, &steady, &|r| r.frame_ms = 10.0 + f64::from(r.frame % 3) * 0.1);
    let b = steady.to_str().unwrap();
    let same = occlu(&["compare", b, b]);
    assert_eq!(same.status.code(), Some(0), "{:?}", own_stderr(&same));
    assert!(stdout(&same).contains("omq") && stdout(&same).contains("same"));
    // A verdict it cannot write is trouble, not a regression: exit 2.
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let unwritten = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(["compare", b, b])
        .stdout(full)
        .output()
        .unwrap();
    said_one_line(
        &unwritten,
        2,
        &["cannot write to standard output"],
        "compare > /dev/full",
    );

    let compare_with = |name: &str, edit: &dyn Fn(&mut occlu::measure::FrameStats), extra: &[&str]| {
        let new = dir.path().join(name);
        tampered_copy(&steady, &new, edit);
        let mut args = vec!["compare", b, new.to_str().unwrap()];
        args.extend_from_slice(extra);
        occlu(&args)
    };
    let more = compare_with(
        "more",
        &|r| {
            if r.mode == "omq" {
                r.triangles_drawn += 100
            }
        },
        &[],
    );
    assert_eq!(more.status.code(), Some(1));
    let line = own_stderr(&more).join(" ");
    assert!(line.contains("omq triangles_drawn"), "{line}");

    // swr's triangles follow the times it measures (its buffer rests where
    // it did not pay): 1 % more is within the noise, as a frame time is.
    let drifted = compare_with(
        "drifted",
        &|r| {
            if r.mode == "swr" {
                r.triangles_drawn += r.triangles_drawn / 100 + 1
            }
        },
        &[],
    );
    assert_eq!(drifted.status.code(), Some(0), "{:?}", own_stderr(&drifted));
    assert!(stdout(&drifted).contains("within noise"), "{}", stdout(&drifted));

    let slow = compare_with(
        "slow",
        &|r| {
            if r.mode == "vfc" {
                r.frame_ms *= 3.0
            }
        },
        &[],
    );
    assert_eq!(slow.status.code(), Some(1));
    assert!(own_stderr(&slow).join(" ").contains("vfc frame_ms"));

    // 1% slower is within the default 5% threshold.
    let noise = compare_with("noise", &|r| r.frame_ms *= 1.01, &[]);
    assert_eq!(noise.status.code(), Some(0), "{:?}", own_stderr(&noise));

    // Gating only on counters ignores the slower frames.
    let counters = compare_with(
        "counters",
        &|r| r.frame_ms *= 3.0,
        &["--metric", "triangles_drawn,error_pixels"],
    );
    assert_eq!(counters.status.code(), Some(0));

    let fewer = compare_with("fewer", &|r| r.triangles_drawn /= 2, &[]);
    assert_eq!(
        fewer.status.code(),
        Some(0),
        "fewer triangles is better, not a regression"
    );
    assert!(stdout(&fewer).contains("better"));

    // The same model name, other geometry (a changed file): compared, with
    // a note that says so.
    let changed = dir.path().join("changed");
    tampered_copy(&steady, &changed, &|_| {});
    let summary_path = changed.join("summary.json");
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
    summary["scene"]["geometry"]["fnv1a"] = "0123456789abcdef".into();
    std::fs::write(&summary_path, summary.to_string()).unwrap();
    let noted = occlu(&["compare", b, changed.to_str().unwrap()]);
    assert_eq!(noted.status.code(), Some(0), "{:?}", own_stderr(&noted));
    assert!(
        stdout(&noted).contains("the scene's geometry differ (#") && stdout(&noted).contains("#0123456789abcdef)"),
        "{}",
        stdout(&noted)
    );

    // Frame times that vary along the path far more than between runs (a
    // review's finding: 1.5 times slower on every frame passed as noise,
    // each run's spread being the path's). Paired frame by frame, the
    // change stands out; noise of a few percent a frame does not.
    let varied = dir.path().join("varied");
    tampered_copy(&base, &varied, &|r| {
        r.frame_ms = if r.frame % 2 == 0 { 10.0 } else { 50.0 }
    });
    let v = varied.to_str().unwrap();
    let against_varied = |name: &str, edit: &dyn Fn(&mut occlu::measure::FrameStats)| {
        let new = dir.path().join(name);
        tampered_copy(&varied, &new, edit);
        occlu(&["compare", v, new.to_str().unwrap()])
    };
    let slower = against_varied("slower", &|r| r.frame_ms *= 1.5);
    assert_eq!(slower.status.code(), Some(1), "{}", stdout(&slower));
    assert!(own_stderr(&slower).join(" ").contains("vfc frame_ms +50.0%"));
    // Frames 4 % slower and 1 % faster by turns: within the noise even
    // with no threshold, the interval reaching 1.
    let jittered = dir.path().join("jittered");
    tampered_copy(&varied, &jittered, &|r| {
        r.frame_ms *= if r.frame % 3 == 0 { 1.04 } else { 0.99 }
    });
    let jitter = occlu(&["compare", v, jittered.to_str().unwrap(), "--max-regression", "0"]);
    assert_eq!(jitter.status.code(), Some(0), "{}", stdout(&jitter));
    assert!(stdout(&jitter).contains("within noise"), "{}", stdout(&jitter));

    // Runs that measured something else are refused: another warmup, other
    // mode parameters; one path named two ways (its cameras the same) is
    // one path, and another is not.
    // A copy of the steady run with its first `frames` frames, and its
    // summary edited.
    let edited_summary_over = |name: &str, frames: u32, edit: &dyn Fn(&mut serde_json::Value)| {
        let copy = dir.path().join(name);
        common::rewritten_copy(&steady, &copy, &mut |rows| rows.retain(|r| r.frame < frames));
        let summary_path = copy.join("summary.json");
        let mut summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
        edit(&mut summary);
        std::fs::write(&summary_path, summary.to_string()).unwrap();
        copy
    };
    let edited_summary = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| edited_summary_over(name, 8, edit);
    let warm = edited_summary("warm", &|s| s["warmup"] = 0.into());
    fails_with(
        &["compare", b, warm.to_str().unwrap()],
        2,
        &["their warmup frames: 2 vs 0"],
    );
    // Clusters of another size are other objects to cull.
    let clustered = edited_summary("clustered", &|s| s["scene"]["cluster_triangles"] = 16.into());
    fails_with(
        &["compare", b, clustered.to_str().unwrap()],
        2,
        &["their cluster sizes (--cluster-triangles): 4096 vs 16"],
    );
    // A copy whose omq parameters `edit` changed.
    let omq_edited = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        edited_summary(name, &|s| {
            let omq = s["modes"]
                .as_array_mut()
                .unwrap()
                .iter_mut()
                .find(|m| m["name"] == "omq")
                .unwrap();
            edit(&mut omq["parameters"]);
        })
    };
    let tuned = omq_edited("tuned", &|p| p["om"] = "80x60".into());
    fails_with(
        &["compare", b, tuned.to_str().unwrap()],
        2,
        &["their mode parameters: omq.om=64x48 vs omq.om=80x60)"],
    );
    // A parameter a run from an older occlu did not record is named too.
    let older = omq_edited("older", &|p| {
        p.as_object_mut().unwrap().remove("om");
    });
    fails_with(
        &["compare", b, older.to_str().unwrap()],
        2,
        &["their mode parameters: omq.om=64x48 vs omq.om not recorded)"],
    );
    // A value that differs in its type alone is told apart.
    let as_text = omq_edited("as_text", &|p| p["om"] = "7".into());
    let as_number = omq_edited("as_number", &|p| p["om"] = 7.into());
    fails_with(
        &["compare", as_text.to_str().unwrap(), as_number.to_str().unwrap()],
        2,
        &["their mode parameters: omq.om=\"7\" vs omq.om=7)"],
    );
    // (From before the cluster size was recorded, too.)
    let renamed = edited_summary("renamed", &|s| {
        s["path"]["source"] = "/ci/checkout/path.json".into();
        s["scene"].as_object_mut().unwrap().remove("cluster_triangles");
    });
    let same_path = occlu(&["compare", b, renamed.to_str().unwrap()]);
    assert_eq!(same_path.status.code(), Some(0), "{:?}", own_stderr(&same_path));
    // Renamed and run over fewer frames (which a path's fingerprint holds):
    // the frame count is named.
    let shorter = edited_summary_over("shorter", 7, &|s| {
        s["path"]["source"] = "/ci/checkout/path.json".into();
        s["path"]["cameras"]["fnv1a"] = "0123456789abcdef".into();
        s["frames"] = 7.into();
    });
    fails_with(
        &["compare", b, shorter.to_str().unwrap()],
        2,
        &["their frame counts: 8 vs 7"],
    );
    let other = edited_summary("other", &|s| {
        s["path"]["source"] = "/ci/checkout/other.json".into();
        s["path"]["cameras"]["fnv1a"] = "0123456789abcdef".into();
    });
    fails_with(&["compare", b, other.to_str().unwrap()], 2, &["their paths"]);

    fails_with(
        &["compare", b, dir.path().join("absent").to_str().unwrap()],
        2,
        &["summary.json"],
    );
    fails_with(&["compare", b, b, "--max-regression=-3"], 2, &["--max-regression"]);
    // Written apart from its flag, a negative value is refused by the same
    // rule (it was taken for an unknown flag).
    fails_with(
        &["compare", b, b, "--max-regression", "-3"],
        2,
        &["--max-regression must be a percentage of 0 or more, got -3"],
    );
    fails_with(&["compare", b, b, "--metric", "speed"], 2, &["invalid value 'speed'"]);
}

#[test]
fn render_draws_a_frame_its_overview_and_its_depth_complexity() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let base = [
        "render",
        "--scene",
        "city:blocks=2",
        "--frame",
        "3",
        "--resolution",
        "160x120",
    ];
    let with = |extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        occlu(&args)
    };
    let overview = out("overview.png");
    let r = with(&["--mode", "omq", "--overview", "-o", &overview]);
    assert!(r.status.success(), "{:?}", own_stderr(&r));
    let (w, h, colours) = png_colours(std::path::Path::new(&overview));
    assert_eq!((w, h), (320, 120), "the view and the overview side by side");
    let near = |c: &[u8; 3], want: [u8; 3]| c.iter().zip(want).all(|(&a, b)| a.abs_diff(b) <= 2);
    assert!(
        colours.iter().any(|c| near(c, [255, 217, 0])),
        "yellow boxes of culled objects"
    );
    assert!(colours.iter().any(|c| near(c, [230, 26, 26])), "the red frustum");

    let heat = out("heat.png");
    // `--out`, as bench spells it, names the file too.
    let r = with(&["--mode", "vfc", "--heat", "--out", &heat]);
    assert!(r.status.success(), "{:?}", own_stderr(&r));
    let (w, h, colours) = png_colours(std::path::Path::new(&heat));
    assert_eq!((w, h), (160, 120));
    assert!(
        colours.contains(&[0, 0, 0]) && colours.len() > 5,
        "sky is black, surfaces are coloured"
    );

    let bad = |extra: &[&str], needle: &str| {
        let mut args = vec!["render", "--scene", "city:blocks=1", "--resolution", "64x48", "-o"];
        let target = out("bad.png");
        args.push(&target);
        args.extend_from_slice(extra);
        fails_with(&args, 2, &[needle]);
    };
    bad(&["--frame", "500", "--mode", "vfc"], "beyond the path's 120 frames");
    bad(&["--frame", "0", "--mode", "warp"], "unknown mode 'warp'");
    let jpeg = out("frame.JPG");
    fails_with(
        &[
            "render",
            "--scene",
            "city:blocks=1",
            "--resolution",
            "64x48",
            "--frame",
            "0",
            "--mode",
            "vfc",
            "-o",
            &jpeg,
        ],
        2,
        &["occlu writes PNG only, and"],
    );
    assert!(!std::path::Path::new(&jpeg).exists());
    bad(&["--frame", "0", "--mode", "vfc,omq"], "render draws one");
    bad(
        &["--frame", "0", "--mode", "all"],
        "'all' names more than one mode, and render draws one",
    );
}

#[test]
fn a_reader_that_goes_away_ends_the_output_quietly() {
    // The read end is closed before occlu starts, so its first write meets
    // a broken pipe.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(["stress", "--list"])
        .stdout(writer)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{:?}", own_stderr(&out));
    assert!(own_stderr(&out).is_empty(), "{:?}", own_stderr(&out));
}

#[test]
fn a_full_stdout_is_one_line_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "m.obj", THREE_OBJECTS_OBJ);
    for args in [
        vec!["info", model.to_str().unwrap()],
        vec!["--help"],
        vec!["bench", "--help"],
    ] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
            .args(&args)
            .stdout(full)
            .output()
            .unwrap();
        said_one_line(
            &out,
            1,
            &["cannot write to standard output"],
            &format!("{args:?} > /dev/full"),
        );
    }
}

#[test]
fn a_closed_or_full_stderr_loses_its_lines_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "m.obj", THREE_OBJECTS_OBJ);
    let path = dir.path().join("p.json");
    // Success (its "wrote" line lost) and bad input (its error lost) keep
    // their exit status; neither panics (101).
    let commands: [(&[&str], i32); 2] = [
        (
            &["path", "gen", model.to_str().unwrap(), "-o", path.to_str().unwrap()],
            0,
        ),
        (&["info", "no-such-model.obj"], 2),
    ];
    for (args, code) in commands {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
            .args(args)
            .stderr(full)
            .status()
            .unwrap();
        assert_eq!(status.code(), Some(code), "{args:?} 2>/dev/full");
        // A pipe whose reader has gone.
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
            .args(args)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take());
        assert_eq!(child.wait().unwrap().code(), Some(code), "{args:?} 2>closed pipe");
    }
}

#[test]
fn messages_name_the_real_cause() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "not-a-folder", "x");
    fails_with(
        &["bench", "--out", file.to_str().unwrap()],
        2,
        &["not-a-folder", "is not a directory"],
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(["stress", "--cases", "edge-on"])
        .env("WGPU_BACKEND", "bogus")
        .output()
        .unwrap();
    said_one_line(&out, 2, &["WGPU_BACKEND names 'bogus'"], "WGPU_BACKEND=bogus stress");
}

#[test]
fn a_resolution_beyond_the_adapters_buffers_is_refused_before_any_work() {
    for gpu in common::gpus() {
        let limit = gpu.device.limits().max_storage_buffer_binding_size;
        // The smallest square picture whose depths (4 bytes a pixel) do not
        // fit one storage binding; none where 8192 × 8192 fits.
        let side = (((limit / 4) as f64).sqrt() as u64 + 1).max(1);
        if side > 8192 {
            continue;
        }
        let resolution = format!("{side}x{side}");
        let backend = gpu.adapter.backend.clone();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let started = std::time::Instant::now();
        let run = occlu(&[
            "bench",
            "--scene",
            "city:blocks=1",
            "--frames",
            "1",
            "--backend",
            &backend,
            "--resolution",
            &resolution,
            "--out",
            out.to_str().unwrap(),
        ]);
        // The scene and adapter lines come first; then one error line, and
        // the exit status of bad input: a smaller size would run.
        let lines = own_stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{lines:?}");
        let last = lines.last().unwrap();
        assert!(
            last.starts_with("occlu: error:") && last.contains("a smaller --resolution fits"),
            "{lines:?}"
        );
        assert!(last.contains(&limit.to_string()) && !lines.iter().any(|l| l.contains("panicked")));
        assert!(started.elapsed().as_secs() < 60, "refused before rendering");
        assert!(!out.join("frames.csv").exists());
    }
}

#[test]
fn input_that_never_ends_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let endless = dir.path().join("endless.obj");
    std::os::unix::fs::symlink("/dev/zero", &endless).unwrap();
    let started = std::time::Instant::now();
    fails_with(
        &["info", endless.to_str().unwrap()],
        2,
        &["endless.obj", "not a regular file"],
    );
    // A FIFO would block a reader until something writes to it.
    let fifo = dir.path().join("path.json");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let out = dir.path().join("out");
    fails_with(
        &[
            "bench",
            "--path",
            fifo.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        2,
        &["path.json", "not a regular file"],
    );
    assert!(started.elapsed().as_secs() < 20, "neither read to its end");
}

#[test]
fn compare_fails_on_what_the_new_run_leaves_out_and_refuses_other_adapters() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "bench",
            "--scene",
            "city:blocks=1",
            "--frames",
            "8",
            "--warmup",
            "0",
            "--resolution",
            "64x48",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let result = occlu(&args);
        assert!(result.status.success(), "{:?}", own_stderr(&result));
        out.to_str().unwrap().to_string()
    };
    let base = run("base", &["--modes", "vfc,omq"]);
    let fewer = run("fewer", &["--modes", "vfc"]);
    let blind = run("blind", &["--modes", "vfc,omq", "--no-error"]);

    let missing_mode = occlu(&["compare", &base, &fewer]);
    assert_eq!(missing_mode.status.code(), Some(1), "{:?}", own_stderr(&missing_mode));
    assert!(stdout(&missing_mode).contains("MISSING") && own_stderr(&missing_mode).join(" ").contains("omq"));
    let allowed = occlu(&[
        "compare",
        &base,
        &fewer,
        "--allow-missing",
        "--metric",
        "triangles_drawn",
    ]);
    assert_eq!(allowed.status.code(), Some(0), "{:?}", own_stderr(&allowed));
    assert!(stdout(&allowed).contains("note: mode omq is in the base run only"));

    let missing_error = occlu(&["compare", &base, &blind, "--metric", "error_pixels,missed_objects"]);
    assert_eq!(missing_error.status.code(), Some(1), "{}", stdout(&missing_error));
    assert!(own_stderr(&missing_error).join(" ").contains("vfc error_pixels"));

    // Few frames: the table says what "within noise" rests on.
    let same = occlu(&["compare", &base, &base]);
    assert_eq!(same.status.code(), Some(0));
    assert!(
        stdout(&same).contains("8 frames: frame_ms is 'within noise' when"),
        "{}",
        stdout(&same)
    );

    // Another adapter: refused, unless asked.
    let other = dir.path().join("other");
    // Three times slower there: the adapters differ, not the code.
    tampered_copy(std::path::Path::new(&base), &other, &|r| r.frame_ms *= 3.0);
    let summary = std::fs::read_to_string(other.join("summary.json")).unwrap();
    let mut summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    summary["adapter"]["name"] = "Another GPU".into();
    std::fs::write(other.join("summary.json"), summary.to_string()).unwrap();
    let other = other.to_str().unwrap();
    fails_with(
        &["compare", &base, other],
        2,
        &["different adapters", "--cross-adapter"],
    );
    let crossed = occlu(&["compare", &base, other, "--cross-adapter", "--json"]);
    assert_eq!(crossed.status.code(), Some(0), "{:?}", own_stderr(&crossed));
    let verdicts: serde_json::Value = serde_json::from_str(&stdout(&crossed)).unwrap();
    let changes = verdicts["changes"].as_array().unwrap();
    assert_eq!(changes.len(), 2 * 6);
    for c in changes {
        let expected = if c["metric"] == "frame_ms" {
            "not_judged"
        } else {
            "same"
        };
        assert_eq!(c["verdict"], expected, "{c}");
    }
    assert!(verdicts["notes"][0].as_str().unwrap().contains("Another GPU"));
    // More drawn there: judged where the adapters work alike, and not where
    // they work otherwise (another backend, whose depth precision moves
    // what box tests hide), where only what the modes got wrong compares.
    let differently = |name: &str, backend: Option<&str>| {
        let to = dir.path().join(name);
        tampered_copy(std::path::Path::new(&base), &to, &|r| {
            r.frame_ms *= 3.0;
            r.triangles_drawn += 1000;
        });
        let summary = std::fs::read_to_string(to.join("summary.json")).unwrap();
        let mut summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
        summary["adapter"]["name"] = "Another GPU".into();
        if let Some(backend) = backend {
            summary["adapter"]["backend"] = backend.into();
        }
        std::fs::write(to.join("summary.json"), summary.to_string()).unwrap();
        to.to_str().unwrap().to_string()
    };
    let alike = differently("alike", None);
    let more = occlu(&["compare", &base, &alike, "--cross-adapter"]);
    assert_eq!(more.status.code(), Some(1), "{}", stdout(&more));
    assert!(own_stderr(&more).join(" ").contains("vfc triangles_drawn"));
    let base_backend = serde_json::from_str::<serde_json::Value>(
        &std::fs::read_to_string(std::path::Path::new(&base).join("summary.json")).unwrap(),
    )
    .unwrap()["adapter"]["backend"]
        .as_str()
        .unwrap()
        .to_string();
    let other_backend = if base_backend == "gl" { "vulkan" } else { "gl" };
    let unlike = differently("unlike", Some(other_backend));
    let crossed = occlu(&["compare", &base, &unlike, "--cross-adapter", "--json"]);
    assert_eq!(crossed.status.code(), Some(0), "{:?}", own_stderr(&crossed));
    let verdicts: serde_json::Value = serde_json::from_str(&stdout(&crossed)).unwrap();
    for c in verdicts["changes"].as_array().unwrap() {
        let error = c["metric"] == "error_pixels" || c["metric"] == "missed_objects";
        assert_eq!(c["verdict"], if error { "same" } else { "not_judged" }, "{c}");
    }
    assert!(verdicts["notes"][0].as_str().unwrap().contains("backends differ"));
    // Where only indirect counts differ, the GPU walks' round trips alone
    // are not judged (they read their lists' lengths back without them).
    let walks = run("walks", &["--modes", "vfc,roc"]);
    let readback = dir.path().join("readback");
    tampered_copy(std::path::Path::new(&walks), &readback, &|r| {
        r.frame_ms *= 3.0;
        if r.mode == "roc" {
            r.query_batches += 1;
        }
    });
    let summary = std::fs::read_to_string(readback.join("summary.json")).unwrap();
    let mut summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    summary["adapter"]["name"] = "Another GPU".into();
    summary["adapter"]["indirect_count"] = (!summary["adapter"]["indirect_count"].as_bool().unwrap()).into();
    std::fs::write(readback.join("summary.json"), summary.to_string()).unwrap();
    let trips = occlu(&[
        "compare",
        &walks,
        readback.to_str().unwrap(),
        "--cross-adapter",
        "--json",
    ]);
    assert_eq!(trips.status.code(), Some(0), "{:?}", own_stderr(&trips));
    let verdicts: serde_json::Value = serde_json::from_str(&stdout(&trips)).unwrap();
    for c in verdicts["changes"].as_array().unwrap() {
        let timed = c["metric"] == "frame_ms" || c["metric"] == "query_batches" && c["mode"] == "roc";
        assert_eq!(c["verdict"], if timed { "not_judged" } else { "same" }, "{c}");
    }
    fails_with(
        &[
            "compare",
            &base,
            &unlike,
            "--cross-adapter",
            "--metric",
            "frame_ms,triangles_drawn",
        ],
        2,
        &["only error counters compare", "nothing would be judged"],
    );
    // A gate on frame time alone would judge nothing there: refused.
    fails_with(
        &["compare", &base, other, "--cross-adapter", "--metric", "frame_ms"],
        2,
        &["nothing would be judged"],
    );

    // The same software adapter rasterising on other threads: its times
    // do not compare either.
    let threads = dir.path().join("threads");
    tampered_copy(std::path::Path::new(&base), &threads, &|_| {});
    let summary = std::fs::read_to_string(threads.join("summary.json")).unwrap();
    let mut summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let adapter = summary["adapter"].as_object_mut().unwrap();
    if adapter.remove("lp_num_threads").is_none() {
        adapter.insert("lp_num_threads".into(), "0".into());
    }
    std::fs::write(threads.join("summary.json"), summary.to_string()).unwrap();
    fails_with(
        &["compare", &base, threads.to_str().unwrap()],
        2,
        &["different adapters", "LP_NUM_THREADS"],
    );
}

#[test]
fn mesas_software_adapters_record_the_threads_they_rasterise_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let result = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(bench_args(&["--modes", "vfc"], out.to_str().unwrap()))
        // Mesa reads the number and ignores the rest; the report shows it
        // all, on its line.
        .env("LP_NUM_THREADS", "1\n# Injected heading")
        .output()
        .unwrap();
    assert!(result.status.success(), "{:?}", own_stderr(&result));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let adapter = &summary["adapter"];
    // Only Mesa's software adapters read the variable (lavapipe names its
    // device after llvmpipe): elsewhere none is recorded.
    let expected = if adapter["name"].as_str().unwrap().contains("llvmpipe") {
        serde_json::json!("1\\n# Injected heading")
    } else {
        serde_json::Value::Null
    };
    assert_eq!(adapter["lp_num_threads"], expected, "{adapter}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(!report.lines().any(|l| l.starts_with("# Injected")), "{report}");
}

#[test]
fn a_headless_run_prints_no_wayland_noise() {
    // libwayland complains about a missing XDG_RUNTIME_DIR when the Vulkan
    // loader probes for a display; occlu gives it a private folder.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(["stress", "--cases", "on-face", "--modes", "vfc"])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", common::stderr(&out));
    let stderr = common::stderr(&out);
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert!(stderr.lines().all(|l| l.starts_with("adapter: ")), "{stderr}");
}

/// Whether a run left a staging folder in `out`.
fn staged_files_left(out: &std::path::Path) -> bool {
    std::fs::read_dir(out)
        .unwrap()
        .any(|e| e.unwrap().file_name().to_string_lossy().starts_with(".occlu-staging"))
}

/// A tiny bench run into `out`.
fn tiny_run(out: &std::path::Path) -> std::process::Output {
    occlu(&bench_args(&["--modes", "vfc"], out.to_str().unwrap()))
}

#[test]
fn result_folders_are_claimed_whole_and_checked_when_read() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let run = tiny_run(&a);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let left: Vec<String> = std::fs::read_dir(&a)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert_eq!(left, [".occlu.lock"], "no staging folder left");

    // A frames.csv cut short, or another run's, is refused.
    let b = dir.path().join("b");
    tampered_copy(&a, &b, &|_| {});
    let frames = std::fs::read(a.join("frames.csv")).unwrap();
    std::fs::write(b.join("frames.csv"), &frames[..frames.len() - 10]).unwrap();
    let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
    fails_with(
        &["compare", a_str, b_str],
        2,
        &["frames.csv", "does not match summary.json"],
    );
    let c = dir.path().join("c");
    assert!(
        occlu(&bench_args(&["--modes", "omq"], c.to_str().unwrap()))
            .status
            .success()
    );
    std::fs::copy(c.join("frames.csv"), b.join("frames.csv")).unwrap();
    fails_with(&["plot", b_str], 2, &["does not match summary.json"]);

    // A folder another process holds is refused, naming it; once it lets
    // go, the folder is free again.
    let lock = std::fs::OpenOptions::new()
        .write(true)
        .open(a.join(".occlu.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    std::fs::write(a.join(".occlu.lock"), std::process::id().to_string()).unwrap();
    let refused = format!("occlu process {} claimed it last", std::process::id());
    fails_with(&bench_args(&["--modes", "vfc"], a_str), 2, &[".occlu.lock", &refused]);
    fails_with(&["plot", a_str], 2, &[".occlu.lock", &refused]);
    drop(lock);
    let run = tiny_run(&a);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
}

#[test]
fn a_full_disk_fails_with_exit_1_and_leaves_the_earlier_results() {
    let dir = tempfile::tempdir().unwrap();
    let mount = dir.path().join("small");
    std::fs::create_dir(&mount).unwrap();
    let mounted = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=4m", "tmpfs", mount.to_str().unwrap()])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !mounted {
        cannot_run("mounting a small tmpfs needs root");
        return;
    }
    let unmount = || {
        let _ = std::process::Command::new("umount").arg(&mount).status();
    };
    let out = mount.join("run");
    let first = tiny_run(&out);
    let earlier = std::fs::read(out.join("summary.json"));
    // Leave about 16 KiB free: too little for the charts.
    let free = || {
        let df = std::process::Command::new("df")
            .args(["-B1", "--output=avail"])
            .arg(&mount)
            .output()
            .unwrap();
        String::from_utf8_lossy(&df.stdout)
            .lines()
            .nth(1)
            .unwrap()
            .trim()
            .parse::<u64>()
            .unwrap()
    };
    let filler = vec![0u8; free().saturating_sub(16 << 10) as usize];
    let filled = std::fs::write(mount.join("filler"), filler);
    let second = tiny_run(&out);
    let after = std::fs::read(out.join("summary.json"));
    let staging_left = staged_files_left(&out);
    unmount();
    assert!(first.status.success() && filled.is_ok(), "{:?}", own_stderr(&first));
    let lines = own_stderr(&second);
    assert_eq!(second.status.code(), Some(1), "{lines:?}");
    assert!(lines.last().unwrap().contains("No space left on device"), "{lines:?}");
    assert_eq!(earlier.unwrap(), after.unwrap(), "the earlier results stand");
    assert!(!staging_left, "no partial files");
}

#[test]
fn bench_speaks_to_machines_json_github_benchmark_quiet_and_log_lines() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    // Inside the --out folder, which the run creates.
    let export = out.join("github.json");
    let out_str = out.to_str().unwrap();
    let json = occlu(&bench_args(
        &[
            "--modes",
            "vfc,omq",
            "--json",
            "--export-github-benchmark",
            export.to_str().unwrap(),
        ],
        out_str,
    ));
    assert!(json.status.success(), "{:?}", own_stderr(&json));
    // stdout is summary.json itself.
    let printed: serde_json::Value = serde_json::from_str(&stdout(&json)).unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(printed, written);
    assert!(out.join("report.md").exists(), "report.md is still written");
    // Outside a terminal, progress comes as log lines, the last at the end.
    let log = own_stderr(&json);
    assert!(
        log.iter().any(|l| l.ends_with("s left") && l.contains("frame 2 of 2")),
        "{log:?}"
    );
    // github-action-benchmark's customSmallerIsBetter: name, unit, value.
    let entries: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&export).unwrap()).unwrap();
    let entries = entries.as_array().unwrap();
    assert_eq!(entries.len(), 2 * 4, "four metrics for each of two modes");
    for e in entries {
        assert!(
            e["name"].is_string() && e["unit"].is_string() && e["value"].is_number(),
            "{e}"
        );
    }
    let omq_mean = entries.iter().find(|e| e["name"] == "omq frame_ms mean").unwrap();
    let omq = written["modes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "omq")
        .unwrap();
    assert_eq!(omq_mean["value"], omq["stats"]["frame_ms"]["mean"]);

    // A file that could not be written is refused before the run.
    let never = dir.path().join("never");
    let unwritable = dir.path().join("no-such-folder").join("bench.json");
    fails_with(
        &bench_args(
            &["--export-github-benchmark", unwritable.to_str().unwrap()],
            never.to_str().unwrap(),
        ),
        2,
        &["no-such-folder/bench.json", "No such file"],
    );
    assert!(!never.join("frames.csv").exists(), "refused before anything ran");

    let quiet = occlu(&bench_args(&["--modes", "vfc", "--quiet"], out_str));
    assert!(quiet.status.success());
    assert!(own_stderr(&quiet).is_empty(), "{:?}", own_stderr(&quiet));
}

#[test]
fn an_interrupted_run_leaves_the_earlier_results_intact() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    assert!(tiny_run(&out).status.success());
    let earlier = std::fs::read(out.join("summary.json")).unwrap();
    // A long run into the same folder, interrupted as Ctrl-C would.
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args([
            "bench",
            "--scene",
            "city:blocks=2",
            "--frames",
            "5000",
            "--resolution",
            "64x48",
        ])
        .args(["--out", out.to_str().unwrap()])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let interrupted = child.wait_with_output().unwrap();
    // It stops between frames, says so, and ends as killed by SIGINT, so a
    // calling script stops too.
    let last = own_stderr(&interrupted).pop().unwrap_or_default();
    use std::os::unix::process::ExitStatusExt as _;
    assert_eq!(interrupted.status.signal(), Some(2), "{last}");
    assert!(last.starts_with("occlu: interrupted: no results written"), "{last}");
    assert_eq!(
        std::fs::read(out.join("summary.json")).unwrap(),
        earlier,
        "the earlier results stand"
    );
    assert!(!staged_files_left(&out), "no partial files");
    // Its claim on the folder went with it.
    let next = tiny_run(&out);
    assert!(next.status.success(), "{:?}", own_stderr(&next));
}

#[test]
fn a_message_naming_a_huge_name_leaves_out_its_middle() {
    let dir = tempfile::tempdir().unwrap();
    // Two indices: the mesh's error names it.
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"name": "n".repeat(1_000_000), "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 4}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 2, "type": "SCALAR"}
        ]
    });
    let model = write(dir.path(), "m.gltf", gltf.to_string());
    let out = occlu(&["info", model.to_str().unwrap()]);
    said_one_line(&out, 2, &["mesh 'nnn", "characters left out"], "a huge mesh name");
    assert!(
        common::stderr(&out).len() < 2500,
        "{} bytes",
        common::stderr(&out).len()
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_backend_this_system_never_has_is_a_bad_flag() {
    let out = tempfile::tempdir().unwrap();
    let out = out.path().to_str().unwrap();
    for (backend, system) in [("metal", "macOS and iOS"), ("dx12", "Windows")] {
        fails_with(
            &bench_args(&["--backend", backend], out),
            2,
            &[&format!("the {backend} backend exists only on {system}")],
        );
    }
    // auto, narrowed by WGPU_BACKEND to an API with no adapter here: a
    // machine without the driver, exit 1.
    let narrowed = std::process::Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(bench_args(&[], out))
        .env("WGPU_BACKEND", "metal")
        .output()
        .unwrap();
    let said = own_stderr(&narrowed);
    assert_eq!(narrowed.status.code(), Some(1), "{said:?}");
    let last = said.last().map_or("", String::as_str);
    assert!(
        last.starts_with("occlu: error: no graphics adapter found for backend 'auto'"),
        "{said:?}"
    );
}

#[test]
fn a_bad_frame_count_names_the_flag_and_the_config_field_it_may_come_from() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (fields, said) in [
        (
            r#""frames": 0"#,
            "frames (--frames, or \"frames\" in a --config file) must be in 1..=",
        ),
        (
            r#""warmup": 100000"#,
            "warmup (--warmup, or \"warmup\" in a --config file) must be at most",
        ),
    ] {
        let config = write(
            dir.path(),
            "c.json",
            format!(r#"{{"scene": "city:blocks=1", {fields}}}"#),
        );
        fails_with(
            &[
                "bench",
                "--config",
                config.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            2,
            &[said],
        );
    }
}

/// A hostile-input review's finding: `--external-buffers` before the model
/// took the model's path as its value (and refused it as no boolean).
#[test]
fn external_buffers_before_the_model_leaves_the_model_alone() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "m.obj", THREE_OBJECTS_OBJ);
    let model = obj.to_str().unwrap();
    for flag in [
        "--external-buffers",
        "--external-buffers=false",
        "--external-buffers=true",
    ] {
        let info = occlu(&["info", flag, model]);
        assert!(info.status.success(), "{flag}: {:?}", own_stderr(&info));
        assert!(stdout(&info).contains("m.obj"), "{flag}: {}", stdout(&info));
    }
}

#[test]
fn a_run_whose_results_cannot_be_written_leaves_its_extra_files_as_they_were() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // A folder where a chart goes: the results are refused whole.
    std::fs::create_dir_all(out.join("summary.png")).unwrap();
    let (github, trace) = (write(dir.path(), "gh.json", "OLD"), write(dir.path(), "t.json", "OLD"));
    let run = occlu(&[
        "bench",
        "--scene",
        "city:blocks=1",
        "--frames",
        "2",
        "--warmup",
        "0",
        "--resolution",
        "64x48",
        "--modes",
        "vfc",
        "--out",
        out.to_str().unwrap(),
        "--export-github-benchmark",
        github.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(2), "{:?}", own_stderr(&run));
    assert!(own_stderr(&run).join(" ").contains("summary.png"));
    for file in [&github, &trace] {
        assert_eq!(std::fs::read_to_string(file).unwrap(), "OLD", "{}", file.display());
    }
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 3, "no temporary file left: {left:?}");
}
