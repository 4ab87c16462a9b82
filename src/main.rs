//! The `occlu` command line: parses arguments, calls the library, prints,
//! and maps errors to one line and an exit code (2: bad input, 1: a failure
//! while running).

use std::fmt::Write as _;
use std::io::{IsTerminal as _, Write as _};
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::Instant;

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use occlu::animation::{AnimationError, AnimationOptions, DEFAULT_SCALE, FrameRange, MAX_SCALE};
use occlu::bench::{BenchError, BenchEvent, execute};
use occlu::camera::generate::{PathRequest, plan_heard};
use occlu::camera::path::{CameraPath, PathError};
use occlu::config::{BenchConfig, BenchPlan, ConfigError, load_options, scene_spec};
use occlu::cull::{ModeError, ModeParams, parse_modes};
use occlu::gpu::{BackendChoice, Resolution};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::input::ByteSize;
use occlu::matrix::{Matrix, MatrixError, Shard};
use occlu::picture::{LEAD_IN, Look, PictureError};
use occlu::raycast::{Budget, RayCaster, Stopped};
use occlu::report::compare::{CompareError, CompareOptions, Metric};
use occlu::report::merge::MergeError;
use occlu::report::{ReportError, SceneFacts};
use occlu::scene::builtin::SCENES;
use occlu::scene::up::UpChoice;
use occlu::scene::{LoadOptions, Scene, SceneError, SceneSpec, load};
use occlu::stress::{StressError, StressEvent};
use occlu::world::World;

/// Writes a line to standard error, its control and reordering characters
/// escaped ([`occlu::text::one_line`]): file, object and parser names reach
/// it from anyone's files, and must neither drive the terminal nor break
/// the line. A closed or full standard error is no reason to fail a run
/// (and must not panic, as `eprintln!` does): the line is dropped.
macro_rules! say {
    ($($arg:tt)*) => {{
        let line = occlu::text::one_line(&format!($($arg)*));
        let _ = writeln!(std::io::stderr().lock(), "{line}");
    }};
}

#[derive(Parser)]
#[command(
    name = "occlu",
    version,
    about = "Benchmark occlusion culling: replay a camera path offscreen in each culling mode and report frame time next to image error.",
    after_help = after_help()
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

fn after_help() -> String {
    let modes: Vec<String> = occlu::cull::modes()
        .map(|m| {
            let params = m
                .params
                .iter()
                .map(|p| format!("\n             --param {}.{}={}  {}", m.id, p.key, p.default, p.summary));
            format!("  {:<8} {}{}", m.id.name(), m.summary, params.collect::<String>())
        })
        .collect();
    let scenes: Vec<String> = SCENES.iter().map(|(n, s)| format!("  {n:<8} {s}")).collect();
    format!(
        "Modes:\n{}\n\nBuilt-in scenes (--scene NAME[:key=value,...]):\n{}\n\nExit status: 0 success (a closed output pipe included), 2 bad input, 1 failure while running, 130 interrupted (Ctrl-C, SIGTERM, SIGHUP).",
        modes.join("\n"),
        scenes.join("\n")
    )
}

#[derive(Subcommand)]
enum Command {
    /// Replay a camera path in each culling mode; write frames.csv,
    /// summary.json and report.md. With a matrix configuration (--config
    /// listing runs), every run of it (or --shard's share) into a folder
    /// of its own under --out.
    Bench(Box<BenchArgs>),
    /// Print a model's objects, triangles, hierarchy, load time and warnings.
    Info(InfoArgs),
    /// Camera paths.
    Path {
        #[command(subcommand)]
        command: PathCommand,
    },
    /// Render one frame of one mode to a PNG: what it drew, shaded (or its
    /// depth complexity), optionally beside a bird's-eye view marking its
    /// frustum and the boxes it culled.
    Render(RenderArgs),
    /// Fly a path in one or more modes and write it as an animated PNG:
    /// each frame the modes side by side as render paints them (the
    /// overview beside each with --overview), each under a caption with the
    /// mode, the frame and its frame time.
    Flythrough(Box<FlythroughArgs>),
    /// Run the built-in matrix of numerically hard cases (eye inside boxes,
    /// near-plane crossings, 1e7 offsets, tiny and huge scales, flat boxes,
    /// coplanar walls, 1° and 170° fields of view, vertical views,
    /// teleports) through every mode against the DR reference; exit 1 when a
    /// conservative mode shows any error or a moved case renders differently.
    Stress(StressArgs),
    /// Write a scene as occlu holds it (after clustering) and a camera path
    /// (as a camera animation) to a GLB, to replay them in another engine.
    Export {
        #[command(flatten)]
        scene: SceneAndPath,
        /// Output .glb file.
        #[arg(long, short, value_name = "FILE")]
        output: PathBuf,
    },
    /// Draw a run's charts (and report.md) again from its frames.csv and summary.json.
    Plot {
        /// A bench output directory.
        run_dir: PathBuf,
    },
    /// Merge result folders from many machines and adapters (bench --out
    /// folders, or matrix folders of run folders, e.g. one per CI shard)
    /// into one report: per run, its modes on every adapter side by side
    /// (never averaged), a chart of each mode's ratio to the oracle per
    /// adapter, counters that differ between adapters of one backend
    /// flagged; merged.json for machines, and a copy of every run folder
    /// under runs/. Folders of one run that measured different scenes,
    /// paths, resolutions or frame counts are refused.
    Merge {
        /// Result folders: a run's folder (holding summary.json) or a
        /// folder of them (a matrix's --out).
        #[arg(value_name = "DIR")]
        dirs: Vec<PathBuf>,
        /// Where merged.json, report.md, charts/ and runs/ go.
        #[arg(long, short, value_name = "MERGED")]
        out: PathBuf,
        /// Merge a matrix that lacks runs (a shard left out, a run that
        /// failed): the runs present are merged and the missing ones named
        /// in the report and merged.json. Without it such a merge is
        /// refused (exit 2), naming them.
        #[arg(long)]
        allow_partial: bool,
    },
    /// Compare two bench runs for CI: exit 1 when a counter (triangles,
    /// queries, round trips, wrong pixels, missed objects) grows, or when the
    /// mean frame time grows beyond --max-regression and beyond the measured
    /// spread (median ± MAD). Two merged folders (occlu merge) compare run
    /// by run and adapter by adapter.
    Compare {
        /// The reference run's output directory (or merged folder).
        base: PathBuf,
        /// The run to judge (or merged folder).
        new: PathBuf,
        /// Allowed growth of mean frame time, percent.
        #[arg(long, default_value_t = 5.0, value_name = "PCT")]
        max_regression: f64,
        /// Metrics to gate on, comma-separated [default: all].
        #[arg(long, value_enum, value_delimiter = ',')]
        metric: Vec<Metric>,
        /// Let the new run lack modes or metrics the base measured (e.g. run
        /// with fewer --modes or with --no-error) without failing.
        #[arg(long)]
        allow_missing: bool,
        /// Compare runs from different adapters or backends (counters only:
        /// frame times are not comparable across them).
        #[arg(long)]
        cross_adapter: bool,
        /// Print the verdicts as JSON (for machines) instead of the table.
        #[arg(long)]
        json: bool,
    },
}

