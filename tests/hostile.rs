//! Hostile inputs, as a careless CI or a hostile user hands them to occlu
//! (issue 35): links and devices where result files go, result folders
//! that lie, models that make path planning endless, signals at every
//! moment. Each must end in a clear line and the documented exit status,
//! never a clobbered file, a hang or a misleading result.

mod common;

use std::io::BufRead as _;
use std::os::unix::fs::symlink;
use std::os::unix::process::ExitStatusExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::gltf_writer::GltfWriter;
use common::{occlu, own_stderr, rewritten_copy, said_one_line, stdout, tampered_copy, write};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs occlu with `args` and checks it is refused with exit 2 in one line
/// holding `needles`.
fn refused(args: &[&str], needles: &[&str]) {
    said_one_line(&occlu(args), 2, needles, &format!("{args:?}"));
}

/// `bench` of `scene` (a model file, or `--scene` and a spec) at 64×48
/// into `out`, with `extra`: two frames of vfc unless `extra` gives
/// `--frames` or `--modes`.
fn bench_of<'a>(scene: &[&'a str], out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["bench"];
    args.extend_from_slice(scene);
    args.extend(["--warmup", "0", "--resolution", "64x48", "--out", s(out)]);
    for (flag, default) in [("--frames", "2"), ("--modes", "vfc")] {
        if !extra.contains(&flag) {
            args.extend([flag, default]);
        }
    }
    args.extend_from_slice(extra);
    args
}

/// [`bench_of`] the one-block city.
fn tiny_bench<'a>(out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    bench_of(&["--scene", "city:blocks=1"], out, extra)
}

/// A tiny run into `out`, which must succeed.
fn tiny_run(out: &Path, extra: &[&str]) {
    let run = occlu(&tiny_bench(out, extra));
    assert!(run.status.success(), "{:?}", own_stderr(&run));
}

/// The plain files of a run folder, copied into `to`.
fn copy_run(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_file() && !entry.file_name().to_string_lossy().starts_with('.') {
            std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
        }
    }
}

fn mkfifo(path: &Path) {
    assert!(Command::new("mkfifo").arg(path).status().unwrap().success());
}

/// An occlu process whose stderr is read line by line as it comes.
struct Running {
    child: Child,
    lines: Arc<Mutex<Vec<String>>>,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl Running {
    fn start(args: &[&str]) -> Running {
        let mut child = Command::new(env!("CARGO_BIN_EXE_occlu"))
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let stderr = child.stderr.take().unwrap();
        let sink = lines.clone();
        let reader = std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines() {
                sink.lock().unwrap().push(line.unwrap_or_default());
            }
        });
        Running {
            child,
            lines,
            reader: Some(reader),
        }
    }

    fn lines(&self) -> Vec<String> {
        self.lines.lock().unwrap().clone()
    }

    /// Waits up to `limit` for a line of stderr that `wanted` accepts.
    fn wait_for_line(&mut self, limit: Duration, wanted: impl Fn(&str) -> bool) -> Option<String> {
        let start = Instant::now();
        while start.elapsed() < limit {
            if let Some(line) = self.lines().into_iter().find(|l| wanted(l)) {
                return Some(line);
            }
            if self.child.try_wait().unwrap().is_some() {
                std::thread::sleep(Duration::from_millis(50));
                return self.lines().into_iter().find(|l| wanted(l));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }

    fn signal(&self, name: &str) {
        let sent = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
    }

    /// Waits up to `limit` for the process to end; kills it and returns
    /// `None` when it does not.
    fn finish(mut self, limit: Duration) -> Option<(ExitStatus, Vec<String>)> {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                self.reader.take().unwrap().join().unwrap();
                return Some((status, self.lines()));
            }
            if start.elapsed() > limit {
                let _ = self.child.kill();
                let _ = self.child.wait();
                return None;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

// Item 1: the lock and every file a command puts into --out.
#[test]
fn no_command_follows_a_link_or_opens_a_device_in_its_out_folder() {
    let dir = tempfile::tempdir().unwrap();
    let victim = write(dir.path(), "victim.txt", "keep me");
    let run = dir.path().join("run");
    tiny_run(&run, &[]);
    let lock = |out: &Path| out.join(".occlu.lock");
    let linked = |out: &Path, target: &Path| {
        std::fs::create_dir_all(out).unwrap();
        let _ = std::fs::remove_file(lock(out));
        symlink(target, lock(out)).unwrap();
    };
    let (bench, merged, stressed) = (dir.path().join("b"), dir.path().join("m"), dir.path().join("st"));
    let commands: [(&Path, Vec<&str>); 4] = [
        (&bench, tiny_bench(&bench, &[])),
        (&run, vec!["plot", s(&run)]),
        (&merged, vec!["merge", s(&run), "--out", s(&merged)]),
        (
            &stressed,
            vec!["stress", "--cases", "size-1x1", "--modes", "vfc", "--out", s(&stressed)],
        ),
    ];
    for (out, args) in &commands {
        linked(out, &victim);
        refused(args, &[".occlu.lock", "not a regular file"]);
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me", "{args:?}");
    }
    // A dangling link creates nothing, and a pipe is no lock either.
    let nowhere = dir.path().join("made-by-the-link");
    linked(&bench, &nowhere);
    refused(&commands[0].1, &[".occlu.lock", "not a regular file"]);
    assert!(!nowhere.exists(), "the link's target was created");
    std::fs::remove_file(lock(&bench)).unwrap();
    mkfifo(&lock(&bench));
    refused(&commands[0].1, &[".occlu.lock", "not a regular file"]);
    // stress.md and stress.json replace a link in --out; they do not write
    // through it.
    let stress_out = dir.path().join("stress");
    std::fs::create_dir(&stress_out).unwrap();
    symlink(&victim, stress_out.join("stress.md")).unwrap();
    let stress = occlu(&[
        "stress",
        "--cases",
        "size-1x1",
        "--modes",
        "vfc",
        "--out",
        s(&stress_out),
    ]);
    assert!(stress.status.success(), "{:?}", own_stderr(&stress));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me");
    let md = std::fs::symlink_metadata(stress_out.join("stress.md")).unwrap();
    assert!(md.is_file(), "stress.md is the report itself");
}

// Item 2.
#[test]
fn merge_copies_a_runs_regular_files_only_and_names_any_other() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    tiny_run(&run, &[]);
    let secret = write(dir.path(), "secret.txt", "s3cret");
    // Which file is replaced, and by what.
    type Plant<'a> = dyn Fn(&Path) + 'a;
    let cases: [(&str, &Plant); 3] = [
        ("report.md", &|p| symlink(&secret, p).unwrap()),
        ("report.md", &|p| mkfifo(p)),
        ("frame_time.png", &|p| symlink("/dev/zero", p).unwrap()),
    ];
    for (k, (name, plant)) in cases.iter().enumerate() {
        let copy = dir.path().join(format!("copy{k}"));
        copy_run(&run, &copy);
        std::fs::remove_file(copy.join(name)).unwrap();
        plant(&copy.join(name));
        let out = dir.path().join(format!("merged{k}"));
        let started = Instant::now();
        refused(&["merge", s(&copy), "--out", s(&out)], &[name, "not a regular file"]);
        assert!(started.elapsed() < Duration::from_secs(30), "{name}: read to its end");
        assert!(!out.exists(), "{name}: nothing merged");
    }
}

/// A sphere of `n`×`n` quads (2n² triangles) of radius 1 at the origin.
fn sphere(n: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (theta, phi) = (
                std::f32::consts::PI * j as f32 / n as f32,
                std::f32::consts::TAU * i as f32 / n as f32,
            );
            positions.push([theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()]);
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            indices.extend([k, k + n + 2, k + 1, k, k + n + 1, k + n + 2]);
        }
    }
    (positions, indices)
}

