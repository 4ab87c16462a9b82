//! What a merge makes: merged.json's types (runs with their adapters as
//! columns, each mode's results, the counters adapters disagree on, the
//! runs a partial matrix lacks), the names of the copies and charts in the
//! merged folder, and merged.json read back for `compare`.

use std::collections::BTreeSet;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::gpu::Resolution;
use crate::measure::ModeSummary;
use crate::report::files::ReportError;
use crate::report::summary::{Fingerprint, MatrixIdentity, SkippedMode, ToolInfo};
use crate::text::slug;

/// merged.json's version, bumped as summary.json's is.
pub const MERGED_SCHEMA_VERSION: u32 = 1;

/// What merged.json holds.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Merged {
    pub schema_version: u32,
    pub tool: ToolInfo,
    pub runs: Vec<MergedRun>,
    /// Runs of a matrix that no merged folder held (merged with
    /// `--allow-partial`); absent in files from before it was recorded.
    #[serde(default)]
    pub missing: Vec<MissingRuns>,
}

/// The runs of one matrix that a partial merge lacks.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MissingRuns {
    pub matrix: MatrixIdentity,
    /// Runs of the matrix that are here.
    pub present: usize,
    /// The places of those that are not (`02`: the folder `02-…`).
    pub runs: Vec<String>,
}

impl MissingRuns {
    /// Which runs are missing, as plain text: the error, the report and
    /// the warning on stderr all say it.
    pub fn describe(&self) -> String {
        const SHOWN: usize = 10;
        let mut places = self.runs.iter().take(SHOWN).cloned().collect::<Vec<_>>().join(", ");
        if self.runs.len() > SHOWN {
            places += &format!(" and {} more", self.runs.len() - SHOWN);
        }
        format!(
            "{} of the matrix's {} here (#{:016x}); missing: run {places} (a shard not merged, or a run that failed)",
            self.present,
            crate::text::count(self.matrix.runs, "run"),
            self.matrix.names
        )
    }
}

/// One run (a matrix run, or a scene and path) on every adapter that ran it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MergedRun {
    /// The matrix run's name, or the scene's and path's.
    pub name: String,
    pub scene: String,
    pub path: String,
    pub resolution: Resolution,
    pub frames: u32,
    /// The columns, sorted by name and backend.
    pub adapters: Vec<AdapterColumn>,
    /// Every mode any adapter ran, in the order the first that ran it gave.
    pub modes: Vec<ModeRow>,
    /// Counters that differ between adapters of one backend.
    pub disagreements: Vec<Disagreement>,
    /// The ratio-to-oracle chart, relative to the merged folder; `None`
    /// when no adapter ran the oracle.
    pub chart: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AdapterColumn {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    /// The copy of its run folder, relative to the merged folder.
    pub folder: String,
    /// The folder it was merged from, as given (lossily as text: a folder
    /// name need not be UTF-8, and JSON holds text).
    pub merged_from: String,
    /// Modes this adapter could not run, with why.
    pub skipped: Vec<SkippedMode>,
    /// Whether wrong pixels were measured (false: run with --no-error).
    pub error_measured: bool,
}

impl AdapterColumn {
    pub fn label(&self) -> String {
        adapter_label(&self.name, &self.backend)
    }
}

/// An adapter as a column's heading: its name and backend.
pub(super) fn adapter_label(name: &str, backend: &str) -> String {
    format!("{name} ({backend})")
}

/// A mode's results, one per adapter column (`None`: not run there).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ModeRow {
    pub mode: String,
    pub results: Vec<Option<ModeResult>>,
}

/// What the merged report shows of a mode on one adapter: means per frame,
/// and the run's total of wrong pixels.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ModeResult {
    pub frame_ms: Option<f64>,
    pub ratio_to_oracle: Option<f64>,
    pub error_pixels: Option<u64>,
    pub objects_drawn: Option<f64>,
    pub triangles_drawn: Option<f64>,
    pub queries: Option<f64>,
    pub round_trips: Option<f64>,
}

impl ModeResult {
    pub(super) fn of(m: &ModeSummary) -> ModeResult {
        let mean = |column: &str| m.stats.get(column).map(|d| d.mean);
        ModeResult {
            frame_ms: mean("frame_ms"),
            ratio_to_oracle: m.ratio_to_oracle,
            error_pixels: m.error_pixels_total,
            objects_drawn: mean("objects_drawn"),
            triangles_drawn: mean("triangles_drawn"),
            queries: mean("queries"),
            round_trips: mean("query_batches"),
        }
    }
}

/// A counter that two adapters of one backend measured differently.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Disagreement {
    pub mode: String,
    pub counter: String,
    pub backend: String,
    /// Each adapter of the backend and its value.
    pub values: Vec<(String, f64)>,
}

impl Disagreement {
    /// What differs, and each adapter's value, as plain text: the report
    /// and the warning on stderr both say it.
    pub fn describe(&self) -> String {
        let values: Vec<String> = self
            .values
            .iter()
            .map(|(a, v)| format!("{a} {}", number(Some(*v), 1)))
            .collect();
        format!(
            "{} {} differs between {} adapters ({})",
            self.mode,
            self.counter,
            self.backend,
            values.join(", ")
        )
    }
}

/// `stem` + `extension`, or with `-2`, `-3`, … after the stem when `used`
/// has it; marked used. (Names are unique by construction, a hash of what
/// they name included; this keeps a collision from overwriting a file.)
pub(super) fn unique(stem: String, extension: &str, used: &mut BTreeSet<String>) -> String {
    let mut candidate = format!("{stem}{extension}");
    let mut n = 1;
    while !used.insert(candidate.clone()) {
        n += 1;
        candidate = format!("{stem}-{n}{extension}");
    }
    candidate
}

/// A run folder's copy under `runs/`: the run's and the adapter's names as
/// slugs (cut short, so they only say what it holds) and a hash of the
/// whole identity, so two runs or adapters whose names share their first
/// characters never share a folder.
pub(super) fn column_folder(run: &str, adapter: &str, backend: &str) -> String {
    let identity = Fingerprint::of(format!("{run}\n{adapter}\n{backend}").as_bytes());
    format!(
        "runs/{}--{}-{:08x}",
        slug(run),
        slug(&format!("{adapter} {backend}")),
        identity.fnv1a >> 32
    )
}

/// `v` with up to `decimals` decimals (none for whole numbers), `–` when
/// not measured.
pub(super) fn number(v: Option<f64>, decimals: usize) -> String {
    match v {
        None => "–".into(),
        Some(v) if v.fract() == 0.0 => format!("{v:.0}"),
        Some(v) => format!("{v:.decimals$}"),
    }
}

/// Reads a merged folder's merged.json (for `occlu compare`); `None` when
/// `dir` holds none.
pub fn read_merged(dir: &Path) -> Result<Option<Merged>, ReportError> {
    let path = dir.join("merged.json");
    if !path.exists() {
        return Ok(None);
    }
    let io = ReportError::at(&path);
    let text = crate::input::read_text(&path, crate::input::TEXT_LIMIT).map_err(&io)?;
    let merged: Merged =
        serde_json::from_str(&text).map_err(|e| io(std::io::Error::other(format!("not an occlu merged.json: {e}"))))?;
    if merged.schema_version != MERGED_SCHEMA_VERSION {
        return Err(io(std::io::Error::other(format!(
            "schema_version {} is not the {MERGED_SCHEMA_VERSION} this occlu reads",
            merged.schema_version
        ))));
    }
    Ok(Some(merged))
}