/// A frame count as `--frames` takes it: 1 to the most a path may have,
/// said in the message for any other number (u32's own range would be).
fn frame_count() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(occlu::camera::path::MAX_FRAMES))
}

/// Where the scene comes from: a file, or a built-in scene (the city by default).
#[derive(Args)]
struct SceneArgs {
    /// Model file: .obj, .gltf or .glb. Without one, the built-in city.
    model: Option<PathBuf>,
    /// Built-in scene, NAME[:key=value,...], e.g. city:blocks=4,seed=7.
    #[arg(long, conflicts_with = "model")]
    scene: Option<String>,
    /// Cars driving round the city's blocks, so culling meets moving
    /// objects (the scene's movers=N parameter) [default: 0].
    #[arg(long, value_name = "N", conflicts_with = "model")]
    movers: Option<u32>,
    /// Meshes with more triangles than this are split into clusters [default: 4096].
    #[arg(long, value_name = "N")]
    cluster_triangles: Option<u32>,
    /// Largest model or glTF buffer file read, e.g. 512M or 16G; larger
    /// files, and files that grow past it while read, are refused [default: 4G].
    #[arg(long, value_name = "SIZE")]
    max_file_size: Option<ByteSize>,
    /// Let a glTF file's buffers lie outside its folder (absolute paths,
    /// "..", file: URIs). Off by default, so a model from elsewhere cannot
    /// make occlu read other files (=false overrides a config file).
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    external_buffers: Option<bool>,
    /// The scene's up axis, for generated paths and the overview: x, y, z,
    /// -x, -y, -z, or auto (+Y for glTF and built-in scenes; for OBJ, +Z
    /// when the model is at least twice as flat in Z as across and stands
    /// on its Z minimum, else +Y) [default: auto].
    #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
    up: Option<UpChoice>,
}

impl SceneArgs {
    fn spec(&self) -> Result<SceneSpec, ConfigError> {
        scene_spec(self.model.clone(), self.scene.clone(), self.movers)
    }

    fn options(&self) -> LoadOptions {
        load_options(
            self.cluster_triangles,
            self.max_file_size,
            self.external_buffers,
            self.up,
        )
    }
}

/// A scene and a camera path over it, as `render` and `export` take them.
#[derive(Args)]
struct SceneAndPath {
    #[command(flatten)]
    scene: SceneArgs,
    /// Camera path (JSON) [default: the path bench would generate].
    #[arg(long, value_name = "FILE")]
    path: Option<PathBuf>,
    /// Resamples the path to this many frames, as bench's --frames does
    /// [default: the path's].
    #[arg(long, value_name = "N", value_parser = frame_count())]
    frames: Option<u32>,
}

impl SceneAndPath {
    /// Refuses an `output` that is one of the files this reads.
    fn refuse_as_output(&self, output: &std::path::Path) -> anyhow::Result<()> {
        let inputs: Vec<&std::path::Path> = [self.scene.model.as_deref(), self.path.as_deref()]
            .into_iter()
            .flatten()
            .collect();
        Ok(occlu::report::refuse_input_as_output(output, &inputs)?)
    }

    /// The scene and the path; an `output` that is one of the files the
    /// scene was read from (a glTF file's buffers) is refused.
    fn load(&self, output: &std::path::Path) -> anyhow::Result<(Scene, CameraPath)> {
        // Read first: a bad path file fails before a long scene load.
        let path_file = self.path.as_deref().map(CameraPath::load).transpose()?;
        let scene = load(&self.scene.spec()?, &self.scene.options())?;
        occlu::report::refuse_input_as_output(output, &scene.files)?;
        let path = match path_file {
            Some(p) => p,
            None => {
                let mut progress = Progress::new(false, 0, String::new());
                let planned =
                    occlu::camera::generate::default_path_heard(&scene, progress.listener("planning the path"))?.0;
                stop_listening()?;
                planned
            }
        };
        let path = match self.frames {
            Some(n) => path.with_frames(n)?,
            None => path,
        };
        Ok((scene, path))
    }
}

#[derive(Args)]
struct BenchArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Camera path (JSON); generated from the scene when omitted (the city:
    /// a street-level walk; models: an orbit).
    #[arg(long, value_name = "FILE")]
    path: Option<PathBuf>,
    /// Modes to run, comma-separated, or "all" [default: all].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    modes: Option<Vec<String>>,
    /// Frames to record; resamples the path [default: the path's].
    #[arg(long, value_name = "N", value_parser = frame_count())]
    frames: Option<u32>,
    /// Frames run before recording starts [default: 3].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=i64::from(occlu::config::MAX_WARMUP)))]
    warmup: Option<u32>,
    /// Render size [default: 800x600].
    #[arg(long, value_name = "WxH")]
    resolution: Option<Resolution>,
    /// Graphics API; auto honours WGPU_BACKEND [default: auto].
    #[arg(long, value_enum)]
    backend: Option<BackendChoice>,
    /// Run configuration (JSON, see configs/); flags override it. A file
    /// listing "runs" (or "models"/"scenes" × "paths") is a matrix: every
    /// run goes into a folder of its own under --out, its fields over the
    /// file's, flags over both.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Run only the K-th of N shares of the matrix (1 <= K <= N): its runs
    /// K, K+N, K+2N, ..., so N CI jobs given 1/N ... N/N run every run once.
    /// A configuration that lists no runs is a matrix of one.
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Output directory [default: occlu-out].
    #[arg(long, short, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Skip the reference render and error measure (faster; error columns stay empty).
    #[arg(long)]
    no_error: bool,
    /// Also write flythrough.png beside the charts: every recorded frame,
    /// each mode's picture beside the scene from above (as render
    /// --overview paints it, at half size), with its frame time.
    #[arg(long)]
    animate: bool,
    /// Print summary.json (every mode's statistics) to stdout instead of
    /// report.md; report.md is still written.
    #[arg(long)]
    json: bool,
    /// Also write FILE for github-action-benchmark (customSmallerIsBetter):
    /// per mode frame ms mean and p95, triangles drawn, wrong pixels.
    #[arg(long, value_name = "FILE")]
    export_github_benchmark: Option<PathBuf>,
    /// Also write the run's timeline to FILE as Trace Event JSON (open it
    /// in ui.perfetto.dev or chrome://tracing): per mode, each frame's
    /// culling, commands and waits on the CPU, and its box tests and
    /// drawing on the GPU where the adapter has timestamps.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Print no progress and no notes on stderr, only errors.
    #[arg(long, short)]
    quiet: bool,
    /// A mode parameter, MODE.KEY=VALUE (repeatable), e.g. omq.om=80x60.
    #[arg(long = "param", value_name = "MODE.KEY=VALUE")]
    params: Vec<String>,
    /// Run one mode at several values of a parameter in the same run, e.g.
    /// ac.threshold=0,100,1000 (labels like ac[threshold=100]).
    #[arg(long, value_name = "MODE.KEY=V1,V2,...")]
    sweep: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneAndPath,
    /// Frame of the path to render (0-based).
    #[arg(long, value_name = "K")]
    frame: u32,
    /// The culling mode whose frame is rendered.
    #[arg(long, value_name = "MODE")]
    mode: String,
    #[command(flatten)]
    picture: PictureArgs,
    /// Compare the frame with direct rendering: paint the pixels whose depth
    /// differs in magenta and outline the boxes of the objects the mode
    /// missed, and list them.
    #[arg(long)]
    show_missed: bool,
    /// Lay the depth buffer a CPU culling mode (swr) culled the frame with
    /// over the picture: cells holding an occluder's depth from white (near)
    /// to deep blue (far; all of them when they share one depth), the rest
    /// of the frame dimmed.
    #[arg(long)]
    occluders: bool,
}

