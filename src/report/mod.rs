//! Result files of a bench run: frames.csv (one row per mode and frame),
//! summary.json (machine-readable, versioned) and report.md (for people).

pub mod charts;
pub mod compare;
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

/// The files a run wrote.
pub struct ResultFiles {
    pub frames_csv: PathBuf,
    pub summary_json: PathBuf,
    pub report_md: PathBuf,
    /// Written only when a mode got something wrong.
    pub missed_csv: Option<PathBuf>,
    pub charts: Vec<PathBuf>,
}

/// Writes `rows` to `path` as CSV with a header of field names.
fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<(), ReportError> {
    let fail = |error| ReportError {
        path: path.to_path_buf(),
        error,
    };
    let mut csv = csv::Writer::from_path(path).map_err(|e| fail(std::io::Error::other(e)))?;
    for row in rows {
        csv.serialize(row).map_err(|e| fail(std::io::Error::other(e)))?;
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
    let mut writer = encoder.write_header().map_err(|e| fail(std::io::Error::other(e)))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| fail(std::io::Error::other(e)))?;
    writer.finish().map_err(|e| fail(std::io::Error::other(e)))
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
    let mut reader = csv::Reader::from_path(&csv_path).map_err(|e| io(csv_path.clone())(std::io::Error::other(e)))?;
    let rows = reader
        .deserialize()
        .collect::<Result<Vec<FrameStats>, _>>()
        .map_err(|e| io(csv_path)(std::io::Error::other(format!("not an occlu frames.csv: {e}"))))?;
    Ok((summary, rows))
}

/// Creates `out` and checks that files can be written there, so a bad
/// `--out` fails before a long run rather than after it.
pub fn prepare_output(out: &Path) -> Result<(), ReportError> {
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
    std::fs::remove_file(&probe).map_err(io(&probe))
}

pub fn write_results(
    out: &Path,
    summary: &Summary,
    rows: &[FrameStats],
    missed: &[MissedObject],
) -> Result<ResultFiles, ReportError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| ReportError { path, error }
    };
    debug_assert_eq!(summary.missed, MissedSummary::of(missed), "the summary heads this list");
    std::fs::create_dir_all(out).map_err(io(out))?;
    let missed_csv = out.join("missed.csv");
    let files = ResultFiles {
        frames_csv: out.join("frames.csv"),
        summary_json: out.join("summary.json"),
        report_md: out.join("report.md"),
        missed_csv: (!missed.is_empty()).then(|| missed_csv.clone()),
        charts: Vec::new(),
    };
    write_csv(&files.frames_csv, rows)?;
    if missed.is_empty() {
        // An earlier run's list must not pass for this run's.
        match std::fs::remove_file(&missed_csv) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(&missed_csv)(e)),
            _ => {}
        }
    } else {
        write_csv(&missed_csv, missed)?;
    }
    let json = serde_json::to_string_pretty(summary).expect("summary serialises: no maps with non-string keys");
    std::fs::write(&files.summary_json, json + "\n").map_err(io(&files.summary_json))?;
    std::fs::write(&files.report_md, render_markdown(summary)).map_err(io(&files.report_md))?;
    let charts = charts::write_charts(out, summary, rows)?;
    Ok(ResultFiles { charts, ..files })
}