/// A GLB whose `instances` nodes all place one mesh at the origin: every
/// ray planning a walk meets every instance.
fn pile_of_instances(dir: &Path, instances: usize, mesh: (Vec<[f32; 3]>, Vec<u32>)) -> PathBuf {
    let mut w = GltfWriter::default();
    let m = w.mesh("ball", &[(&mesh.0, Some(&mesh.1), 4)]);
    let roots: Vec<usize> = (0..instances)
        .map(|k| w.node(serde_json::json!({"name": format!("n{k}"), "mesh": m})))
        .collect();
    write(dir, "pile.glb", w.glb(&roots))
}

// Item 3.
#[test]
fn path_planning_is_bounded_says_so_and_shows_progress() {
    let dir = tempfile::tempdir().unwrap();
    // 2 000 instances of a 20 000-triangle sphere in one place: 40 M
    // triangles on every ray down the grid.
    let pile = pile_of_instances(dir.path(), 2000, sphere(100));
    let written = dir.path().join("path.json");
    let started = Instant::now();
    let planning = Running::start(&["path", "gen", s(&pile), "-o", s(&written)]);
    let Some((status, lines)) = planning.finish(Duration::from_secs(120)) else {
        panic!("path gen still planning after 120 s");
    };
    let took = started.elapsed();
    assert!(status.success(), "{lines:?}");
    assert!(
        lines.iter().any(|l| l.contains("budget") && l.contains("orbit")),
        "the fallback is said: {lines:?}"
    );
    let path: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&written).unwrap()).unwrap();
    assert_eq!(path["keyframes"].as_array().unwrap().len(), 25, "an orbit: {path}");
    if took > Duration::from_secs(2) {
        assert!(
            lines.iter().any(|l| l.starts_with("planning the path:")),
            "{took:?} without progress: {lines:?}"
        );
    }
}

// Item 3: Ctrl-C while a path is planned stops it.
#[test]
fn ctrl_c_stops_path_planning() {
    let dir = tempfile::tempdir().unwrap();
    // 20 000 cubes in one place: little to draw, much to plan.
    let (cube, indices) = common::gltf_writer::cube();
    let pile = pile_of_instances(dir.path(), 20_000, (cube, indices));
    let out = dir.path().join("run");
    let mut bench = Running::start(&bench_of(&[s(&pile)], &out, &[]));
    let loaded = bench.wait_for_line(Duration::from_secs(60), |l| l.starts_with("scene: "));
    assert!(loaded.is_some(), "{:?}", bench.lines());
    std::thread::sleep(Duration::from_millis(500));
    bench.signal("INT");
    let Some((status, lines)) = bench.finish(Duration::from_secs(20)) else {
        panic!("Ctrl-C did not stop the run within 20 s");
    };
    assert_eq!(status.signal(), Some(2), "{lines:?}");
    assert!(lines.last().unwrap().starts_with("occlu: interrupted"), "{lines:?}");
}

/// A config of a matrix of two runs of the one-block city.
fn matrix_of_two(dir: &Path) -> PathBuf {
    write(
        dir,
        "two.json",
        r#"{"runs": [{"scene": "city:blocks=1"}, {"scene": "city:blocks=1,seed=2"}],
            "modes": ["vfc"], "frames": 2, "warmup": 0, "resolution": "64x48"}"#,
    )
}