/// How `render` and `flythrough` picture a mode's frame, and where to.
#[derive(Args)]
struct PictureArgs {
    /// A mode parameter, MODE.KEY=VALUE (repeatable).
    #[arg(long = "param", value_name = "MODE.KEY=VALUE")]
    params: Vec<String>,
    /// Output PNG (animated, for flythrough).
    #[arg(long, short, value_name = "FILE")]
    output: PathBuf,
    /// Add a bird's-eye view beside each mode's frame: the frustum in red,
    /// culled objects' boxes in yellow.
    #[arg(long)]
    overview: bool,
    /// Colour pixels by depth complexity (surfaces drawn over them) instead of shading.
    #[arg(long)]
    heat: bool,
    /// Render size [default: 800x600].
    #[arg(long, value_name = "WxH")]
    resolution: Option<Resolution>,
    /// Graphics API [default: auto].
    #[arg(long, value_enum)]
    backend: Option<BackendChoice>,
}

impl PictureArgs {
    /// The look these flags ask for, with `render`'s own two.
    fn look(&self, show_missed: bool, occluders: bool) -> Look {
        Look {
            resolution: self.resolution.unwrap_or(Resolution::DEFAULT),
            overview: self.overview,
            heat: self.heat,
            show_missed,
            occluders,
        }
    }
}

#[derive(Args)]
struct FlythroughArgs {
    #[command(flatten)]
    scene: SceneAndPath,
    /// Modes side by side, comma-separated, or "all".
    #[arg(long, value_delimiter = ',', value_name = "LIST", required = true)]
    modes: Vec<String>,
    /// Frames A to B-1 of the path, every STEP-th pictured (all of them
    /// run; the two before A first, as render runs them) [default: the
    /// whole path].
    #[arg(long, value_name = "A..B[:STEP]")]
    range: Option<FrameRange>,
    #[command(flatten)]
    picture: PictureArgs,
    /// Panels are the pictures shrunk by K: each pixel the mean of K x K
    /// (a picture smaller than K across is shrunk to one pixel) [default: 2].
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SCALE)))]
    scale: Option<u32>,
    /// Every pixel as painted (24-bit) instead of one palette of 256
    /// colours for the whole animation: exact, about three times larger.
    #[arg(long)]
    true_colour: bool,
    /// Print no progress and no notes on stderr, only errors.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct StressArgs {
    /// Modes to run, comma-separated, or "all" [default: all].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    modes: Option<Vec<String>>,
    /// Cases to run, comma-separated [default: all]; --list shows them.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    cases: Vec<String>,
    /// Print the cases and exit.
    #[arg(long)]
    list: bool,
    /// Render size [default: 400x300].
    #[arg(long, value_name = "WxH")]
    resolution: Option<Resolution>,
    /// Graphics API; auto honours WGPU_BACKEND [default: auto].
    #[arg(long, value_enum)]
    backend: Option<BackendChoice>,
    /// Also write stress.md and stress.json here.
    #[arg(long, short, value_name = "DIR")]
    out: Option<PathBuf>,
}

#[derive(Args)]
struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Subcommand)]
enum PathCommand {
    /// Write a camera path made from a scene: its shape, or a glTF file's
    /// own cameras and camera animations.
    Gen {
        #[command(flatten)]
        scene: SceneArgs,
        /// orbit, walk, flyover, cameras (the file's cameras in order) or
        /// animation[=NAME] (an animation that moves a camera) [default: the
        /// file's animated camera; a walk for streets, places, interiors
        /// and domes; an orbit for objects].
        #[arg(long, value_name = "KIND")]
        kind: Option<PathRequest>,
        /// Frames of the path [default: 120; one per camera for cameras; the
        /// animation's own time at 30 per second for animation].
        #[arg(long, value_name = "N", value_parser = frame_count())]
        frames: Option<u32>,
        /// Output file.
        #[arg(long, short, value_name = "FILE")]
        output: PathBuf,
    },
}

fn main() -> ExitCode {
    give_wayland_a_runtime_folder();
    listen_for_ctrl_c();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // The message with the lines that complete it (the values a
            // flag takes, the arguments missing), up to the usage.
            let text = e.render().to_string();
            let lines: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.is_empty()).collect();
            let message = lines.join(" ");
            say!("occlu: {}", message.trim_start_matches("error: "));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Bench(args) => bench(*args).map(|()| ExitCode::SUCCESS),
        Command::Info(args) => info(args).map(|()| ExitCode::SUCCESS),
        Command::Path {
            command:
                PathCommand::Gen {
                    scene,
                    kind,
                    frames,
                    output,
                },
        } => path_gen(scene, kind, frames, output).map(|()| ExitCode::SUCCESS),
        Command::Stress(args) => stress(args),
        Command::Export { scene, output } => export(&scene, &output).map(|()| ExitCode::SUCCESS),
        Command::Plot { run_dir } => plot(&run_dir).map(|()| ExitCode::SUCCESS),
        Command::Render(args) => render(args).map(|()| ExitCode::SUCCESS),
        Command::Flythrough(args) => flythrough(*args).map(|()| ExitCode::SUCCESS),
        Command::Merge {
            dirs,
            out,
            allow_partial,
        } => merge(&dirs, &out, allow_partial).map(|()| ExitCode::SUCCESS),
        Command::Compare {
            base,
            new,
            max_regression,
            metric,
            allow_missing,
            cross_adapter,
            json,
        } => {
            let options = CompareOptions {
                max_regression_pct: max_regression,
                metrics: if metric.is_empty() {
                    Metric::ALL.to_vec()
                } else {
                    metric
                },
                allow_missing,
                cross_adapter,
            };
            compare(&base, &new, &options, json)
        }
    };
    let code = match result {
        Err(e) if was_interrupted(&e) => {
            say!("occlu: {e:#}");
            end_by_sigint()
        }
        Ok(code) => code,
        Err(e) => {
            say!("occlu: error: {e:#}");
            ExitCode::from(if is_input_error(&e) { 2 } else { 1 })
        }
    };
    // Ctrl-C while the results were written: they are whole, and the
    // interruption still reaches the caller.
    if CTRL_C.load(Ordering::SeqCst) == HEARD {
        say!("occlu: interrupted");
        end_by_sigint();
    }
    code
}

