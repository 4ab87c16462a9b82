//! The command line as a user meets it: bad input gets one clear line and a
//! non-zero exit; a small bench writes its three result files.

mod common;

use common::{THREE_OBJECTS_OBJ, occlu, own_stderr, stdout, write};

/// Runs occlu and checks it fails with exit code `code` and one line of
/// stderr that contains every one of `needles`.
fn fails_with(args: &[&str], code: i32, needles: &[&str]) {
    let out = occlu(args);
    let lines = own_stderr(&out);
    assert_eq!(out.status.code(), Some(code), "{args:?}: {lines:?}");
    assert_eq!(lines.len(), 1, "{args:?}: one line expected, got {lines:?}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{}' lacks '{n}'", lines[0]);
    }
    assert!(!lines[0].contains("panicked"), "{args:?}: {}", lines[0]);
}

/// Bench arguments that keep a run tiny.
const QUICK: &[&str] = &[
    "--scene",
    "city:blocks=1",
    "--frames",
    "2",
    "--warmup",
    "0",
    "--resolution",
    "64x48",
];

fn bench_args<'a>(extra: &[&'a str], out: &'a str) -> Vec<&'a str> {
    let mut a = vec!["bench"];
    a.extend_from_slice(QUICK);
    a.extend_from_slice(&["--out", out]);
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
        &["unknown mode 'warp'", "dr, vfc, sq, omq, ac, oracle"],
    );
    fails_with(
        &["bench", &s(&good_obj), "--frames", "0", "--out", &out],
        2,
        &["--frames must be in 1..="],
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
        &bench_args(&["--param", "omq.bogus=1"], &out),
        2,
        &["unknown parameter 'omq.bogus'", "omq.factor"],
    );
    fails_with(
        &bench_args(&["--param", "omq.om=wide"], &out),
        2,
        &["parameter 'omq.om'", "'wide'"],
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
        &["frame count must be in 1..="],
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
        &["--warmup must be at most"],
    );
    // An unwritable output directory is refused before any work.
    let blocker = write(dir.path(), "blocker", "a file, not a directory");
    let blocked = format!("{}/sub", blocker.display());
    let started = std::time::Instant::now();
    fails_with(&["bench", "--out", &blocked], 2, &["blocker"]);
    assert!(started.elapsed().as_secs() < 5, "refused before loading the city");
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
    assert_eq!(modes, ["dr", "vfc", "sq", "omq", "ac", "oracle"]);
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
        "error_pixels",
        "missed_objects",
    ] {
        assert!(header.split(',').any(|c| c == column), "frames.csv lacks {column}");
    }
    assert_eq!(lines.count(), 12, "2 frames × 6 modes");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| oracle |") && report.contains("Adapter:"));
    for chart in occlu::report::charts::CHARTS {
        assert!(report.contains(&format!("]({chart})")), "report.md links {chart}");
        let (width, height, colours) = png_colours(&out.join(chart));
        assert_eq!((width, height), (1200, 700), "{chart}");
        assert!(colours.len() > 50, "{chart} has only {} colours: is it blank?", colours.len());
    }
    // The data is drawn, not only axes: the lines of vfc and the oracle.
    let (_, _, lines) = png_colours(&out.join("frame_time.png"));
    assert!(lines.contains(&[31, 119, 180]) && lines.contains(&[20, 20, 20]), "mode lines missing");
    // `occlu plot` draws them again from the files alone.
    for chart in occlu::report::charts::CHARTS {
        std::fs::remove_file(out.join(chart)).unwrap();
    }
    let plot = occlu(&["plot", out_s]);
    assert!(plot.status.success(), "{:?}", own_stderr(&plot));
    assert!(occlu::report::charts::CHARTS.iter().all(|c| out.join(c).exists()));
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

/// Width, height and distinct colours of an RGB PNG.
fn png_colours(path: &std::path::Path) -> (u32, u32, std::collections::HashSet<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let colours = buf[..info.buffer_size()].chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    (info.width, info.height, colours)
}
