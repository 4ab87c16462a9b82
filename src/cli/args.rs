//! The command line's shape: every subcommand, flag and help text as clap
//! types, and how a few of them turn into the library's values (a scene's
//! spec and load options, a picture's look). Nothing here runs anything.

use std::path::PathBuf;

use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand};
use occlu::animation::{FrameRange, MAX_SCALE};
use occlu::camera::generate::PathRequest;
use occlu::config::{ConfigError, load_options, scene_spec};
use occlu::gpu::{BackendChoice, Resolution};
use occlu::input::ByteSize;
use occlu::matrix::Shard;
use occlu::picture::Look;
use occlu::report::compare::Metric;
use occlu::scene::builtin::SCENES;
use occlu::scene::up::UpChoice;
use occlu::scene::{LoadOptions, SceneSpec};

#[derive(Parser)]
#[command(
    name = "occlu",
    version,
    about = "Benchmark occlusion culling: replay a camera path offscreen in each culling mode and report frame time next to image error.",
    after_help = after_help()
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
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
pub enum Command {
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
    /// coplanar walls, 1° and 170° fields of view, 1° with the eye nearly
    /// touching a wall, vertical views, teleports) through every mode
    /// against the DR reference; exit 1 when a conservative mode shows any
    /// error or a moved case renders differently.
    Stress(StressArgs),
    /// Write a scene as occlu holds it (after clustering) and a camera path
    /// (as a camera animation) to a GLB, to replay them in another engine.
    Export(ExportArgs),
    /// Draw a run's charts (and report.md) again from its frames.csv and summary.json.
    Plot(PlotArgs),
    /// Merge result folders from many machines and adapters (bench --out
    /// folders, or matrix folders of run folders, e.g. one per CI shard)
    /// into one report: per run, its modes on every adapter side by side
    /// (never averaged), a chart of each mode's ratio to the oracle per
    /// adapter, counters that differ between adapters of one backend
    /// flagged; merged.json for machines, and a copy of every run folder
    /// under runs/. Folders of one run that measured different scenes,
    /// paths, resolutions or frame counts are refused.
    Merge(MergeArgs),
    /// Compare two bench runs for CI: exit 1 when a counter (triangles,
    /// queries, round trips, wrong pixels, missed objects) grows, or when the
    /// mean frame time grows beyond --max-regression and beyond the measured
    /// noise (the 95 % interval of the ratio of the means, from frames paired
    /// along the path); exit 2 when it cannot judge (runs that cannot be
    /// compared, a verdict it cannot write). Two merged folders (occlu
    /// merge) compare run by run and adapter by adapter.
    Compare(CompareArgs),
}

/// A frame count as `--frames` takes it: 1 to the most a path may have,
/// said in the message for any other number (u32's own range would be).
fn frame_count() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(occlu::camera::path::MAX_FRAMES))
}

/// Extensions of image formats other than PNG, as a picture's file may
/// be misnamed with one.
const OTHER_IMAGE_KINDS: &[&str] = &[
    "jpg", "jpeg", "gif", "webp", "bmp", "tif", "tiff", "tga", "exr", "hdr", "avif", "heic", "ppm", "qoi",
];

/// Extensions of model formats other than GLB, as an exported scene's
/// file may be misnamed with one (occlu reads .obj and .gltf by their
/// extension, so it would refuse its own export so named).
const OTHER_MODEL_KINDS: &[&str] = &[
    "obj", "gltf", "fbx", "stl", "ply", "dae", "3ds", "usd", "usda", "usdc", "usdz",
];