/// What Ctrl-C does now: [`ENDS_AT_ONCE`], [`LISTENED`] or [`HEARD`]. One
/// value, so that the handler and a step that stops listening cannot both
/// miss a Ctrl-C between them.
static CTRL_C: AtomicU8 = AtomicU8::new(ENDS_AT_ONCE);

/// No step that stops cleanly is running: Ctrl-C ends the process at once,
/// as it would without a handler. Nothing is half-written then: the
/// operating system drops the claim on --out, and result files are moved
/// into place whole.
const ENDS_AT_ONCE: u8 = 0;
/// A step that stops cleanly on Ctrl-C is running (see [`go_on`]): the
/// first Ctrl-C asks it to stop.
const LISTENED: u8 = 1;
/// Ctrl-C came while a step listened: the work stops at its next frame
/// (bench), case (stress) or stretch of ray casts (planning), writes
/// nothing, and ends the process.
const HEARD: u8 = 2;

/// The first Ctrl-C (or SIGTERM, or SIGHUP: a terminal closed, a job
/// cancelled) asks a listening step to stop (see [`CTRL_C`]); a second
/// one, or one while nothing listens, ends the process at once.
fn listen_for_ctrl_c() {
    let _ = ctrlc::set_handler(|| {
        if CTRL_C
            .compare_exchange(LISTENED, HEARD, Ordering::SeqCst, Ordering::SeqCst)
            .is_err()
        {
            end_by_sigint();
        }
    });
}

/// Ends the process as killed by SIGINT, so a calling shell or script sees
/// the interruption (status 130) and stops as well, which an exit code
/// alone would not make it do. A results folder this process made and
/// wrote no results into goes first.
fn end_by_sigint() -> ! {
    occlu::report::abandon_unfinished();
    #[cfg(unix)]
    // SAFETY: restores SIGINT's default action and raises it; neither call
    // touches memory, and the default action ends the process.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
        libc::raise(libc::SIGINT);
    }
    std::process::exit(130)
}

/// Whether the work should go on (no Ctrl-C yet); from its first call on,
/// Ctrl-C asks the work to stop instead of ending the process, until
/// [`stop_listening`].
fn go_on() -> ControlFlow<()> {
    match CTRL_C.compare_exchange(ENDS_AT_ONCE, LISTENED, Ordering::SeqCst, Ordering::SeqCst) {
        Err(HEARD) => ControlFlow::Break(()),
        _ => ControlFlow::Continue(()),
    }
}

/// A command heard Ctrl-C while a step of it listened, and stopped before
/// writing anything.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: nothing written")]
struct Interrupted;

/// Ends a step that listened for Ctrl-C (path planning in `render`,
/// `export` and `path gen`), for a command whose later steps do not ask
/// [`go_on`]: from here on Ctrl-C ends the process at once again, rather
/// than being heard by nothing while the command runs to its end and
/// writes. A Ctrl-C that the step heard after it last asked stops the
/// command here.
fn stop_listening() -> Result<(), Interrupted> {
    match CTRL_C.compare_exchange(LISTENED, ENDS_AT_ONCE, Ordering::SeqCst, Ordering::SeqCst) {
        Err(HEARD) => Err(Interrupted),
        _ => Ok(()),
    }
}

fn was_interrupted(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.is::<Interrupted>()
            || matches!(c.downcast_ref::<BenchError>(), Some(BenchError::Interrupted))
            || matches!(c.downcast_ref::<StressError>(), Some(StressError::Interrupted))
            || matches!(c.downcast_ref::<AnimationError>(), Some(AnimationError::Interrupted))
            || matches!(c.downcast_ref::<PathError>(), Some(PathError::Interrupted))
    })
}

/// On a headless Linux machine the Vulkan loader probes for a Wayland
/// display, and libwayland prints "XDG_RUNTIME_DIR is invalid or not set"
/// on every run when that variable is missing. occlu opens no window: where
/// the variable is unset it points it at a private folder of the user's
/// (created 0700 under the temporary folder, as the XDG specification asks
/// of a runtime folder), in which the probe finds no display and says
/// nothing. A folder that exists but is not the user's alone is left alone,
/// and so is the message.
fn give_wayland_a_runtime_folder() {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
        if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
            return;
        }
        let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
            return;
        };
        let dir = std::env::temp_dir().join(format!("occlu-runtime-{uid}"));
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let private = std::fs::symlink_metadata(&dir)
            .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o777 == 0o700);
        if private {
            // SAFETY: main has started no thread yet, so nothing reads the
            // environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

fn is_input_error(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<BenchError>().is_some_and(BenchError::is_input_error)
            || c.is::<SceneError>()
            || c.is::<PathError>()
            || c.is::<ConfigError>()
            || c.is::<MatrixError>()
            || c.downcast_ref::<MergeError>().is_some_and(MergeError::is_input_error)
            || c.downcast_ref::<ReportError>().is_some_and(ReportError::is_input_error)
            || c.is::<CompareError>()
            || c.is::<ModeError>()
            || c.is::<occlu::export::ExportError>()
            || c.downcast_ref::<StressError>().is_some_and(StressError::is_input_error)
            || c.downcast_ref::<occlu::gpu::GpuError>()
                .is_some_and(occlu::gpu::GpuError::is_input_error)
            || c.downcast_ref::<PictureError>()
                .is_some_and(PictureError::is_input_error)
            || c.downcast_ref::<AnimationError>()
                .is_some_and(AnimationError::is_input_error)
    })
}