// Item 4.
#[test]
fn merge_names_the_runs_a_matrix_lacks_and_refuses_them_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let matrix = matrix_of_two(dir.path());
    let shard = dir.path().join("shard1");
    let run = occlu(&[
        "bench",
        "--config",
        s(&matrix),
        "--shard",
        "1/2",
        "--quiet",
        "--out",
        s(&shard),
    ]);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let out = dir.path().join("merged");
    refused(
        &["merge", s(&shard), "--out", s(&out)],
        &["02", "1 of the matrix's 2 runs", "--allow-partial"],
    );
    assert!(!out.exists(), "nothing merged");
    let partial = occlu(&["merge", s(&shard), "--out", s(&out), "--allow-partial"]);
    assert!(partial.status.success(), "{:?}", own_stderr(&partial));
    assert!(
        own_stderr(&partial).iter().any(|l| l.contains("02")),
        "{:?}",
        own_stderr(&partial)
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("run 02"), "{report}");
    let help = stdout(&occlu(&["merge", "--help"]));
    assert!(help.contains("--allow-partial"));
    // A summary.json whose matrix lists more runs than a matrix may is
    // refused: merge counted through every place it lacked, without end.
    let run = std::fs::read_dir(&shard)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .find(|path| path.join("summary.json").exists())
        .unwrap();
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    summary["matrix"]["runs"] = u64::MAX.into();
    std::fs::write(run.join("summary.json"), summary.to_string()).unwrap();
    let lying = dir.path().join("lying");
    refused(
        &["merge", s(&shard), "--out", s(&lying), "--allow-partial"],
        &[
            "summary.json",
            "its matrix lists 18446744073709551615 runs, not 1 to the 10000 a matrix may",
        ],
    );
}

/// A one-keyframe path over the one-block city with `extra` fields at the
/// top and `key` fields in its keyframe.
fn path_with(dir: &Path, name: &str, top: &str, key: &str) -> PathBuf {
    write(
        dir,
        name,
        format!(r#"{{"frames": 2, {top} "keyframes": [{{"time": 0, "position": [0, 30, -40], {key}}}]}}"#),
    )
}

// Item 5.
#[test]
fn a_zero_up_or_one_along_the_view_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let cases = [
        (
            "top.json",
            r#""up": [0, 0, 0],"#,
            r#""target": [0, 0, 0]"#,
            "up must not be zero",
        ),
        (
            "key.json",
            "",
            r#""target": [0, 0, 0], "up": [0, 0, 0]"#,
            "keyframe 0: up must not be zero",
        ),
        (
            "along.json",
            "",
            r#""direction": [0, -1, 0]"#,
            "keyframe 0: up [0, 1, 0] lies along the view",
        ),
    ];
    for (name, top, key, message) in cases {
        let path = path_with(dir.path(), name, top, key);
        refused(&tiny_bench(&out, &["--path", s(&path)]), &[name, message]);
        refused(
            &[
                "export",
                "--scene",
                "city:blocks=1",
                "--path",
                s(&path),
                "-o",
                s(&dir.path().join("x.glb")),
            ],
            &[name, message],
        );
    }
    let across = path_with(
        dir.path(),
        "across.json",
        "",
        r#""direction": [0, -1, 0], "up": [0, 0, 1]"#,
    );
    tiny_run(&out, &["--path", s(&across)]);
}

// Item 6.
#[test]
fn compare_and_merge_take_statistics_only_from_valid_rows_of_frames_csv() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base");
    tiny_run(&base, &["--modes", "vfc,dr"]);
    let bad: [(&str, f64); 3] = [("NaN", f64::NAN), ("inf", f64::INFINITY), ("-1", -1.0)];
    for (k, (shown, value)) in bad.into_iter().enumerate() {
        let new = dir.path().join(format!("bad{k}"));
        tampered_copy(&base, &new, &|r| {
            if r.mode == "vfc" && r.frame == 1 {
                r.frame_ms = value;
            }
        });
        refused(
            &["compare", s(&base), s(&new)],
            &["frames.csv", "vfc", "frame 1", "frame_ms", shown],
        );
        refused(
            &["merge", s(&new), "--out", s(&dir.path().join("m"))],
            &["frames.csv", "frame_ms", shown],
        );
    }
    // Rows per mode must be the run's frames.
    let short = dir.path().join("short");
    rewritten_copy(&base, &short, &mut |rows| {
        rows.retain(|r| !(r.mode == "dr" && r.frame == 0))
    });
    refused(
        &["compare", s(&base), s(&short)],
        &["frames.csv", "dr", "1 row", "2 frames"],
    );
    // Without its fingerprint, a frames.csv of its header alone is no run.
    let bare = dir.path().join("bare");
    rewritten_copy(&base, &bare, &mut |rows| rows.clear());
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(bare.join("summary.json")).unwrap()).unwrap();
    summary.as_object_mut().unwrap().remove("frames_csv");
    std::fs::write(bare.join("summary.json"), summary.to_string()).unwrap();
    refused(
        &["compare", s(&base), s(&bare), "--allow-missing"],
        &["frames.csv", "0 rows", "2 frames"],
    );
    // Statistics come from frames.csv for merge as for compare: an edited
    // mean in summary.json changes neither.
    let edited = dir.path().join("edited");
    copy_run(&base, &edited);
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(edited.join("summary.json")).unwrap()).unwrap();
    let measured = summary["modes"][0]["stats"]["frame_ms"]["mean"].as_f64().unwrap();
    summary["modes"][0]["stats"]["frame_ms"]["mean"] = 999.0.into();
    std::fs::write(edited.join("summary.json"), summary.to_string()).unwrap();
    let merged = dir.path().join("merged");
    let merge = occlu(&["merge", s(&edited), "--out", s(&merged)]);
    assert!(merge.status.success(), "{:?}", own_stderr(&merge));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(merged.join("merged.json")).unwrap()).unwrap();
    assert_eq!(
        m["runs"][0]["modes"][0]["results"][0]["frame_ms"].as_f64(),
        Some(measured)
    );
    let same = occlu(&["compare", s(&base), s(&edited)]);
    assert!(same.status.success(), "{:?}", own_stderr(&same));
}