/// An output file as `--output` takes it, for a command that writes only
/// `kind` files: a name that says another format of its family (`others`:
/// `frame.jpg` for a picture) is refused, rather than given bytes of
/// another kind; any other name is taken.
fn output_of(kind: &'static str, others: &'static [&'static str]) -> impl TypedValueParser<Value = PathBuf> {
    clap::builder::PathBufValueParser::new().try_map(move |path: PathBuf| {
        let named = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match named.filter(|named| others.contains(&named.as_str())) {
            Some(named) => Err(format!(
                "occlu writes {kind} only, and '{}' names a .{named} file: name it .{}",
                path.display(),
                kind.to_ascii_lowercase()
            )),
            None => Ok(path),
        }
    })
}

/// Where the scene comes from: a file, or a built-in scene (the city by default).
#[derive(Args)]
pub struct SceneArgs {
    /// Model file: .obj, .gltf or .glb. Without one, the built-in city.
    pub model: Option<PathBuf>,
    /// Built-in scene, NAME[:key=value,...], e.g. city:blocks=4,seed=7.
    #[arg(long, conflicts_with = "model")]
    pub scene: Option<String>,
    /// Cars driving round the city's blocks, so culling meets moving
    /// objects (the scene's movers=N parameter) [default: 0].
    #[arg(long, value_name = "N", conflicts_with = "model")]
    pub movers: Option<u32>,
    /// Meshes with more triangles than this are split into clusters [default: 4096].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub cluster_triangles: Option<u32>,
    /// Largest model or glTF buffer file read, e.g. 512M or 16G; larger
    /// files, and files that grow past it while read, are refused [default: 4G].
    #[arg(long, value_name = "SIZE")]
    pub max_file_size: Option<ByteSize>,
    /// Let a glTF file's buffers lie outside its folder (absolute paths,
    /// "..", file: URIs). Off by default, so a model from elsewhere cannot
    /// make occlu read other files (=false overrides a config file; the
    /// value needs its `=`, so `--external-buffers MODEL` reads MODEL).
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub external_buffers: Option<bool>,
    /// The scene's up axis, for generated paths, the overview and swr's
    /// cells (taller where the camera looks level in it): x, y, z,
    /// -x, -y, -z, or auto (+Y for glTF and built-in scenes; for OBJ, +Z
    /// when the model is at least twice as flat in Z as across and stands
    /// on its Z minimum, else +Y) [default: auto].
    #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
    pub up: Option<UpChoice>,
}

impl SceneArgs {
    pub fn spec(&self) -> Result<SceneSpec, ConfigError> {
        scene_spec(self.model.clone(), self.scene.clone(), self.movers)
    }

    pub fn options(&self) -> LoadOptions {
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
pub struct SceneAndPath {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Camera path (JSON) [default: the path bench would generate].
    #[arg(long, value_name = "FILE")]
    pub path: Option<PathBuf>,
    /// Resamples the path to this many frames, as bench's --frames does
    /// [default: the path's].
    #[arg(long, value_name = "N", value_parser = frame_count())]
    pub frames: Option<u32>,
}

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Camera path (JSON); generated from the scene when omitted (the city:
    /// a street-level walk; models: an orbit).
    #[arg(long, value_name = "FILE")]
    pub path: Option<PathBuf>,
    /// Modes to run, comma-separated, or "all" [default: all].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub modes: Option<Vec<String>>,
    /// Frames to record; resamples the path [default: the path's].
    #[arg(long, value_name = "N", value_parser = frame_count())]
    pub frames: Option<u32>,
    /// Frames run before recording starts [default: 10].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=i64::from(occlu::config::MAX_WARMUP)))]
    pub warmup: Option<u32>,
    /// Render size [default: 800x600].
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<Resolution>,
    /// Graphics API; auto honours WGPU_BACKEND [default: auto].
    #[arg(long, value_enum)]
    pub backend: Option<BackendChoice>,
    /// Run configuration (JSON, see configs/); flags override it. A file
    /// listing "runs" (or "models"/"scenes" × "paths") is a matrix: every
    /// run goes into a folder of its own under --out, its fields over the
    /// file's, flags over both.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Run only the K-th of N shares of the matrix (1 <= K <= N): its runs
    /// K, K+N, K+2N, ..., so N CI jobs given 1/N ... N/N run every run once.
    /// A configuration that lists no runs is a matrix of one.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Output directory [default: occlu-out].
    #[arg(long, short, visible_alias = "output", value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Skip the reference render and error measure (faster; error columns stay empty).
    #[arg(long)]
    pub no_error: bool,
    /// Also write flythrough.png beside the charts: every recorded frame,
    /// each mode's picture beside the scene from above (as render
    /// --overview paints it, at half size), with its frame time.
    #[arg(long)]
    pub animate: bool,
    /// Print summary.json (every mode's statistics) to stdout instead of
    /// report.md; report.md is still written.
    #[arg(long)]
    pub json: bool,
    /// Also write FILE for github-action-benchmark (customSmallerIsBetter):
    /// per mode frame ms mean and p95, triangles drawn, wrong pixels.
    #[arg(long, value_name = "FILE")]
    pub export_github_benchmark: Option<PathBuf>,
    /// Also write the run's timeline to FILE as Trace Event JSON (open it
    /// in ui.perfetto.dev or chrome://tracing): per mode, each frame's
    /// culling, commands and waits on the CPU, and its box tests and
    /// drawing on the GPU where the adapter has timestamps.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Print no progress and no notes on stderr, only errors.
    #[arg(long, short)]
    pub quiet: bool,
    /// A mode parameter, MODE.KEY=VALUE (repeatable, each key once), e.g.
    /// omq.om=80x60; of a mode that runs, or of one of auto's candidates
    /// where auto runs.
    #[arg(long = "param", value_name = "MODE.KEY=VALUE")]
    pub params: Vec<String>,
    /// Run one mode at several values of a parameter in the same run, e.g.
    /// ac.threshold=0,100,1000 (labels like ac[threshold=100]).
    #[arg(long, value_name = "MODE.KEY=V1,V2,...")]
    pub sweep: Option<String>,
}

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneAndPath,
    /// Frame of the path to render (0-based).
    #[arg(long, value_name = "K")]
    pub frame: u32,
    /// The culling mode whose frame is rendered.
    #[arg(long, value_name = "MODE")]
    pub mode: String,
    #[command(flatten)]
    pub picture: PictureArgs,
    /// Compare the frame with direct rendering: paint the pixels whose depth
    /// differs in magenta and outline the boxes of the objects the mode
    /// missed, and list them.
    #[arg(long)]
    pub show_missed: bool,
    /// Lay the depth buffer a CPU culling mode culled the frame with
    /// over the picture: cells holding an occluder's depth from white (near)
    /// to deep blue (far; all of them when they share one depth), tinted
    /// orange at pixels whose depth is that of occluders covering only part
    /// of their cell (that depth counts only at those pixels), the rest of
    /// the frame dimmed.
    #[arg(long)]
    pub occluders: bool,
}

/// How `render` and `flythrough` picture a mode's frame, and where to.
#[derive(Args)]
pub struct PictureArgs {
    /// A mode parameter, MODE.KEY=VALUE (repeatable, each key once).
    #[arg(long = "param", value_name = "MODE.KEY=VALUE")]
    pub params: Vec<String>,
    /// Output PNG (animated, for flythrough).
    #[arg(long, short, visible_alias = "out", value_name = "FILE", value_parser = output_of("PNG", OTHER_IMAGE_KINDS))]
    pub output: PathBuf,
    /// Add a bird's-eye view beside each mode's frame: the frustum in red,
    /// culled objects' boxes in yellow.
    #[arg(long)]
    pub overview: bool,
    /// Colour pixels by depth complexity (surfaces drawn over them) instead of shading.
    #[arg(long)]
    pub heat: bool,
    /// Render size [default: 800x600].
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<Resolution>,
    /// Graphics API [default: auto].
    #[arg(long, value_enum)]
    pub backend: Option<BackendChoice>,
}

impl PictureArgs {
    /// The look these flags ask for, with `render`'s own two.
    pub fn look(&self, show_missed: bool, occluders: bool) -> Look {
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
pub struct FlythroughArgs {
    #[command(flatten)]
    pub scene: SceneAndPath,
    /// Modes side by side, comma-separated, or "all".
    #[arg(long, value_delimiter = ',', value_name = "LIST", required = true)]
    pub modes: Vec<String>,
    /// Frames A to B-1 of the path, every STEP-th pictured (all of them
    /// run; the two before A first, as render runs them) [default: the
    /// whole path].
    #[arg(long, value_name = "A..B[:STEP]")]
    pub range: Option<FrameRange>,
    #[command(flatten)]
    pub picture: PictureArgs,
    /// Panels are the pictures shrunk by K: each pixel the mean of K x K
    /// (a picture smaller than K across is shrunk to one pixel) [default: 2].
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SCALE)))]
    pub scale: Option<u32>,
    /// Every pixel as painted (24-bit) instead of one palette of 256
    /// colours for the whole animation: exact, about three times larger.
    #[arg(long)]
    pub true_colour: bool,
    /// Print no progress and no notes on stderr, only errors.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Args)]
pub struct StressArgs {
    /// Modes to run, comma-separated, or "all" [default: all].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub modes: Option<Vec<String>>,
    /// Cases to run, comma-separated [default: all]; --list shows them.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub cases: Vec<String>,
    /// Print the cases and exit.
    #[arg(long)]
    pub list: bool,
    /// Render size [default: 400x300].
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<Resolution>,
    /// Graphics API; auto honours WGPU_BACKEND [default: auto].
    #[arg(long, value_enum)]
    pub backend: Option<BackendChoice>,
    /// Also write stress.md and stress.json here.
    #[arg(long, short, visible_alias = "output", value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// A mode parameter, MODE.KEY=VALUE (repeatable, each key once), of a
    /// mode that runs (or of auto's candidates where auto runs), e.g.
    /// hiz.texels=2 to check a tuned mode. It is set over the values that
    /// exercise every frame (swr.rests=false, chc.visible_for=1), which
    /// the other keys keep.
    #[arg(long = "param", value_name = "MODE.KEY=VALUE")]
    pub params: Vec<String>,
}

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum PathCommand {
    /// Write a camera path made from a scene: its shape, or a glTF file's
    /// own cameras and camera animations.
    Gen(PathGenArgs),
}

#[derive(Args)]
pub struct PathGenArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// orbit, walk, flyover, cameras (the file's cameras in order) or
    /// animation[=NAME] (an animation that moves a camera) [default: the
    /// file's animated camera; a walk for streets, places, interiors
    /// and domes; an orbit for objects].
    #[arg(long, value_name = "KIND")]
    pub kind: Option<PathRequest>,
    /// Frames of the path [default: 120; one per camera for cameras; the
    /// animation's own time at 30 per second for animation].
    #[arg(long, value_name = "N", value_parser = frame_count())]
    pub frames: Option<u32>,
    /// Output file.
    #[arg(long, short, visible_alias = "out", value_name = "FILE")]
    pub output: PathBuf,
}

