//! Result files of a bench run: frames.csv (one row per mode and frame),
//! summary.json (machine-readable, versioned) and report.md (for people).

pub mod charts;
pub mod compare;
pub mod github;
mod markdown;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::gpu::{AdapterReport, Resolution};
use crate::hierarchy::{Hierarchy, HierarchyParams, HierarchyStats};
use crate::measure::{FrameStats, MissedObject, ModeSummary};
use crate::scene::Scene;

pub use markdown::render as render_markdown;

/// Bumped whenever a field of summary.json changes meaning or disappears
/// (adding fields does not bump it).
pub const SCHEMA_VERSION: u32 = 1;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub schema_version: u32,
    pub tool: ToolInfo,
    pub adapter: AdapterReport,
    pub scene: SceneSummary,
    pub path: PathSummary,
    pub resolution: Resolution,
    pub frames: u32,
    pub warmup: u32,
    pub error_measured: bool,
    pub modes: Vec<ModeSummary>,
    /// Modes the adapter could not run, with why.
    pub skipped: Vec<SkippedMode>,
    /// The parameter sweep, if any: its mode summaries are labelled
    /// `MODE[KEY=VALUE]`, in the order of `values`.
    pub sweep: Option<SweepSummary>,
    /// What the modes got wrong; every row is in missed.csv.
    #[serde(default)]
    pub missed: MissedSummary,
    /// frames.csv's fingerprint, set when the results are written (absent
    /// in files from before it existed, which are read unchecked).
    #[serde(default)]
    pub frames_csv: Option<Fingerprint>,
}

/// The head of missed.csv, for report.md and machines.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct MissedSummary {
    /// Rows in missed.csv (0: no mode got anything wrong, and no file).
    pub rows: usize,
    /// The first [`MissedSummary::SHOWN`] of them.
    pub first: Vec<MissedObject>,
}

impl MissedSummary {
    /// Rows report.md lists.
    pub const SHOWN: usize = 10;