// Item 7.
#[test]
fn no_output_may_be_an_input_or_one_of_the_runs_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    tiny_run(&run, &[]);
    let summary = std::fs::read(run.join("summary.json")).unwrap();
    let own = run.join("summary.json");
    refused(
        &tiny_bench(&run, &["--export-github-benchmark", s(&own)]),
        &["summary.json", "one of the run's own files"],
    );
    refused(
        &tiny_bench(&run, &["--trace", s(&own)]),
        &["summary.json", "one of the run's own files"],
    );
    assert_eq!(std::fs::read(&own).unwrap(), summary);
    // The animation is one of them too, where --animate writes it.
    let animation = run.join("flythrough.png");
    refused(
        &tiny_bench(&run, &["--animate", "--trace", s(&animation)]),
        &["flythrough.png", "one of the run's own files"],
    );
    // Nor may two outputs be one file, even by two spellings.
    let export = dir.path().join("bench.json");
    let same = dir.path().join(".").join("bench.json");
    refused(
        &tiny_bench(&run, &["--export-github-benchmark", s(&export), "--trace", s(&same)]),
        &["bench.json", "another output of this command"],
    );
    assert!(!export.exists(), "nothing written");
    let report = std::fs::read(run.join("report.md")).unwrap();
    let other = dir.path().join("other");
    tiny_run(&other, &[]);
    refused(
        &["merge", s(&other), "--out", s(&run)],
        &["holds a bench run", "report.md"],
    );
    assert_eq!(std::fs::read(run.join("report.md")).unwrap(), report);
    let merged = dir.path().join("merged");
    assert!(occlu(&["merge", s(&other), "--out", s(&merged)]).status.success());
    refused(&tiny_bench(&merged, &[]), &["merged.json", "holds a merged result"]);

    let model = write(dir.path(), "model.obj", common::THREE_OBJECTS_OBJ);
    let path = write(
        dir.path(),
        "path.json",
        r#"{"frames": 2, "keyframes": [{"time": 0, "position": [2, 2, 9], "target": [2, 0, 0]}]}"#,
    );
    let config = write(dir.path(), "config.json", r#"{"frames": 2}"#);
    for args in [
        vec!["render", s(&model), "--frame", "0", "--mode", "vfc", "-o", s(&model)],
        vec![
            "render",
            s(&model),
            "--path",
            s(&path),
            "--frame",
            "0",
            "--mode",
            "vfc",
            "-o",
            s(&path),
        ],
        vec!["export", s(&model), "--path", s(&path), "-o", s(&path)],
        vec!["flythrough", s(&model), "--modes", "vfc", "-o", s(&model)],
        vec![
            "flythrough",
            s(&model),
            "--path",
            s(&path),
            "--modes",
            "vfc",
            "-o",
            s(&path),
        ],
        vec!["path", "gen", s(&model), "-o", s(&model)],
        vec![
            "bench",
            s(&model),
            "--config",
            s(&config),
            "--modes",
            "vfc",
            "--out",
            s(&dir.path().join("b")),
            "--export-github-benchmark",
            s(&config),
        ],
        vec![
            "bench",
            s(&model),
            "--path",
            s(&path),
            "--modes",
            "vfc",
            "--out",
            s(&dir.path().join("b")),
            "--trace",
            s(&path),
        ],
    ] {
        refused(&args, &["is an input"]);
    }
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        r#"{"frames": 2, "keyframes": [{"time": 0, "position": [2, 2, 9], "target": [2, 0, 0]}]}"#
    );
    assert_eq!(std::fs::read_to_string(&model).unwrap(), common::THREE_OBJECTS_OBJ);
    assert_eq!(std::fs::read_to_string(&config).unwrap(), r#"{"frames": 2}"#);
    // An export is GLB, so named: as .obj, occlu would refuse to read it.
    refused(&["export", s(&model), "-o", s(&model)], &["occlu writes GLB only"]);
    refused(
        &["export", s(&model), "-o", "x.GLTF"],
        &["occlu writes GLB only", ".gltf file"],
    );
    assert_eq!(std::fs::read_to_string(&model).unwrap(), common::THREE_OBJECTS_OBJ);
}

// Item 7, for issue 37's outputs: one that cannot be written is refused
// before the run (one line: no adapter, no progress), and a run that made
// its --out takes it away again.
#[test]
fn a_flythrough_or_trace_that_cannot_be_written_is_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let nowhere = dir.path().join("no-such-folder").join("fly.png");
    let out = dir.path().join("run");
    refused(
        &tiny_bench(&out, &["--trace", s(&nowhere)]),
        &["no-such-folder", "No such file"],
    );
    assert!(!out.exists(), "the folder the run made is gone");
    let flythrough = |output: &Path| {
        vec![
            "flythrough".to_string(),
            "--scene".into(),
            "city:blocks=1".into(),
            "--modes".into(),
            "vfc".into(),
            "-o".into(),
            s(output).into(),
        ]
    };
    for (output, needle) in [
        (&nowhere, "No such file"),
        (&dir.path().to_path_buf(), "is a directory"),
    ] {
        let args = flythrough(output);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&args, &[s(output), needle]);
    }
}

// Item 9, for issue 37: Ctrl-C stops a flythrough between frames, and no
// animation is written.
#[test]
fn ctrl_c_stops_a_flythrough_and_writes_no_animation() {
    let dir = tempfile::tempdir().unwrap();
    let fly = dir.path().join("fly.png");
    let mut running = Running::start(&[
        "flythrough",
        "--scene",
        "city:blocks=2",
        "--modes",
        "vfc,roc",
        "--frames",
        "5000",
        "--resolution",
        "64x48",
        "-o",
        s(&fly),
    ]);
    let flying = running.wait_for_line(Duration::from_secs(60), |l| l.contains("frame 1 of 5000"));
    assert!(flying.is_some(), "{:?}", running.lines());
    running.signal("INT");
    let Some((status, lines)) = running.finish(Duration::from_secs(20)) else {
        panic!("Ctrl-C did not stop the flythrough within 20 s");
    };
    assert_eq!(status.signal(), Some(2), "{lines:?}");
    assert_eq!(
        lines.last().map(String::as_str),
        Some("occlu: interrupted: no animation written"),
        "{lines:?}"
    );
    assert!(!fly.exists(), "no animation");
}