fn bench(args: BenchArgs) -> anyhow::Result<()> {
    let flags = BenchConfig {
        model: args.scene.model,
        scene: args.scene.scene,
        movers: args.scene.movers,
        path: args.path,
        modes: args.modes,
        frames: args.frames,
        warmup: args.warmup,
        resolution: args.resolution,
        backend: args.backend,
        out: args.out,
        error: args.no_error.then_some(false),
        cluster_triangles: args.scene.cluster_triangles,
        max_file_size: args.scene.max_file_size,
        external_buffers: args.scene.external_buffers,
        up: args.scene.up,
        export_github_benchmark: args.export_github_benchmark,
        trace: args.trace,
        animate: args.animate.then_some(true),
        params: (!args.params.is_empty()).then_some(args.params),
        sweep: args.sweep,
    };
    let matrix = match &args.config {
        Some(path) => Matrix::load(path)?,
        None => Matrix::default(),
    };
    let quiet = args.quiet;
    let note = |text: String| {
        if !quiet {
            say!("{text}");
        }
    };
    if !matrix.lists_runs() && args.shard.is_none() {
        let plan = matrix.single_run(&flags)?;
        let model = match &plan.scene {
            SceneSpec::File(model) => Some(model.as_path()),
            SceneSpec::Builtin(_) => None,
        };
        let inputs: Vec<&std::path::Path> = [model, plan.path.as_deref(), args.config.as_deref()]
            .into_iter()
            .flatten()
            .collect();
        for output in [&plan.export_github_benchmark, &plan.trace].into_iter().flatten() {
            occlu::report::refuse_input_as_output(output, &inputs)?;
        }
        if let (Some(export), Some(trace)) = (&plan.export_github_benchmark, &plan.trace) {
            occlu::report::refuse_one_file_twice(export, trace)?;
        }
        let outcome = bench_one(&plan, &note, quiet, format!("{} modes", plan.modes.len()))?;
        return if args.json {
            emit(&(serde_json::to_string_pretty(&outcome.summary)? + "\n"))
        } else {
            emit(&occlu::report::render_markdown(&outcome.summary))
        };
    }
    // Every run is checked before any runs, on every shard alike.
    let runs = matrix.plan(&flags)?;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let mine: Vec<_> = runs
        .iter()
        .enumerate()
        .filter(|&(place, _)| shard.takes(place))
        .map(|(_, run)| run)
        .collect();
    if mine.is_empty() {
        note(format!(
            "shard {shard}: none of the matrix's {} falls to this shard; nothing run, nothing written",
            occlu::text::count(runs.len(), "run")
        ));
        // --json still prints a list, of no summaries.
        return if args.json { emit("[]\n") } else { Ok(()) };
    }
    let mut summaries = Vec::new();
    let mut table = String::from("| run | scene | path | adapter | folder |\n|---|---|---|---|---|\n");
    for (k, run) in mine.iter().enumerate() {
        note(format!(
            "run {} of {} (shard {shard} of a matrix of {}): {}",
            k + 1,
            mine.len(),
            runs.len(),
            run.name
        ));
        let outcome =
            bench_one(&run.plan, &note, quiet, run.name.clone()).with_context(|| format!("run {}", run.name))?;
        let s = &outcome.summary;
        let _ = writeln!(
            table,
            "| {} | {} | {} | {} | {} |",
            run.name,
            occlu::text::markdown(&s.scene.facts.source),
            occlu::text::markdown(&s.path.source),
            occlu::text::markdown(&s.adapter.to_string()),
            occlu::text::markdown(&run.plan.out.display().to_string())
        );
        summaries.push(outcome.summary);
    }
    if args.json {
        emit(&(serde_json::to_string_pretty(&summaries)? + "\n"))
    } else {
        emit(&table)
    }
}

/// Runs one plan with its progress on stderr (`prefix` names it there) and
/// says where its results went.
fn bench_one(
    plan: &BenchPlan,
    note: &dyn Fn(String),
    quiet: bool,
    prefix: String,
) -> anyhow::Result<occlu::bench::BenchOutcome> {
    let mut progress = Progress::new(quiet, plan.warmup, prefix);
    let outcome = execute(plan, &mut |event| {
        heard(&mut progress, event, note);
        go_on()
    })?;
    progress.finish();
    for path in [&plan.export_github_benchmark, &plan.trace].into_iter().flatten() {
        note(format!("wrote {}", path.display()));
    }
    let files = &outcome.files;
    let optional: String = [&files.missed_csv, &files.animation]
        .into_iter()
        .flatten()
        .map(|p| format!(", {}", p.display()))
        .collect();
    note(format!(
        "results: {}, {}, {}{optional} and {} charts in {}",
        files.report_md.display(),
        files.summary_json.display(),
        files.frames_csv.display(),
        files.charts.len(),
        plan.out.display()
    ));
    Ok(outcome)
}

fn merge(dirs: &[PathBuf], out: &std::path::Path, allow_partial: bool) -> anyhow::Result<()> {
    let merged = occlu::report::merge::merge(dirs, out, allow_partial)?;
    emit(&occlu::report::merge::render(&merged))?;
    let adapters: std::collections::BTreeSet<String> = merged
        .runs
        .iter()
        .flat_map(|r| r.adapters.iter().map(|a| a.label()))
        .collect();
    say!(
        "merged {} on {} into {} (report.md, merged.json, charts/, runs/)",
        occlu::text::count(merged.runs.len(), "run"),
        occlu::text::count(adapters.len(), "adapter"),
        out.display()
    );
    for partial in &merged.missing {
        say!(
            "warning: a partial matrix, merged as asked (--allow-partial): {}",
            partial.describe()
        );
    }
    for run in &merged.runs {
        for d in &run.disagreements {
            say!("warning: {}: {}: a backend-specific bug?", run.name, d.describe());
        }
    }
    Ok(())
}

/// What bench says on stderr as its run goes.
fn heard(progress: &mut Progress, event: BenchEvent, note: &dyn Fn(String)) {
    match event {
        BenchEvent::Loaded {
            scene,
            hierarchy,
            load_ms,
            build_ms,
        } => {
            note(format!(
                "scene: {}: {} objects, {} triangles (load {load_ms:.0} ms, hierarchy of {} nodes {build_ms:.0} ms)",
                scene.source,
                scene.objects.len(),
                scene.triangles(),
                hierarchy.nodes.len()
            ));
            for w in &scene.warnings {
                note(format!("warning: {w}"));
            }
        }
        BenchEvent::Skipped { mode, reason } => note(format!("skipped: {mode}: {reason}")),
        BenchEvent::Work { what, spent, budget } => progress.work(what, spent, budget),
        BenchEvent::Adapter(adapter) => note(format!("adapter: {adapter}")),
        BenchEvent::Path(path, frames) => {
            let why = path.generated.as_ref().map(|w| format!(" ({w})")).unwrap_or_default();
            note(format!("path: {}{why}", path.source));
            match path.frames_with_geometry_within_near {
                Some(0) => {}
                Some(n) => note(format!(
                    "warning: {n} of {frames} frames have geometry nearer than the near plane's corners ({}): it may be clipped",
                    path.near
                )),
                None => note(near_not_counted()),
            }
        }
        BenchEvent::Frame { done, total } => progress.frame(done, total),
        BenchEvent::Encoding { done, total } => {
            if done == 0 {
                progress.finish();
                note(format!("encoding the animation's {total} frames"));
            }
            progress.encoding(done, total);
        }
        BenchEvent::NothingVisible => note(
            "warning: no object was visible in any frame (the reference drew nothing): check the camera path, and the model's place and size".into(),
        ),
    }
}

/// What a run says when counting frames with geometry within the near
/// plane spent its budget of ray casts.
fn near_not_counted() -> String {
    format!(
        "note: frames with geometry nearer than the near plane were not counted: the count spent its budget of {} M box and triangle tests",
        occlu::camera::generate::PLANNING_TESTS / 1_000_000
    )
}