#[derive(Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub scene: SceneAndPath,
    /// Output .glb file.
    #[arg(long, short, visible_alias = "out", value_name = "FILE", value_parser = output_of("GLB", OTHER_MODEL_KINDS))]
    pub output: PathBuf,
}

#[derive(Args)]
pub struct PlotArgs {
    /// A bench output directory.
    pub run_dir: PathBuf,
}

#[derive(Args)]
pub struct MergeArgs {
    /// Result folders: a run's folder (holding summary.json) or a
    /// folder of them (a matrix's --out).
    #[arg(value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Where merged.json, report.md, charts/ and runs/ go.
    #[arg(long, short, visible_alias = "output", value_name = "MERGED")]
    pub out: PathBuf,
    /// Merge a matrix that lacks runs (a shard left out, a run that
    /// failed): the runs present are merged and the missing ones named
    /// in the report and merged.json. Without it such a merge is
    /// refused (exit 2), naming them.
    #[arg(long)]
    pub allow_partial: bool,
}

#[derive(Args)]
pub struct CompareArgs {
    /// The reference run's output directory (or merged folder).
    pub base: PathBuf,
    /// The run to judge (or merged folder).
    pub new: PathBuf,
    /// Allowed growth of mean frame time, percent. (A negative number is
    /// taken as its value, to be refused with the rule, not as a flag.)
    #[arg(long, default_value_t = 5.0, value_name = "PCT", allow_negative_numbers = true)]
    pub max_regression: f64,
    /// Metrics to gate on, comma-separated [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub metric: Vec<Metric>,
    /// Let the new run lack modes or metrics the base measured (e.g. run
    /// with fewer --modes or with --no-error) without failing.
    #[arg(long)]
    pub allow_missing: bool,
    /// Compare runs from different adapters or backends (counters only:
    /// frame times are not comparable across them; where the adapters work
    /// differently, as another backend or sub-pixel precision does, only
    /// wrong pixels and missed objects).
    #[arg(long)]
    pub cross_adapter: bool,
    /// Print the verdicts as JSON (for machines) instead of the table.
    #[arg(long)]
    pub json: bool,
}