// Item 8.
#[test]
fn merged_runs_have_names_of_their_own_whatever_the_order_of_the_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    // With the oracle, so each run has its chart.
    tiny_run(&a, &["--modes", "vfc,oracle"]);
    tiny_run(&b, &["--modes", "vfc,oracle", "--frames", "3"]);
    let (ab, ba) = (dir.path().join("ab"), dir.path().join("ba"));
    for (out, first, second) in [(&ab, &a, &b), (&ba, &b, &a)] {
        let merged = occlu(&["merge", s(first), s(second), "--out", s(out)]);
        assert!(merged.status.success(), "{:?}", own_stderr(&merged));
        let m: occlu::report::merge::Merged =
            serde_json::from_str(&std::fs::read_to_string(out.join("merged.json")).unwrap()).unwrap();
        assert_eq!(m.runs.len(), 2);
        assert_ne!(m.runs[0].name, m.runs[1].name, "two runs, two names");
        for run in &m.runs {
            let chart = run.chart.as_deref().unwrap();
            assert!(chart.ends_with(".png") && out.join(chart).is_file(), "{chart}");
        }
    }
    for (base, new) in [(&ab, &ba), (&ba, &ab)] {
        let compared = occlu(&["compare", s(base), s(new)]);
        assert!(compared.status.success(), "{:?}", own_stderr(&compared));
    }
}