/// Progress of a bench run on stderr: a bar over the recorded frames in a
/// terminal (warm-up frames first show as such), and outside one (a CI log)
/// a line every few seconds; nothing when quiet. Both say which frame of
/// how many, the time spent and, once it can tell, how long is left.
struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    warmup: u32,
    prefix: String,
    started: Instant,
    last_line: Option<Instant>,
    pace: Pace,
    /// The step of ray casts under way (planning a path), and when it began.
    step: Option<(&'static str, Instant)>,
}

/// Seconds between progress lines outside a terminal.
const PROGRESS_EVERY: f64 = 5.0;

impl Progress {
    fn new(quiet: bool, warmup: u32, prefix: String) -> Progress {
        Progress {
            bar: None,
            quiet,
            warmup,
            prefix,
            started: Instant::now(),
            last_line: None,
            pace: Pace::default(),
            step: None,
        }
    }

    /// A step of ray casts, `what`, has spent `spent` of its `budget` box
    /// and triangle tests.
    fn work(&mut self, what: &'static str, spent: u64, budget: u64) {
        self.report_step(what, || {
            format!(
                "{} M of at most {} M box and triangle tests",
                spent / 1_000_000,
                budget / 1_000_000
            )
        });
    }

    /// `done` of an animation's `total` frames are encoded.
    fn encoding(&mut self, done: u32, total: u32) {
        self.report_step("encoding the animation", || format!("frame {done} of {total}"));
    }

    /// A step before or after the frames, `what`, has got as far as
    /// `so_far` says: said once the step has taken a second (most take
    /// less), then every few seconds.
    fn report_step(&mut self, what: &'static str, so_far: impl FnOnce() -> String) {
        if self.quiet {
            return;
        }
        let now = Instant::now();
        let began = match self.step {
            Some((step, began)) if step == what => began,
            _ => {
                self.step = Some((what, now));
                self.last_line = None;
                now
            }
        };
        let taken = now.duration_since(began).as_secs_f64();
        let due = self
            .last_line
            .map_or(taken >= 1.0, |t| now.duration_since(t).as_secs_f64() >= PROGRESS_EVERY);
        if due {
            self.last_line = Some(now);
            say!("{what}: {taken:.0} s, {}", so_far());
        }
    }