    pub fn of(missed: &[MissedObject]) -> MissedSummary {
        MissedSummary {
            rows: missed.len(),
            first: missed.iter().take(Self::SHOWN).cloned().collect(),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SkippedMode {
    pub mode: String,
    pub reason: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SweepSummary {
    pub mode: String,
    pub key: String,
    pub values: Vec<String>,
}

impl SweepSummary {
    pub fn label(&self, value: &str) -> String {
        format!("{}[{}={value}]", self.mode, self.key)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ToolInfo {
    pub name: String,
    pub version: String,
}

impl ToolInfo {
    pub fn current() -> ToolInfo {
        ToolInfo {
            name: env!("CARGO_PKG_NAME").into(),
            version: env!("CARGO_PKG_VERSION").into(),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SceneSummary {
    #[serde(flatten)]
    pub facts: SceneFacts,
    pub hierarchy_params: HierarchyParams,
    pub upload_ms: f64,
}

/// What `occlu info` says of a scene, and summary.json records.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SceneFacts {
    pub source: String,
    pub objects: usize,
    pub meshes: usize,
    pub triangles: u64,
    pub vertices: usize,
    pub bounds_min: [f64; 3],
    pub bounds_max: [f64; 3],
    pub hierarchy: HierarchyStats,
    /// Objects that move from frame to frame.
    #[serde(default)]
    pub movers: usize,
    pub warnings: Vec<String>,
    pub load_ms: f64,
    pub build_ms: f64,
}

impl SceneFacts {
    pub fn of(scene: &Scene, hierarchy: &Hierarchy, load_ms: f64, build_ms: f64) -> SceneFacts {
        SceneFacts {
            source: scene.source.clone(),
            objects: scene.objects.len(),
            meshes: scene.meshes.len(),
            triangles: scene.triangles(),
            vertices: scene.vertices.len(),
            bounds_min: scene.bounds.min.to_array(),
            bounds_max: scene.bounds.max.to_array(),
            hierarchy: hierarchy.stats(),
            movers: scene.movers.len(),
            warnings: scene.warnings.clone(),
            load_ms,
            build_ms,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PathSummary {
    pub source: String,
    pub keyframes: usize,
    pub near: f64,
}

#[derive(Debug, thiserror::Error)]
#[error("{}: {error}", path.display())]
pub struct ReportError {
    pub path: PathBuf,
    pub error: std::io::Error,
}

impl ReportError {
    /// Whether the user's input was at fault (a missing run, a bad --out),
    /// as opposed to the machine failing while running (a full disk).
    pub fn is_input_error(&self) -> bool {
        !matches!(
            self.error.kind(),
            std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded | std::io::ErrorKind::WriteZero
        )
    }
}

/// The files a run wrote.
pub struct ResultFiles {
    pub frames_csv: PathBuf,
    pub summary_json: PathBuf,
    pub report_md: PathBuf,
    /// Written only when a mode got something wrong.
    pub missed_csv: Option<PathBuf>,
    pub charts: Vec<PathBuf>,
}

/// Writes `bytes` to `path` whole or not at all: into a temporary file
/// beside it, then renamed over it.
pub fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    let fail = |error| ReportError {
        path: path.to_path_buf(),
        error,
    };
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(".occlu-partial");
    let temporary = PathBuf::from(temporary);
    let written = std::fs::write(&temporary, bytes).and_then(|()| std::fs::rename(&temporary, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    written.map_err(fail)
}

/// Writes `rows` to `path` as CSV with a header of field names.
fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<(), ReportError> {
    let fail = |error| ReportError {
        path: path.to_path_buf(),
        error,
    };
    let mut csv = csv::Writer::from_path(path).map_err(|e| fail(e.into()))?;
    for row in rows {
        csv.serialize(row).map_err(|e| fail(e.into()))?;
    }
    csv.flush().map_err(fail)
}

/// Writes an 8-bit RGB image as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ReportError> {
    let fail = |error: std::io::Error| ReportError {
        path: path.to_path_buf(),
        error,
    };
    let file = std::fs::File::create(path).map_err(fail)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // An I/O failure (a full disk) keeps its kind, so it exits as one.
    let encoding = |e: png::EncodingError| match e {
        png::EncodingError::IoError(io) => fail(io),
        e => fail(std::io::Error::other(e)),
    };
    let mut writer = encoder.write_header().map_err(encoding)?;
    writer.write_image_data(rgb).map_err(encoding)?;
    writer.finish().map_err(encoding)
}

/// Reads a run directory's summary.json and frames.csv (for `occlu plot`
/// and `occlu compare`).
pub fn read_results(dir: &Path) -> Result<(Summary, Vec<FrameStats>), ReportError> {
    let io = |path: PathBuf| move |error| ReportError { path, error };
    let json_path = dir.join("summary.json");
    let text = std::fs::read_to_string(&json_path).map_err(io(json_path.clone()))?;
    let summary: Summary = serde_json::from_str(&text)
        .map_err(|e| io(json_path.clone())(std::io::Error::other(format!("not an occlu summary: {e}"))))?;
    if summary.schema_version != SCHEMA_VERSION {
        return Err(io(json_path)(std::io::Error::other(format!(
            "schema_version {} is not the {SCHEMA_VERSION} this occlu reads",
            summary.schema_version
        ))));
    }
    let csv_path = dir.join("frames.csv");
    let bytes = crate::input::read_file(&csv_path, crate::input::MODEL_LIMIT).map_err(io(csv_path.clone()))?;
    if let Some(expected) = summary.frames_csv
        && Fingerprint::of(&bytes) != expected
    {
        return Err(io(csv_path)(std::io::Error::other(
            "does not match summary.json: written by another run, or changed or cut short since",
        )));
    }
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let rows = reader
        .deserialize()
        .collect::<Result<Vec<FrameStats>, _>>()
        .map_err(|e| io(csv_path)(std::io::Error::other(format!("not an occlu frames.csv: {e}"))))?;
    Ok((summary, rows))
}

/// A run's claim on its `--out` folder: `.occlu.lock`, holding the process
/// id, removed when the claim is dropped (the run ended, well or not).
#[must_use = "the folder is claimed only while the lock lives"]
pub struct OutputLock {
    path: PathBuf,
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Creates `out`, checks that files can be written there (so a bad `--out`
/// fails before a long run rather than after it) and claims it: a second
/// run into the same folder is refused while the first runs. A lock left by
/// a process that no longer runs (killed) is taken over.
pub fn prepare_output(out: &Path) -> Result<OutputLock, ReportError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| ReportError { path, error }
    };
    if out.exists() && !out.is_dir() {
        let error = std::io::Error::other("exists and is not a directory: --out names the folder results go to");
        return Err(io(out)(error));
    }
    std::fs::create_dir_all(out).map_err(io(out))?;
    let probe = out.join(".occlu-write-test");
    std::fs::write(&probe, b"").map_err(io(&probe))?;
    std::fs::remove_file(&probe).map_err(io(&probe))?;
    let path = out.join(".occlu.lock");
    for _ in 0..2 {
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(mut file) => {
                use std::io::Write as _;
                write!(file, "{}", std::process::id()).map_err(io(&path))?;
                return Ok(OutputLock { path });
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let holder = std::fs::read_to_string(&path)
                    .ok()
                    .and_then(|t| t.trim().parse::<u32>().ok());
                // Where /proc tells, a holder that no longer runs left it.
                let running = holder.is_some_and(|pid| Path::new(&format!("/proc/{pid}")).exists())
                    || !Path::new("/proc/self").exists();
                if running {
                    let who = holder.map_or("another occlu run".to_string(), |pid| format!("occlu process {pid}"));
                    return Err(io(&path)(std::io::Error::other(format!(
                        "{who} is writing results into this folder; use another --out (or remove this file if no run is)"
                    ))));
                }
                std::fs::remove_file(&path).map_err(io(&path))?;
            }
            Err(e) => return Err(io(&path)(e)),
        }
    }
    Err(io(&path)(std::io::Error::other("could not claim the folder")))
}

/// Writes a run's result files into `out`, whole or not at all: every
/// file is first written into a staging folder inside `out` and moved into
/// place only once all of them are complete, so a failure (a full disk)
/// leaves `out`'s earlier contents as they were. summary.json records
/// frames.csv's fingerprint, which [`read_results`] checks.
pub fn write_results(
    out: &Path,
    summary: &mut Summary,
    rows: &[FrameStats],
    missed: &[MissedObject],
) -> Result<ResultFiles, ReportError> {
    debug_assert_eq!(summary.missed, MissedSummary::of(missed), "the summary heads this list");
    let staging = out.join(STAGING);
    let staged = write_staged(&staging, summary, rows, missed);
    let moved = staged.and_then(|names| {
        for name in &names {
            std::fs::rename(staging.join(name), out.join(name)).map_err(|error| ReportError {
                path: out.join(name),
                error,
            })?;
        }
        if missed.is_empty() {
            // An earlier run's list must not pass for this run's.
            let stale = out.join("missed.csv");
            match std::fs::remove_file(&stale) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(ReportError { path: stale, error: e });
                }
                _ => {}
            }
        }
        Ok(names)
    });
    let _ = std::fs::remove_dir_all(&staging);
    let names = moved?;
    let path = |name: &str| out.join(name);
    Ok(ResultFiles {
        frames_csv: path("frames.csv"),
        summary_json: path("summary.json"),
        report_md: path("report.md"),
        missed_csv: (!missed.is_empty()).then(|| path("missed.csv")),
        charts: names.iter().filter(|n| n.ends_with(".png")).map(|n| path(n)).collect(),
    })
}

/// The folder inside `--out` that results are written into before they
/// are moved into place.
const STAGING: &str = ".occlu-staging";

/// Writes every result file into `staging` (made afresh) and returns their
/// names, frames.csv first.
fn write_staged(
    staging: &Path,
    summary: &mut Summary,
    rows: &[FrameStats],
    missed: &[MissedObject],
) -> Result<Vec<String>, ReportError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| ReportError { path, error }
    };
    let _ = std::fs::remove_dir_all(staging);
    std::fs::create_dir_all(staging).map_err(io(staging))?;
    let mut names = vec!["frames.csv".to_string()];
    let frames_csv = staging.join("frames.csv");
    write_csv(&frames_csv, rows)?;
    summary.frames_csv = Some(Fingerprint::of(&std::fs::read(&frames_csv).map_err(io(&frames_csv))?));
    if !missed.is_empty() {
        write_csv(&staging.join("missed.csv"), missed)?;
        names.push("missed.csv".into());
    }
    let json = serde_json::to_string_pretty(summary).expect("summary serialises: no maps with non-string keys");
    let summary_json = staging.join("summary.json");
    std::fs::write(&summary_json, json + "\n").map_err(io(&summary_json))?;
    let report_md = staging.join("report.md");
    std::fs::write(&report_md, render_markdown(summary)).map_err(io(&report_md))?;
    names.extend(["summary.json".to_string(), "report.md".to_string()]);
    for chart in charts::write_charts(staging, summary, rows)? {
        names.push(
            chart
                .file_name()
                .expect("a chart is a file")
                .to_string_lossy()
                .into_owned(),
        );
    }
    Ok(names)
}

/// What identifies a frames.csv: its length and FNV-1a hash. Not a defence
/// against forgery, only against a file from another run or cut short.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Fingerprint {
    pub bytes: u64,
    /// FNV-1a (64 bits) of the file, in hex.
    #[serde(with = "hex64")]
    pub fnv1a: u64,
}

impl Fingerprint {
    pub fn of(bytes: &[u8]) -> Fingerprint {
        let fnv1a = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        Fingerprint {
            bytes: bytes.len() as u64,
            fnv1a,
        }
    }
}

/// A u64 as a hex string, which JSON readers that hold numbers in doubles
/// keep whole.
mod hex64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        u64::from_str_radix(&text, 16).map_err(serde::de::Error::custom)
    }
}