/// Whether `out` was left behind.
fn left(out: &Path) -> Vec<String> {
    std::fs::read_dir(out)
        .map(|e| {
            e.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

// Item 9.
#[test]
fn a_run_that_ends_without_results_takes_the_folder_it_made_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let long_bench = |out: &Path| {
        vec![
            "bench".to_string(),
            "--scene".into(),
            "city:blocks=2".into(),
            "--frames".into(),
            "5000".into(),
            "--resolution".into(),
            "64x48".into(),
            "--out".into(),
            s(out).into(),
        ]
    };
    let loading = |out: &Path| {
        vec![
            "bench".to_string(),
            "--scene".into(),
            "city:blocks=24".into(),
            "--out".into(),
            s(out).into(),
        ]
    };
    let stress = |out: &Path| vec!["stress".to_string(), "--out".into(), s(out).into()];
    type Args = dyn Fn(&Path) -> Vec<String>;
    // What to run, how long to let it run, and the signals to send.
    let cases: [(&str, &Args, u64, &[&str]); 4] = [
        ("SIGINT while loading", &loading, 500, &["INT"]),
        ("two SIGINTs", &long_bench, 1500, &["INT", "INT"]),
        ("SIGTERM", &long_bench, 1500, &["TERM"]),
        ("SIGINT in stress", &stress, 1500, &["INT"]),
    ];
    for (k, (what, args, after, signals)) in cases.into_iter().enumerate() {
        let out = dir.path().join(format!("out{k}"));
        let args = args(&out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let running = Running::start(&args);
        std::thread::sleep(Duration::from_millis(after));
        for signal in signals {
            running.signal(signal);
            std::thread::sleep(Duration::from_millis(20));
        }
        let Some((status, lines)) = running.finish(Duration::from_secs(60)) else {
            panic!("{what}: still running a minute later");
        };
        assert!(status.signal().is_some(), "{what}: {status:?} {lines:?}");
        assert_eq!(left(&out), Vec::<String>::new(), "{what}: {lines:?}");
        assert!(!out.exists(), "{what}: the folder it made is gone");
        // Review finding 9: so no line may say that its contents stand.
        assert!(
            lines.iter().all(|l| !l.contains("earlier contents")),
            "{what}: {lines:?}"
        );
    }
}

// Item 9: a merge that fails on a full disk.
#[test]
fn a_merge_that_fails_on_a_full_disk_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    tiny_run(&run, &[]);
    let mount = dir.path().join("small");
    std::fs::create_dir(&mount).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs", s(&mount)])
        .output()
        .is_ok_and(|o| o.status.success());
    if !mounted {
        eprintln!("skipped: mounting a small tmpfs needs root");
        return;
    }
    let out = mount.join("merged");
    let merge = occlu(&["merge", s(&run), "--out", s(&out)]);
    let gone = !out.exists();
    let _ = Command::new("umount").arg(&mount).status();
    assert_eq!(merge.status.code(), Some(1), "{:?}", own_stderr(&merge));
    assert!(gone, "the folder it made is gone");
}

// A hostile-input review's finding: an extra output that cannot be
// written (a full disk) fails the run, and the results folder stays as it
// was: the earlier run's results, or no folder where the run made it.
#[test]
fn a_run_whose_trace_or_export_cannot_be_written_leaves_the_results_folder_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let earlier = dir.path().join("earlier");
    tiny_run(&earlier, &["--modes", "swr"]);
    let summary = || std::fs::read_to_string(earlier.join("summary.json")).unwrap();
    let before = summary();
    for flag in ["--export-github-benchmark", "--trace"] {
        let over = occlu(&tiny_bench(&earlier, &[flag, "/dev/full"]));
        assert_eq!(over.status.code(), Some(1), "{flag}: {:?}", own_stderr(&over));
        assert!(
            summary() == before,
            "{flag}: the earlier run's summary.json was replaced"
        );
        let fresh = dir.path().join(format!("fresh{flag}"));
        let new = occlu(&tiny_bench(&fresh, &[flag, "/dev/full"]));
        assert_eq!(new.status.code(), Some(1), "{flag}: {:?}", own_stderr(&new));
        assert!(!fresh.exists(), "{flag}: the folder it made is gone");
    }
}

// Item 11.
#[test]
fn duplicate_keys_are_refused_in_configs_and_paths() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    for (name, json) in [
        ("top.json", r#"{"frames": 2, "frames": 3}"#),
        ("run.json", r#"{"runs": [{"frames": 2, "frames": 3}]}"#),
        ("lists.json", r#"{"scenes": ["city"], "scenes": ["forest"]}"#),
    ] {
        let config = write(dir.path(), name, json);
        refused(&tiny_bench(&out, &["--config", s(&config)]), &[name, "duplicate"]);
    }
    let path = path_with(
        dir.path(),
        "path.json",
        r#""near": 1, "near": 2,"#,
        r#""target": [0, 0, 0]"#,
    );
    refused(&tiny_bench(&out, &["--path", s(&path)]), &["path.json", "duplicate"]);
}

#[test]
fn swr_records_the_buffer_it_used() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    tiny_run(&out, &["--modes", "swr", "--param", "swr.resolution=4096x4096"]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["modes"][0]["name"], "swr");
    assert_eq!(summary["modes"][0]["parameters"]["resolution"], "64x48");
}

/// A unit cube's OBJ, moved by `offset` along x.
fn cube_obj(offset: f64) -> String {
    let mut obj = String::from("o cube\n");
    for k in 0..8 {
        let bit = |b: usize| f64::from(u8::from(k & b != 0));
        obj += &format!("v {:?} {} {}\n", offset + bit(1), bit(2), bit(4));
    }
    for t in common::gltf_writer::cube_indices().chunks(3) {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    obj
}

#[test]
fn a_model_too_far_out_for_its_size_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let far = write(dir.path(), "far.obj", cube_obj(1e17));
    let info = occlu(&["info", s(&far), "--json"]);
    assert!(info.status.success(), "{:?}", own_stderr(&info));
    let facts: serde_json::Value = serde_json::from_str(&stdout(&info)).unwrap();
    let warnings = facts["warnings"].to_string();
    assert!(
        warnings.contains("1e17") && warnings.contains("nearer the origin"),
        "{warnings}"
    );
    let near = write(dir.path(), "near.obj", cube_obj(1e6));
    let facts: serde_json::Value = serde_json::from_str(&stdout(&occlu(&["info", s(&near), "--json"]))).unwrap();
    assert_eq!(facts["warnings"], serde_json::json!([]));
    let out = dir.path().join("run");
    let bench = occlu(&bench_of(&[s(&far)], &out, &[]));
    assert!(bench.status.success(), "{:?}", own_stderr(&bench));
    assert!(
        own_stderr(&bench)
            .iter()
            .any(|l| l.contains("no object was visible in any frame")),
        "{:?}",
        own_stderr(&bench)
    );
}

#[test]
fn names_from_files_reach_stderr_and_results_as_themselves_escaped_only_where_shown() {
    let dir = tempfile::tempdir().unwrap();
    // An object with a tab, a right-to-left override and an escape sequence
    // in its name and a degenerate triangle (so a warning names it), in a
    // file whose name holds an escape sequence and a newline.
    let name = "wall\tx\u{202E}gpj.exe\u{1b}[2J";
    let obj = format!("o {name}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\nf 1 1 1\n");
    let model = write(dir.path(), "ev\u{1b}il\nname.obj", obj);
    let out = dir.path().join("run");
    let bench = occlu(&bench_of(&[s(&model)], &out, &[]));
    assert!(bench.status.success(), "{:?}", own_stderr(&bench));
    let err = common::stderr(&bench);
    assert!(
        !err.contains('\u{1b}') && !err.contains('\u{202E}') && !err.contains('\t'),
        "{err:?}"
    );
    assert!(err.contains("ev\\u{1b}il\\nname.obj"), "{err}");
    assert!(err.contains("wall\\tx\\u{202e}gpj.exe\\u{1b}[2J"), "{err}");
    // summary.json holds the name as the file has it (JSON escapes it).
    let summary: occlu::report::Summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary.scene.facts.warnings[0].contains(name),
        "{:?}",
        summary.scene.facts.warnings
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(!report.contains('\u{202E}') && !report.contains('\u{1b}'), "{report}");
    // Object names are kept as they are, for summary.json and missed.csv
    // to escape as each needs.
    let mut w = GltfWriter::default();
    let (p, i) = common::gltf_writer::cube();
    let mesh = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let root = w.node(serde_json::json!({"name": "door\n2\u{202E}", "mesh": mesh}));
    let glb = write(dir.path(), "door.glb", w.glb(&[root]));
    let options = occlu::scene::LoadOptions::default();
    let scene = occlu::scene::load(&occlu::scene::SceneSpec::File(glb), &options).unwrap();
    assert_eq!(scene.objects[0].name, "door\n2\u{202E}");
}

#[test]
fn small_input_faults_get_the_right_status_and_a_plain_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let bogus = Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(tiny_bench(&out, &[]))
        .env("WGPU_BACKEND", "bogus")
        .output()
        .unwrap();
    said_one_line(&bogus, 2, &["WGPU_BACKEND", "bogus"], "WGPU_BACKEND=bogus");

    let far = path_with(dir.path(), "near.json", r#""near": 1e308,"#, r#""target": [0, 0, 0]"#);
    let run = occlu(&tiny_bench(&out, &["--path", s(&far)]));
    said_one_line(&run, 2, &["near.json", "got 1e308"], "near 1e308");
    assert!(own_stderr(&run)[0].len() < 200, "{:?}", own_stderr(&run));

    let tiny = write(dir.path(), "tiny.obj", "v 0 0 0\nv 1e-9 0 0\nv 0 1e-9 0\nf 1 2 3\n");
    let x = dir.path().join("x.json");
    let generated = occlu(&["path", "gen", s(&tiny), "-o", s(&x)]);
    said_one_line(&generated, 2, &["tiny.obj"], "path gen tiny.obj");
    assert!(
        !own_stderr(&generated)[0].contains("x.json"),
        "{:?}",
        own_stderr(&generated)
    );

    let unknown = write(dir.path(), "unknown.json", r#"{"frams": 2}"#);
    refused(
        &tiny_bench(&out, &["--config", s(&unknown)]),
        &[
            "unknown field `frams`",
            "`sweep`",
            "`runs`",
            "`models`",
            "`scenes`",
            "`paths`",
        ],
    );

    for command in [
        vec!["bench", "--frames", "4294967296"],
        vec!["path", "gen", "--frames", "0", "-o", "x.json"],
        vec!["export", "--frames", "100001", "-o", "x.glb"],
    ] {
        refused(&command, &["1..=100000"]);
    }
    refused(&["bench", "--warmup", "10001"], &["0..=10000"]);

    // A byte order mark, as Windows editors write, is not JSON's business.
    let config = write(dir.path(), "bom.json", "\u{feff}{\"frames\": 2}");
    let path = path_with(dir.path(), "path.json", "", r#""target": [0, 0, 0]"#);
    let with_bom = [b"\xef\xbb\xbf".as_slice(), &std::fs::read(&path).unwrap()].concat();
    std::fs::write(&path, with_bom).unwrap();
    tiny_run(&out, &["--config", s(&config), "--path", s(&path)]);
}

// The review of the fixes above (main at 75d5cfd), finding by finding;
// findings 1, 4, 5, 8 and the loaders' messages of 9 are tested beside
// their code (tests/loaders.rs, tests/compressed.rs, unit tests).

// Review finding 2: a glTF file's buffer files are inputs too.
#[test]
fn no_output_may_be_a_gltf_buffer_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::default();
    let (p, i) = common::gltf_writer::cube();
    let m = w.mesh("cube", &[(&p, Some(&i), 4)]);
    let n = w.node(serde_json::json!({"mesh": m}));
    let bin = write(dir.path(), "cube.bin", w.bin());
    let model = write(dir.path(), "cube.gltf", w.gltf_external(&[n], "cube.bin"));
    let out = dir.path().join("run");
    for args in [
        vec!["render", s(&model), "--frame", "0", "--mode", "vfc", "-o", s(&bin)],
        vec!["export", s(&model), "-o", s(&bin)],
        vec!["path", "gen", s(&model), "-o", s(&bin)],
        bench_of(&[s(&model)], &out, &["--export-github-benchmark", s(&bin)]),
    ] {
        refused(&args, &["cube.bin", "is an input"]);
    }
    assert_eq!(std::fs::read(&bin).unwrap(), w.bin());
    assert!(!out.exists(), "the refused bench's folder is gone");
}

/// An OBJ of `n` unit boxes in rows of ten: its exported scene, its
/// picture and its planned path are each larger than a page.
fn grid_of_boxes(n: u32) -> String {
    let boxes: Vec<(String, glam::DVec3, glam::DVec3)> = (0..n)
        .map(|k| {
            let min = glam::DVec3::new(f64::from(k % 10) * 3.0, 0.0, f64::from(k / 10) * 3.0);
            (format!("box{k}"), min, min + glam::DVec3::ONE)
        })
        .collect();
    common::boxes_obj(&boxes)
}

// Review finding 3: once path planning, which hears Ctrl-C, is done,
// render, export and path gen end at once on a signal, as the README
// says, rather than hear it and run on to write their output.
#[test]
fn after_planning_a_signal_ends_render_export_and_path_gen_at_once() {
    use std::io::Read as _;
    use std::os::fd::AsRawFd as _;
    use std::os::unix::fs::OpenOptionsExt as _;
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "boxes.obj", grid_of_boxes(100));
    let commands: [&[&str]; 3] = [
        &["export"],
        &["render", "--frame", "0", "--mode", "vfc"],
        &["path", "gen"],
    ];
    for (k, command) in commands.into_iter().enumerate() {
        // The output is a pipe of one page that nothing empties: the
        // command writes its first bytes after every step before it (the
        // path planned), then waits there.
        let fifo = dir.path().join(format!("out{k}"));
        mkfifo(&fifo);
        let mut reader = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(&fifo)
            .unwrap();
        // SAFETY: an fcntl on a descriptor this test owns, with an integer.
        let resized = unsafe { libc::fcntl(reader.as_raw_fd(), libc::F_SETPIPE_SZ, 4096) };
        assert!(resized >= 0, "F_SETPIPE_SZ");
        let mut args = command.to_vec();
        args.extend([s(&model), "-o", s(&fifo)]);
        let mut running = Running::start(&args);
        let start = Instant::now();
        while !matches!(reader.read(&mut [0]), Ok(1)) {
            let ended = running.child.try_wait().unwrap();
            assert!(
                ended.is_none() && start.elapsed() < Duration::from_secs(60),
                "{command:?}: wrote nothing ({ended:?}): {:?}",
                running.lines()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        running.signal("TERM");
        let Some((status, lines)) = running.finish(Duration::from_secs(10)) else {
            panic!("{command:?}: still running 10 s after SIGTERM");
        };
        assert_eq!(status.signal(), Some(libc::SIGINT), "{command:?}: {lines:?}");
    }
}

// Review finding 6: values no run can have measured, though each is a
// number of 0 or more.
#[test]
fn compare_merge_and_plot_refuse_impossible_times_counts_and_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base");
    tiny_run(&base, &[]);
    type Edit = dyn Fn(&mut occlu::measure::FrameStats);
    let cases: [(&str, &Edit, &[&str]); 5] = [
        ("time", &|r| r.frame_ms = 1e308, &["frame_ms is 1e308"]),
        (
            "camera",
            &|r| r.eye_x = Some(f64::INFINITY),
            &["eye_x is", "not a finite number"],
        ),
        (
            "triangles",
            &|r| r.triangles_drawn = 100_000_000_000,
            &["triangles_drawn is 100000000000", "triangles in the scene"],
        ),
        (
            "missed",
            &|r| {
                r.visible_objects = Some(1);
                r.missed_objects = Some(2);
            },
            &["missed_objects is 2", "1 visible_objects"],
        ),
        ("depth", &|r| r.max_depth_error = Some(2.0), &["max_depth_error is 2"]),
    ];
    for (name, edit, needles) in cases {
        let new = dir.path().join(name);
        tampered_copy(&base, &new, &|r| {
            if r.frame == 1 {
                edit(r);
            }
        });
        let needles = [&["frames.csv", "frame 1"], needles].concat();
        refused(&["compare", s(&base), s(&new)], &needles);
        refused(&["merge", s(&new), "--out", s(&dir.path().join("m"))], &needles);
        refused(&["plot", s(&new)], &needles);
    }
}

// Review finding 7.
#[test]
fn a_configuration_value_of_the_wrong_type_is_named_by_its_field() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    for (name, json, field) in [
        ("sweep.json", r#"{"sweep": []}"#, "sweep: invalid type: sequence"),
        (
            "size.json",
            r#"{"resolution": [160, 120]}"#,
            "resolution: invalid type: sequence",
        ),
        ("count.json", r#"{"frames": "x"}"#, "frames: invalid type: string"),
        (
            "second.json",
            r#"{"runs": [{"scene": "city:blocks=1"}, {"warmup": -1}]}"#,
            "runs[1]: warmup: invalid value: integer `-1`",
        ),
        // Fields by position would pass the check of their names.
        (
            "array.json",
            r#"[null, "city:blocks=1", null, null, ["vfc"], 2, null, null, null, null,
                null, null, null, null, null, null, null, null, null, null]"#,
            "a configuration is a JSON object of fields",
        ),
        (
            "run-array.json",
            r#"{"runs": [[null, "city:blocks=1"]]}"#,
            "runs[0]: a configuration is a JSON object of fields",
        ),
        // An empty path would name the configuration's own folder.
        ("empty-out.json", r#"{"out": ""}"#, "out: an empty path names no file"),
        (
            "empty-path.json",
            r#"{"runs": [{"path": ""}]}"#,
            "runs[0]: path: an empty path names no file",
        ),
    ] {
        let config = write(dir.path(), name, json);
        refused(&tiny_bench(&out, &["--config", s(&config)]), &[name, field]);
    }
}

// Review finding 9: messages that left out what a user needs.
#[test]
fn messages_list_the_values_allowed_and_name_the_file_at_fault() {
    refused(
        &["bench", "--backend", "bogus"],
        &["'bogus'", "--backend", "auto", "vulkan", "gl"],
    );
    refused(
        &["compare", "a", "b", "--metric", "bogus"],
        &["'bogus'", "--metric", "frame_ms", "triangles_drawn"],
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let none = write(dir.path(), "none.json", r#"{"modes": []}"#);
    let listed = write(dir.path(), "listed.json", r#"{"runs": [{"modes": []}]}"#);
    for config in [&none, &listed] {
        refused(
            &["bench", "--config", s(config), "--out", s(&out)],
            &[s(config), "no modes given"],
        );
    }
    // Flags that make the fault are not blamed on the file.
    let fine = write(dir.path(), "fine.json", r#"{"frames": 2}"#);
    let flags = occlu(&["bench", "--config", s(&fine), "--sweep", "bogus", "--out", s(&out)]);
    said_one_line(&flags, 2, &["--sweep 'bogus'"], "--sweep bogus");
    assert!(!own_stderr(&flags)[0].contains("fine.json"), "{:?}", own_stderr(&flags));
}

// The second review of issue 35: a single-file output is written through a
// temporary file beside it, and whatever was planted under that file's name
// (a link to another file, a FIFO) is unlinked, never written through or
// opened.
#[test]
fn a_link_or_fifo_planted_as_an_outputs_temporary_file_is_neither_written_nor_waited_on() {
    let dir = tempfile::tempdir().unwrap();
    let victim = write(dir.path(), "victim.txt", "precious\n");
    let glb = dir.path().join("o.glb");
    symlink(&victim, dir.path().join("o.glb.occlu-partial")).unwrap();
    let export = occlu(&["export", "--scene", "city:blocks=1", "-o", s(&glb)]);
    assert!(export.status.success(), "{:?}", own_stderr(&export));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    assert!(std::fs::symlink_metadata(&glb).unwrap().is_file());
    assert!(std::fs::read(&glb).unwrap().starts_with(b"glTF"));

    let png = dir.path().join("o.png");
    mkfifo(&dir.path().join("o.png.occlu-partial"));
    let mut render = Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(["render", "--scene", "city:blocks=1", "--frame", "0", "--mode", "vfc"])
        .args(["--resolution", "64x48", "-o", s(&png)])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = render.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            render.kill().unwrap();
            panic!("render waited on the FIFO for 60 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "{status:?}");
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
}

// The second review of issue 35: a picture smaller than --scale is shrunk
// to one pixel a panel, not divided by zero.
#[test]
fn a_flythrough_smaller_than_its_scale_shrinks_each_panel_to_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("a.png");
    let run = occlu(&[
        "flythrough",
        "--scene",
        "city:blocks=1",
        "--frames",
        "2",
        "--resolution",
        "7x5",
        "--modes",
        "vfc",
        "--scale",
        "8",
        "-o",
        s(&output),
    ]);
    assert!(run.status.success(), "{:?}", own_stderr(&run));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&output).unwrap()));
    let reader = decoder.read_info().unwrap();
    assert_eq!(reader.info().animation_control().map(|a| a.num_frames), Some(2));
}

#[test]
fn a_model_too_large_or_too_small_for_a_generated_path_is_named_so() {
    let dir = tempfile::tempdir().unwrap();
    for (size, across) in [("large", 1e13), ("small", 1e-14)] {
        let obj = write(
            dir.path(),
            &format!("{size}.obj"),
            format!("v 0 0 0\nv {across:e} 0 0\nv 0 {across:e} 0\nf 1 2 3\n"),
        );
        let written = dir.path().join(format!("{size}.json"));
        refused(
            &["path", "gen", s(&obj), "-o", s(&written)],
            &[
                &format!("units across, too {size} to make a path from"),
                "write the path by hand",
            ],
        );
        assert!(!written.exists(), "no path written for the {size} model");
    }
}