    /// A listener for a step of ray casts, `what`: progress as [`Progress::work`]
    /// says it, and Ctrl-C heard.
    fn listener(&mut self, what: &'static str) -> occlu::camera::generate::PlanListener<'_> {
        Box::new(move |spent, budget| {
            self.work(what, spent, budget);
            go_on()
        })
    }

    /// `done` of `total` frames, warm-up frames included, have run.
    fn frame(&mut self, done: u32, total: u32) {
        if self.quiet {
            return;
        }
        let now = Instant::now();
        let status = self.status(done, total, now);
        let recorded = total.saturating_sub(self.warmup);
        if std::io::stderr().is_terminal() {
            // Created with its length known, so it never shows 0/0.
            let bar = self.bar.get_or_insert_with(|| {
                ProgressBar::new(u64::from(recorded)).with_style(
                    ProgressStyle::with_template("{prefix} [{bar:32}] {msg}")
                        .expect("static template")
                        .progress_chars("=> "),
                )
            });
            bar.set_prefix(self.prefix.clone());
            bar.set_position(u64::from(done.saturating_sub(self.warmup)));
            bar.set_message(status);
        } else {
            let due = self
                .last_line
                .is_none_or(|t| now.duration_since(t).as_secs_f64() >= PROGRESS_EVERY);
            if due || done == total {
                self.last_line = Some(now);
                say!("{}: {status}", self.prefix);
            }
        }
    }

    /// Which frame of how many is done, the time spent and the time left.
    fn status(&mut self, done: u32, total: u32, now: Instant) -> String {
        let (phase, at, of) = if done <= self.warmup {
            ("warm-up frame", done, self.warmup)
        } else {
            ("frame", done - self.warmup, total - self.warmup)
        };
        let elapsed = now.duration_since(self.started).as_secs_f64();
        let left = match self.pace.seconds_left(done, total, self.warmup, now) {
            Some(left) => format!("about {left:.0} s left"),
            None => "estimating the time left".into(),
        };
        format!("{phase} {at} of {of}, {elapsed:.0} s elapsed, {left}")
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// How long a run has left, at the pace of its recorded frames alone: the
/// first frames, on a cold shader cache, take tens of seconds each on a
/// software rasteriser and say nothing of the rest. So the pace is taken
/// from the end of warm-up (or of the first frame, without warm-up on).
#[derive(Default)]
struct Pace {
    /// When the pace is taken from, and the frames done by then.
    from: Option<(Instant, u32)>,
}

impl Pace {
    /// Notes that `done` of `total` frames, the first `warmup` of them
    /// warm-up, have run at `now`; the seconds left, once a frame has run
    /// since the pace is taken from.
    fn seconds_left(&mut self, done: u32, total: u32, warmup: u32, now: Instant) -> Option<f64> {
        if done < warmup.max(1) {
            return None;
        }
        let (from, done_then) = *self.from.get_or_insert((now, done));
        let paced = done - done_then;
        (paced > 0)
            .then(|| now.duration_since(from).as_secs_f64() / f64::from(paced) * f64::from(total.saturating_sub(done)))
    }
}

fn stress(args: StressArgs) -> anyhow::Result<ExitCode> {
    let modes = parse_modes(args.modes.as_deref().unwrap_or(&["all".to_string()]))?;
    let cases = occlu::stress::select(&args.cases)?;
    if args.list {
        let list: String = cases
            .iter()
            .map(|case| format!("{:<15} {} frames: {}\n", case.name, case.cameras.len(), case.summary))
            .collect();
        emit(&list)?;
        return Ok(ExitCode::SUCCESS);
    }
    let backend = args.backend.unwrap_or_default();
    backend.backends()?;
    let _claim = args.out.as_deref().map(occlu::report::prepare_output).transpose()?;
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    say!("adapter: {}", gpu.adapter);
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{prefix:<15} [{bar:32}] {pos}/{len} frames, {elapsed} elapsed")
            .expect("static template")
            .progress_chars("=> "),
    );
    let resolution = args.resolution.unwrap_or(STRESS_RESOLUTION);
    let report = occlu::stress::run(&gpu, &cases, &modes, resolution, &mut |event| {
        match event {
            StressEvent::Skipped { mode, reason } => say!("skipped: {mode}: {reason}"),
            StressEvent::CaseSkipped { case, reason } => say!("skipped case: {case}: {reason}"),
            StressEvent::Case { case } => bar.set_prefix(case.name.clone()),
            StressEvent::Frame { done, total } => {
                bar.set_length(u64::from(total));
                bar.set_position(u64::from(done));
            }
        }
        go_on()
    })?;
    bar.finish_and_clear();
    let markdown = occlu::stress::render_markdown(&report);
    emit(&markdown)?;
    if let Some(out) = &args.out {
        let json = serde_json::to_string_pretty(&report)? + "\n";
        occlu::report::publish_files(
            out,
            &[("stress.md", markdown.as_bytes()), ("stress.json", json.as_bytes())],
        )?;
        say!("results: stress.md and stress.json in {}", out.display());
    }
    let (_, failed) = report.verdicts();
    Ok(if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Small: the cases are about precision, not pixel throughput.
const STRESS_RESOLUTION: Resolution = Resolution {
    width: 400,
    height: 300,
};

fn compare(
    base: &std::path::Path,
    new: &std::path::Path,
    options: &CompareOptions,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let comparison = occlu::report::compare::compare(base, new, options)?;
    if json {
        emit(&(serde_json::to_string_pretty(&comparison)? + "\n"))?;
    } else {
        emit(&occlu::report::compare::render(&comparison))?;
    }
    let regressions: Vec<String> = comparison
        .regressions()
        .map(|c| match (c.base, c.new) {
            (Some(b), Some(n)) if b != 0.0 => format!("{} {} {:+.1}%", c.mode, c.metric, (n - b) / b * 100.0),
            _ => format!("{} {}", c.mode, c.metric),
        })
        .collect();
    if regressions.is_empty() {
        say!("no regression");
        Ok(ExitCode::SUCCESS)
    } else {
        say!("occlu: {} regressions: {}", regressions.len(), regressions.join(", "));
        Ok(ExitCode::from(1))
    }
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let modes = parse_modes(std::slice::from_ref(&args.mode))?;
    let [mode] = modes[..] else {
        anyhow::bail!(ModeError::NotOne(args.mode.clone()));
    };
    let params = ModeParams::parse(&args.picture.params, &modes)?;
    args.scene.refuse_as_output(&args.picture.output)?;
    let backend = args.picture.backend.unwrap_or_default();
    backend.backends()?;
    let (scene, path) = args.scene.load(&args.picture.output)?;
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    if let Some(reason) = mode.info().unsupported_on(&gpu) {
        anyhow::bail!("mode '{mode}' cannot run on {}: {reason}", gpu.adapter);
    }
    let culler = mode.create(&scene, &params)?;
    let mut world = World::new(scene, hierarchy);
    let look = args.picture.look(args.show_missed, args.occluders);
    let picture = occlu::picture::render(&gpu, &mut world, &path, culler, args.frame, &look)?;
    let output = &args.picture.output;
    occlu::report::write_png(output, picture.width, picture.height, &picture.rgb)?;
    say!(
        "wrote {} ({}x{}): {mode} drew {} objects at frame {}, culled {} inside the frustum",
        output.display(),
        picture.width,
        picture.height,
        picture.drawn,
        args.frame,
        picture.culled_in_frustum
    );
    if let Some([written, cells]) = picture.occluder_cells {
        say!("{written} of its {cells} buffer cells hold an occluder's depth (coloured; the rest dimmed)");
    }
    if let Some(wrong) = &picture.wrong {
        say!(
            "{} pixels differ from direct rendering (magenta); {} objects got wrong (boxes outlined)",
            wrong.pixels,
            wrong.objects.len()
        );
        for m in &wrong.objects {
            let first = match (m.first_x, m.first_y) {
                (Some(x), Some(y)) => format!(", first at ({x}, {y})"),
                _ => String::new(),
            };
            let drawn = if m.drawn { "drawn" } else { "not drawn" };
            say!(
                "  object {} '{}': {drawn}, {} wrong pixels{first}",
                m.object,
                m.name,
                m.wrong_pixels
            );
        }
    }
    Ok(())
}

fn flythrough(args: FlythroughArgs) -> anyhow::Result<()> {
    let modes = parse_modes(&args.modes)?;
    let params = ModeParams::parse(&args.picture.params, &modes)?;
    let output = &args.picture.output;
    args.scene.refuse_as_output(output)?;
    occlu::report::check_writable(output)?;
    let backend = args.picture.backend.unwrap_or_default();
    backend.backends()?;
    let note = |text: String| {
        if !args.quiet {
            say!("{text}");
        }
    };
    let (scene, path) = args.scene.load(output)?;
    let range = args.range.unwrap_or(FrameRange::all(path.frames));
    range.check(path.frames)?;
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    note(format!("adapter: {}", gpu.adapter));
    let mut cullers = Vec::new();
    for mode in modes {
        match mode.info().unsupported_on(&gpu) {
            Some(reason) => note(format!("skipped: {mode}: {reason}")),
            None => cullers.push(mode.create(&scene, &params)?),
        }
    }
    anyhow::ensure!(!cullers.is_empty(), "no mode of --modes runs on {}", gpu.adapter);
    let mut world = World::new(scene, hierarchy);
    let options = AnimationOptions {
        look: args.picture.look(false, false),
        scale: args.scale.unwrap_or(DEFAULT_SCALE),
        true_colour: args.true_colour,
    };
    let lead_in = range.start.min(LEAD_IN);
    let mut progress = Progress::new(args.quiet, lead_in, format!("{} modes", cullers.len()));
    let reel = occlu::animation::flythrough(
        &gpu,
        &mut world,
        &path,
        &mut cullers,
        &options,
        range,
        &mut |done, total| {
            progress.frame(done, total);
            go_on()
        },
    )?;
    progress.finish();
    note(format!("encoding the animation's {} frames", reel.frames()));
    let animation = reel.encode(&mut |done, total| {
        progress.encoding(done, total);
        go_on()
    })?;
    occlu::report::write_whole(output, &animation.png)?;
    note(format!(
        "wrote {} ({}x{}, {} frames, {:.1} MB)",
        output.display(),
        animation.width,
        animation.height,
        animation.frames,
        animation.png.len() as f64 / 1e6
    ));
    Ok(())
}

fn plot(run_dir: &std::path::Path) -> anyhow::Result<()> {
    // A folder that holds no run is refused before it is claimed (claiming
    // creates it); then it is read and rewritten under the claim, so no run
    // writes into it meanwhile.
    occlu::report::read_results(run_dir)?;
    let _claim = occlu::report::prepare_output(run_dir)?;
    let (summary, rows) = occlu::report::read_results(run_dir)?;
    let charts = occlu::report::rewrite_report(run_dir, &summary, &rows)?;
    for chart in charts {
        say!("wrote {}", chart.display());
    }
    Ok(())
}

fn info(args: InfoArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let scene = load(&args.scene.spec()?, &args.scene.options())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let report = SceneFacts::of(&scene, &hierarchy, load_ms, build_ms);
    if args.json {
        return emit(&(serde_json::to_string_pretty(&report)? + "\n"));
    }
    let h = report.hierarchy;
    let mut text = String::new();
    let w = &mut text;
    // Names from the file, shown as themselves (see say!).
    let shown = occlu::text::one_line;
    let _ = writeln!(w, "source      {}", shown(&report.source));
    let _ = writeln!(w, "objects     {} ({} meshes)", report.objects, report.meshes);
    if report.movers > 0 {
        let _ = writeln!(w, "movers      {} objects move from frame to frame", report.movers);
    }
    let _ = writeln!(w, "triangles   {}", report.triangles);
    let _ = writeln!(w, "vertices    {}", report.vertices);
    let _ = writeln!(w, "bounds      {:?} to {:?}", report.bounds_min, report.bounds_max);
    let _ = writeln!(w, "up          {} ({})", report.up.axis, report.up.why);
    let _ = writeln!(
        w,
        "hierarchy   {} nodes, {} leaves, depth {}, at most {} objects per leaf",
        h.nodes, h.leaves, h.depth, h.max_leaf_objects
    );
    let p = report.load_phases;
    let _ = writeln!(
        w,
        "load        {load_ms:.1} ms (read {:.1}, parse {:.1}, validate {:.1}, closed-solid test {:.1}, clustering {:.1})",
        p.read_ms, p.parse_ms, p.validate_ms, p.closed_ms, p.cluster_ms
    );
    let _ = writeln!(w, "build       {build_ms:.1} ms (hierarchy)");
    for c in &report.cameras {
        let fov = c.fov_y_deg.map_or(String::new(), |f| format!(", fov {f:.1}°"));
        let near = c.near.map_or(String::new(), |n| format!(", near {n}"));
        let _ = writeln!(
            w,
            "camera      '{}' (node {}, {}{fov}{near})",
            shown(&c.name),
            c.node,
            c.projection
        );
    }
    for a in &report.animations {
        let moves = a.camera.as_ref().map_or("moves no camera".to_string(), |c| {
            format!("moves camera '{}'", shown(c))
        });
        let _ = writeln!(
            w,
            "animation   '{}' ({} channels, {:.2} s, {moves})",
            shown(&a.name),
            a.channels,
            a.duration
        );
    }
    if scene.warnings.is_empty() {
        let _ = writeln!(w, "warnings    none");
    }
    for warning in &scene.warnings {
        let _ = writeln!(w, "warning     {}", shown(warning));
    }
    emit(&text)
}

/// Standard output could not take what a command printed (a full disk).
#[derive(Debug, thiserror::Error)]
#[error("cannot write to standard output: {0}")]
struct StdoutError(std::io::Error);

/// Writes `text` to standard output. A reader that went away (a closed
/// pipe, as in `occlu stress --list | head -1`) is not an error: the rest
/// is not wanted, and the command succeeds as other Unix tools do. Any
/// other failure is (exit 1).
fn emit(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(StdoutError(e).into()),
        _ => Ok(()),
    }
}

fn export(input: &SceneAndPath, output: &std::path::Path) -> anyhow::Result<()> {
    input.refuse_as_output(output)?;
    occlu::report::check_writable(output)?;
    let (scene, path) = input.load(output)?;
    if !scene.movers.is_empty() {
        say!(
            "warning: {} moving objects are written where frame 0 puts them (glTF animation of objects is not exported)",
            scene.movers.len()
        );
    }
    let bytes = occlu::export::glb(&scene, &path, Resolution::DEFAULT.aspect())?;
    occlu::report::write_whole(output, &bytes)?;
    say!(
        "wrote {} ({} objects, {} triangles, {} and {} frames as the animation 'occlu path')",
        output.display(),
        scene.objects.len(),
        scene.triangles(),
        path.source,
        path.frames
    );
    Ok(())
}

fn path_gen(
    scene_args: SceneArgs,
    request: Option<PathRequest>,
    frames: Option<u32>,
    output: PathBuf,
) -> anyhow::Result<()> {
    if let Some(model) = &scene_args.model {
        occlu::report::refuse_input_as_output(&output, &[model])?;
    }
    let scene: Scene = load(&scene_args.spec()?, &scene_args.options())?;
    occlu::report::refuse_input_as_output(&output, &scene.files)?;
    let mut progress = Progress::new(false, 0, String::new());
    let generated = plan_heard(request.as_ref(), &scene, frames, progress.listener("planning the path"))?;
    // Validate what is written, so a generated file always loads.
    let path = CameraPath::from_file(&generated.file, &format!("generated:{}", generated.kind))?;
    let budget = Budget {
        tests: occlu::camera::generate::PLANNING_TESTS,
        listener: progress.listener("counting frames with geometry within the near plane"),
    };
    let caster = RayCaster::with_budget(&scene, budget);
    // Counted before the file is written, so Ctrl-C meanwhile writes nothing.
    let near = match path.frames_with_geometry_within_near(&caster, Resolution::DEFAULT.aspect()) {
        Ok(0) => None,
        Ok(near) => Some(format!(
            "warning: {near} of {} frames have geometry nearer than the near plane's corners (at 4:3)",
            path.frames
        )),
        Err(Stopped::Spent) => Some(near_not_counted()),
        Err(Stopped::Interrupted) => return Err(PathError::Interrupted.into()),
    };
    stop_listening()?;
    let text = serde_json::to_string_pretty(&generated.file)? + "\n";
    occlu::report::write_whole(&output, text.as_bytes())?;
    say!(
        "wrote {} ({}: {}; {} frames, {} keyframes)",
        output.display(),
        generated.kind,
        generated.why,
        path.frames,
        generated.file.keyframes.len()
    );
    if let Some(near) = near {
        say!("{near}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// The seconds left after each frame of a run whose frames took
    /// `seconds` each, `warmup` of them warm-up.
    fn estimates(seconds: &[u64], warmup: u32) -> Vec<Option<f64>> {
        let mut pace = Pace::default();
        let mut now = Instant::now();
        let total = seconds.len() as u32;
        (1..=total)
            .map(|done| {
                now += Duration::from_secs(seconds[done as usize - 1]);
                pace.seconds_left(done, total, warmup, now)
            })
            .collect()
    }

    #[test]
    fn the_time_left_comes_from_recorded_frames_not_warm_up() {
        // Three warm-up frames compiling shaders for 100 s each, then 100
        // frames of 2 s.
        let seconds: Vec<u64> = [100; 3].into_iter().chain([2; 100]).collect();
        let left = estimates(&seconds, 3);
        assert_eq!(left[..3], [None; 3], "estimating during warm-up");
        assert_eq!(left[3], Some(2.0 * 99.0), "after the first recorded frame");
        assert_eq!(left[52], Some(2.0 * 50.0));
        assert_eq!(left[102], Some(0.0));
        // Without warm-up the first frame compiles the shaders: the pace
        // starts after it.
        let seconds: Vec<u64> = [100].into_iter().chain([2; 9]).collect();
        let left = estimates(&seconds, 0);
        assert_eq!(left[..2], [None, Some(2.0 * 8.0)]);
    }
}
