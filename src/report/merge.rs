//! `occlu merge DIR... --out MERGED`: result folders from many machines in
//! one report.
//!
//! A DIR is a run's folder (it holds summary.json) or a folder of them (a
//! matrix's `--out`, one per shard or machine). Folders are one run when
//! summary.json names the same matrix run, or, for runs outside a matrix,
//! when they measured the same scene and path; one run's folders must agree
//! on scene (the geometry's fingerprint), path (the cameras'), resolution
//! and frames, or the merge is refused. Within a run each adapter (name and
//! backend) is a column beside the others, never averaged; two folders of
//! one run on one adapter are refused unless they are copies of one result.
//!
//! Counters that do not depend on the adapter (objects and triangles drawn,
//! boxes tested, wrong pixels) are compared between adapters of the same
//! backend: a difference is listed in the report and merged.json, as it
//! points at a bug in one backend's path. It does not fail the merge;
//! `occlu compare` of merged folders is the gate.
//!
//! MERGED gets merged.json (for machines), report.md, `charts/` (each
//! run's ratio to the oracle per adapter) and `runs/` (a copy of every
//! merged run folder, `RUN--ADAPTER-HASH`, the hash of the run's and the
//! adapter's full names so that names cut short never collide; `occlu
//! compare` of two merged folders pairs them by the run, adapter and
//! backend merged.json records, not by folder name).

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::charts::{CHARTS, RatioBars, ratio_to_oracle_bars};
use super::files::ReportError;
use super::summary::{Fingerprint, MatrixIdentity, SkippedMode, Summary, ToolInfo};
use super::{RESULT_FILES, prepare_output, publish, read_results};
use crate::gpu::Resolution;
use crate::measure::ModeSummary;
use crate::text::{markdown, slug};

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
fn adapter_label(name: &str, backend: &str) -> String {
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
    fn of(m: &ModeSummary) -> ModeResult {
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

/// Reads a counter of a [`ModeResult`].
type Counter = fn(&ModeResult) -> Option<f64>;

/// The counters every adapter of one backend must agree on, by name.
const SAME_ON_EVERY_ADAPTER: [(&str, Counter); 4] = [
    ("objects_drawn", |r| r.objects_drawn),
    ("triangles_drawn", |r| r.triangles_drawn),
    ("queries", |r| r.queries),
    ("error_pixels", |r| r.error_pixels.map(|v| v as f64)),
];

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

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error(transparent)]
    Read(#[from] ReportError),
    #[error("no result folders to merge: give one or more DIRs")]
    NoFolders,
    #[error("{}: not a result folder (no summary.json) and holds none", .0.display())]
    NoRuns(PathBuf),
    #[error("{}: a merged folder (merged.json), not a result folder: merge the run folders in its runs/ instead", .0.display())]
    MergedFolder(PathBuf),
    #[error(
        "{}: a folder of the matrix folder {} without summary.json (a run that failed or still runs?): a partial matrix is not merged; remove it or finish the run",
        folder.display(), matrix.display()
    )]
    NotARun { matrix: PathBuf, folder: PathBuf },
    #[error("a partial matrix: {}: merge every shard's folder, or give --allow-partial to merge these alone", .0.describe())]
    Partial(MissingRuns),
    #[error("--out {} holds a bench run: merging into it would replace its report.md; choose another --out", .0.display())]
    OutHoldsRun(PathBuf),
    #[error("--out {} is, holds or lies in the input {}: the merge would write over what it reads; choose another --out", out.display(), input.display())]
    OutOverlapsInput { out: PathBuf, input: PathBuf },
    #[error(
        "{} and {} are both run {run} but measured different {what} ({} vs {}): not one run (from two matrices?), so not merged",
        folders[0].display(), folders[1].display(), values[0], values[1]
    )]
    NotOneRun {
        run: String,
        folders: Box<[PathBuf; 2]>,
        what: &'static str,
        /// What each folder measured.
        values: Box<[String; 2]>,
    },
    #[error(
        "{} and {} both hold run {run} on {adapter} with different results: which one counts is ambiguous, so merge one of them",
        first.display(), second.display()
    )]
    Ambiguous {
        run: String,
        adapter: String,
        first: PathBuf,
        second: PathBuf,
    },
}

impl MergeError {
    /// Whether the user's input was at fault (as opposed to a full disk).
    pub fn is_input_error(&self) -> bool {
        match self {
            MergeError::Read(e) => e.is_input_error(),
            _ => true,
        }
    }
}

/// One result folder read for the merge.
struct RunFolder {
    dir: PathBuf,
    summary: Summary,
    /// The result files it holds, to be copied.
    files: Vec<&'static str>,
}

impl RunFolder {
    /// Which run it is: its matrix run's name, or its scene's and path's.
    fn run(&self) -> String {
        let s = &self.summary;
        s.run
            .clone()
            .unwrap_or_else(|| format!("{}, {}", s.scene.facts.source, s.path.source))
    }

    /// Whether `other` is the same run: the same matrix run by name, or,
    /// outside a matrix, the same scene and path by their fingerprints (by
    /// their sources' names for files from before fingerprints, so that
    /// `held.json` and `/abs/held.json` are one path when they can be told).
    fn same_run(&self, other: &RunFolder) -> bool {
        let (a, b) = (&self.summary, &other.summary);
        match (&a.run, &b.run) {
            (Some(x), Some(y)) => x == y,
            (None, None) => {
                same_thing(
                    (&a.scene.facts.source, a.scene.facts.geometry),
                    (&b.scene.facts.source, b.scene.facts.geometry),
                ) && same_thing((&a.path.source, a.path.cameras), (&b.path.source, b.path.cameras))
            }
            _ => false,
        }
    }

    /// The first thing `other`, the same run, measured differently, if
    /// any: what it is and each folder's value. What a user sets (frames,
    /// resolution, warmup, mode parameters) comes before the fingerprints,
    /// which a different frame count changes too, so the message names the
    /// real difference.
    fn differs_from(&self, other: &RunFolder) -> Option<(&'static str, String, String)> {
        let (a, b) = (&self.summary, &other.summary);
        let identity = |what, (source_a, fa): (&String, Option<Fingerprint>), (source_b, fb)| {
            let show = |source: &String, f: Option<Fingerprint>| match f {
                Some(f) if source_a == source_b => format!("{source} #{:016x}", f.fnv1a),
                _ => source.clone(),
            };
            (!same_thing((source_a, fa), (source_b, fb))).then(|| (what, show(source_a, fa), show(source_b, fb)))
        };
        let plain = |what, x: String, y: String| (x != y).then_some((what, x, y));
        let params = |s: &Summary, other: &Summary| -> String {
            s.modes
                .iter()
                .filter(|m| other.modes.iter().any(|o| o.name == m.name))
                .map(|m| format!("{} {}", m.name, m.parameters))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let matrices = match (a.matrix, b.matrix) {
            (Some(x), Some(y)) => plain("matrices", x.to_string(), y.to_string()),
            // A file from before matrices were recorded is judged by the rest.
            _ => None,
        };
        matrices
            .or_else(|| plain("frame counts", a.frames.to_string(), b.frames.to_string()))
            .or_else(|| plain("resolutions", a.resolution.to_string(), b.resolution.to_string()))
            .or_else(|| plain("warmup frames", a.warmup.to_string(), b.warmup.to_string()))
            .or_else(|| plain("mode parameters", params(a, b), params(b, a)))
            .or_else(|| {
                identity(
                    "scenes",
                    (&a.scene.facts.source, a.scene.facts.geometry),
                    (&b.scene.facts.source, b.scene.facts.geometry),
                )
            })
            .or_else(|| {
                identity(
                    "paths",
                    (&a.path.source, a.path.cameras),
                    (&b.path.source, b.path.cameras),
                )
            })
    }

    fn adapter(&self) -> (String, String) {
        (self.summary.adapter.name.clone(), self.summary.adapter.backend.clone())
    }
}

/// Whether two scenes or paths (a source's name and its fingerprint) are
/// one: by fingerprint when both have one, else by name.
fn same_thing((source_a, fa): (&String, Option<Fingerprint>), (source_b, fb): (&String, Option<Fingerprint>)) -> bool {
    match (fa, fb) {
        (Some(fa), Some(fb)) => fa == fb,
        _ => source_a == source_b,
    }
}

/// Reads every run folder in `dirs` (each one, or the folders in it that
/// hold a run), checks that the folders of each run agree, and writes the
/// merged report into `out` (claimed while it is written, each file whole).
///
/// A matrix's runs must all be there: the runs a matrix lists and no folder
/// holds (a shard not merged, a run that failed) are refused by place
/// unless `allow_partial`, which merges the rest and names them in the
/// report and merged.json.
pub fn merge(dirs: &[PathBuf], out: &Path, allow_partial: bool) -> Result<Merged, MergeError> {
    if dirs.is_empty() {
        return Err(MergeError::NoFolders);
    }
    // A folder given twice (or as itself and inside its matrix folder) is
    // read once.
    let mut seen = BTreeSet::new();
    let mut folders = Vec::new();
    for dir in dirs {
        refuse_overlap(dir, out)?;
        for run_dir in run_folders(dir)? {
            let canonical = std::fs::canonicalize(&run_dir).map_err(ReportError::at(&run_dir))?;
            if !seen.insert(canonical) {
                continue;
            }
            let (summary, _) = read_results(&run_dir)?;
            let files = result_files(&run_dir)?;
            folders.push(RunFolder {
                dir: run_dir,
                summary,
                files,
            });
        }
    }
    // A run's report.md and the merged one would share a name (a merged
    // folder, which holds neither of these, may be merged into again).
    if ["summary.json", "frames.csv"].iter().any(|f| out.join(f).exists()) {
        return Err(MergeError::OutHoldsRun(out.to_path_buf()));
    }
    let groups = named(group(folders)?);
    let missing = missing_runs(&groups);
    if let Some(partial) = missing.first().filter(|_| !allow_partial) {
        return Err(MergeError::Partial(partial.clone()));
    }
    let _claim = prepare_output(out)?;
    let mut used = BTreeSet::new();
    let mut merged = Merged {
        schema_version: MERGED_SCHEMA_VERSION,
        tool: ToolInfo::current(),
        runs: groups
            .iter()
            .map(|(name, folders)| merged_run(name, folders, &mut used))
            .collect(),
        missing,
    };
    publish(out, &[], |staging| {
        for dir in ["runs", "charts"] {
            let path = staging.join(dir);
            std::fs::create_dir(&path).map_err(ReportError::at(&path))?;
        }
        for ((_, group), run) in groups.iter().zip(&mut merged.runs) {
            for (folder, column) in group.iter().zip(&run.adapters) {
                copy_run(folder, &staging.join(&column.folder))?;
            }
            draw_chart(staging, run, &mut used)?;
        }
        let write = |name: &str, text: String| {
            let path = staging.join(name);
            std::fs::write(&path, text).map_err(ReportError::at(&path))
        };
        write("report.md", render(&merged))?;
        let json = serde_json::to_string_pretty(&merged).map_err(|e| ReportError::at(staging)(e.into()))?;
        write("merged.json", json + "\n")?;
        // merged.json last: a reader never finds it beside older files.
        Ok(["runs", "charts", "report.md", "merged.json"]
            .map(String::from)
            .to_vec())
    })?;
    Ok(merged)
}

/// Refuses an `out` that is `input`, lies inside it or holds it: the merge
/// would write over (or into) what it reads. `out` need not exist yet, so
/// its nearest existing ancestor is resolved and the rest appended.
fn refuse_overlap(input: &Path, out: &Path) -> Result<(), MergeError> {
    let input_path = std::fs::canonicalize(input).map_err(ReportError::at(input))?;
    let mut existing = out;
    let mut rest = Vec::new();
    let out_path = loop {
        match std::fs::canonicalize(if existing.as_os_str().is_empty() {
            Path::new(".")
        } else {
            existing
        }) {
            Ok(path) => break rest.iter().rev().fold(path, |path: PathBuf, part| path.join(part)),
            Err(_) => match (existing.parent(), existing.file_name()) {
                (Some(parent), Some(name)) => {
                    rest.push(name.to_owned());
                    existing = parent;
                }
                // Nothing of it exists (or `..` past the root): it cannot
                // be an input.
                _ => return Ok(()),
            },
        }
    };
    if out_path.starts_with(&input_path) || input_path.starts_with(&out_path) {
        return Err(MergeError::OutOverlapsInput {
            out: out.to_path_buf(),
            input: input.to_path_buf(),
        });
    }
    Ok(())
}

/// `dir` itself when it holds a run, else the folders in it (in name
/// order), each of which must hold a run: a folder without one is a run
/// that failed or is still running, and a matrix without it is not whole.
/// Hidden folders (`.occlu-staging-…`) are not runs and are passed over.
fn run_folders(dir: &Path) -> Result<Vec<PathBuf>, MergeError> {
    if dir.join("summary.json").exists() {
        return Ok(vec![dir.to_path_buf()]);
    }
    if dir.join("merged.json").exists() {
        return Err(MergeError::MergedFolder(dir.to_path_buf()));
    }
    let entries = std::fs::read_dir(dir).map_err(ReportError::at(dir))?;
    let mut runs = Vec::new();
    for entry in entries {
        let entry = entry.map_err(ReportError::at(dir))?;
        let path = entry.path();
        if entry.file_name().as_encoded_bytes().starts_with(b".") || !path.is_dir() {
            continue;
        }
        if !path.join("summary.json").exists() {
            return Err(MergeError::NotARun {
                matrix: dir.to_path_buf(),
                folder: path,
            });
        }
        runs.push(path);
    }
    if runs.is_empty() {
        return Err(MergeError::NoRuns(dir.to_path_buf()));
    }
    runs.sort();
    Ok(runs)
}

/// The folders of each run, runs in name order (a matrix's order), each
/// run's folders in adapter order; refuses folders of one run that differ
/// in what they measured, and two different results of one run on one
/// adapter (copies of one result count once).
fn group(mut folders: Vec<RunFolder>) -> Result<Vec<Vec<RunFolder>>, MergeError> {
    folders.sort_by_key(|f| (f.run(), f.adapter()));
    let mut groups: Vec<Vec<RunFolder>> = Vec::new();
    for folder in folders {
        let Some(group) = groups.iter_mut().find(|g| g[0].same_run(&folder)) else {
            groups.push(vec![folder]);
            continue;
        };
        let first = &group[0];
        if let Some((what, first_value, second_value)) = first.differs_from(&folder) {
            return Err(MergeError::NotOneRun {
                run: folder.run(),
                folders: Box::new([first.dir.clone(), folder.dir]),
                what,
                values: Box::new([first_value, second_value]),
            });
        }
        if let Some(same_adapter) = group.iter().find(|f| f.adapter() == folder.adapter()) {
            let summary = &same_adapter.summary;
            let copies = summary.frames_csv.is_some() && summary.frames_csv == folder.summary.frames_csv;
            if copies {
                continue;
            }
            return Err(MergeError::Ambiguous {
                run: folder.run(),
                adapter: adapter_label(&folder.summary.adapter.name, &folder.summary.adapter.backend),
                first: same_adapter.dir.clone(),
                second: folder.dir,
            });
        }
        group.push(folder);
    }
    for group in &mut groups {
        group.sort_by_key(RunFolder::adapter);
    }
    Ok(groups)
}

/// Each run's folders under a name of its own, runs in name order. A run
/// is named by its matrix run's name, unique in its matrix (two matrices
/// are never merged), or by its scene's and path's; two runs outside a
/// matrix that measured other scenes or paths of one name (a changed file,
/// a generated path of other frames) get their fingerprints' hash after
/// it, so the name is the same whatever order the folders came in.
fn named(groups: Vec<Vec<RunFolder>>) -> Vec<(String, Vec<RunFolder>)> {
    let plain: Vec<String> = groups.iter().map(|g| g[0].run()).collect();
    let mut named: Vec<(String, Vec<RunFolder>)> = groups
        .into_iter()
        .zip(&plain)
        .map(|(folders, name)| {
            if plain.iter().filter(|&n| n == name).count() == 1 {
                return (name.clone(), folders);
            }
            let s = &folders[0].summary;
            let identity = format!("{:?}\n{:?}", s.scene.facts.geometry, s.path.cameras);
            let hash = Fingerprint::of(identity.as_bytes()).fnv1a >> 32;
            (format!("{name} #{hash:08x}"), folders)
        })
        .collect();
    named.sort_by(|a, b| a.0.cmp(&b.0));
    named
}

/// The runs of each matrix among `runs` that none of them is: by place
/// (`02`), as the matrix's run folders are named.
fn missing_runs(runs: &[(String, Vec<RunFolder>)]) -> Vec<MissingRuns> {
    let mut matrices: Vec<(MatrixIdentity, BTreeSet<usize>)> = Vec::new();
    for (_, folders) in runs {
        let s = &folders[0].summary;
        let (Some(matrix), Some(name)) = (s.matrix, &s.run) else {
            continue;
        };
        let place = name.split('-').next().and_then(|digits| digits.parse::<usize>().ok());
        let at = match matrices.iter().position(|(m, _)| *m == matrix) {
            Some(at) => at,
            None => {
                matrices.push((matrix, BTreeSet::new()));
                matrices.len() - 1
            }
        };
        matrices[at].1.extend(place);
    }
    matrices
        .into_iter()
        .filter_map(|(matrix, present)| {
            let width = matrix.runs.to_string().len().max(2);
            let absent: Vec<String> = (1..=matrix.runs)
                .filter(|p| !present.contains(p))
                .map(|p| format!("{p:0width$}"))
                .collect();
            (!absent.is_empty()).then_some(MissingRuns {
                matrix,
                present: matrix.runs - absent.len(),
                runs: absent,
            })
        })
        .collect()
}

/// `stem` + `extension`, or with `-2`, `-3`, … after the stem when `used`
/// has it; marked used. (Names are unique by construction, a hash of what
/// they name included; this keeps a collision from overwriting a file.)
fn unique(stem: String, extension: &str, used: &mut BTreeSet<String>) -> String {
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
fn column_folder(run: &str, adapter: &str, backend: &str) -> String {
    let identity = Fingerprint::of(format!("{run}\n{adapter}\n{backend}").as_bytes());
    format!(
        "runs/{}--{}-{:08x}",
        slug(run),
        slug(&format!("{adapter} {backend}")),
        identity.fnv1a >> 32
    )
}

/// One run's table, columns and cross-check (its chart comes later).
fn merged_run(name: &str, folders: &[RunFolder], used: &mut BTreeSet<String>) -> MergedRun {
    let first = &folders[0].summary;
    let adapters: Vec<AdapterColumn> = folders
        .iter()
        .map(|f| {
            let a = &f.summary.adapter;
            let folder = unique(column_folder(name, &a.name, &a.backend), "", used);
            AdapterColumn {
                name: a.name.clone(),
                backend: a.backend.clone(),
                device_type: a.device_type.clone(),
                folder,
                merged_from: f.dir.to_string_lossy().into_owned(),
                skipped: f.summary.skipped.clone(),
                error_measured: f.summary.error_measured,
            }
        })
        .collect();
    let mut names: Vec<&str> = Vec::new();
    for m in folders.iter().flat_map(|f| &f.summary.modes) {
        if !names.contains(&m.name.as_str()) {
            names.push(&m.name);
        }
    }
    let modes: Vec<ModeRow> = names
        .iter()
        .map(|&mode| ModeRow {
            mode: mode.to_string(),
            results: folders
                .iter()
                .map(|f| f.summary.modes.iter().find(|m| m.name == mode).map(ModeResult::of))
                .collect(),
        })
        .collect();
    let disagreements = cross_check(&adapters, &modes);
    MergedRun {
        name: name.to_string(),
        scene: first.scene.facts.source.clone(),
        path: first.path.source.clone(),
        resolution: first.resolution,
        frames: first.frames,
        adapters,
        modes,
        disagreements,
        chart: None,
    }
}

/// Relative tolerance for "equal" means of deterministic counters (sums of
/// integers over the same frame count).
const SAME: f64 = 1e-9;

/// The counters of [`SAME_ON_EVERY_ADAPTER`] that differ between adapters
/// of one backend.
fn cross_check(adapters: &[AdapterColumn], modes: &[ModeRow]) -> Vec<Disagreement> {
    let backends: BTreeSet<&str> = adapters.iter().map(|a| a.backend.as_str()).collect();
    let mut found = Vec::new();
    for row in modes {
        for &backend in &backends {
            for (counter, value) in SAME_ON_EVERY_ADAPTER {
                let values: Vec<(String, f64)> = adapters
                    .iter()
                    .zip(&row.results)
                    .filter(|(a, _)| a.backend == backend)
                    .filter_map(|(a, r)| Some((a.name.clone(), value(r.as_ref()?)?)))
                    .collect();
                let differ = values
                    .iter()
                    .any(|(_, v)| (v - values[0].1).abs() > SAME * values[0].1.abs().max(1.0));
                if differ {
                    found.push(Disagreement {
                        mode: row.mode.clone(),
                        counter: counter.into(),
                        backend: backend.into(),
                        values,
                    });
                }
            }
        }
    }
    found
}

/// The result files a run folder holds (not its lock or anything else),
/// each a regular file: a link, device or pipe of one of their names is
/// refused by name, since copying it would put another file into the
/// merged artefact (or read forever).
fn result_files(dir: &Path) -> Result<Vec<&'static str>, ReportError> {
    let names = RESULT_FILES.into_iter().chain(CHARTS);
    let mut present = Vec::new();
    for name in names {
        let path = dir.join(name);
        match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Ok(m) if m.is_file() => present.push(name),
            Ok(_) => {
                let error = std::io::Error::other(
                    "not a regular file (a link, a device or a pipe): merge copies a run's own files only",
                );
                return Err(ReportError::at(&path)(error));
            }
            Err(e) => return Err(ReportError::at(&path)(e)),
        }
    }
    Ok(present)
}

/// Copies a run folder's result files.
fn copy_run(run: &RunFolder, to: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(to).map_err(ReportError::at(to))?;
    for name in &run.files {
        let (source, target) = (run.dir.join(name), to.join(name));
        // Read, then written: an error names the file at fault.
        let bytes =
            crate::input::read_unlinked(&source, crate::input::MODEL_LIMIT).map_err(ReportError::at(&source))?;
        std::fs::write(&target, bytes).map_err(ReportError::at(&target))?;
    }
    Ok(())
}

/// Draws `run`'s ratio-to-oracle chart into `staging`'s charts folder and
/// records its name, when any adapter ran the oracle.
fn draw_chart(staging: &Path, run: &mut MergedRun, used: &mut BTreeSet<String>) -> Result<(), ReportError> {
    let bars: Vec<RatioBars> = run
        .modes
        .iter()
        .filter(|row| row.mode != "oracle")
        .map(|row| RatioBars {
            mode: row.mode.clone(),
            ratios: row
                .results
                .iter()
                .map(|r| r.as_ref().and_then(|r| r.ratio_to_oracle))
                .collect(),
        })
        .collect();
    if !bars.iter().any(|b| b.ratios.iter().any(Option::is_some)) {
        return Ok(());
    }
    let hash = Fingerprint::of(run.name.as_bytes()).fnv1a >> 32;
    let name = unique(format!("charts/{}-{hash:08x}", slug(&run.name)), ".png", used);
    let labels: Vec<String> = run.adapters.iter().map(AdapterColumn::label).collect();
    let caption = format!("Mean frame time over the oracle's — {} at {}", run.name, run.resolution);
    ratio_to_oracle_bars(&staging.join(&name), &caption, &labels, &bars)?;
    run.chart = Some(name);
    Ok(())
}

/// Shows one metric of a [`ModeResult`] in a table cell.
type Cell = fn(&ModeResult) -> String;

/// The merged report.md.
pub fn render(merged: &Merged) -> String {
    let mut out = String::new();
    let w = &mut out;
    let adapters: BTreeSet<String> = merged
        .runs
        .iter()
        .flat_map(|r| r.adapters.iter().map(AdapterColumn::label))
        .collect();
    let _ = writeln!(w, "# occlu: merged results\n");
    let _ = writeln!(
        w,
        "{} on {}. Adapters are side by side, never averaged; frame times compare only on one adapter, counters everywhere.\n",
        crate::text::count(merged.runs.len(), "run"),
        crate::text::count(adapters.len(), "adapter")
    );
    for partial in &merged.missing {
        let _ = writeln!(w, "**A partial matrix**: {}.\n", markdown(&partial.describe()));
    }
    for run in &merged.runs {
        let _ = writeln!(w, "## {}\n", markdown(&run.name));
        let _ = writeln!(
            w,
            "Scene {}, path {}, {}, {} frames.\n",
            markdown(&run.scene),
            markdown(&run.path),
            run.resolution,
            run.frames
        );
        let _ = write!(w, "| mode | metric |");
        for a in &run.adapters {
            let _ = write!(w, " {} |", markdown(&a.label()));
        }
        let _ = write!(w, "\n|---|---|");
        for _ in &run.adapters {
            let _ = write!(w, "---:|");
        }
        let _ = writeln!(w);
        let metrics: [(&str, Cell); 7] = [
            ("frame ms (mean)", |r| number(r.frame_ms, 3)),
            ("× oracle", |r| {
                r.ratio_to_oracle.map_or("–".into(), |v| format!("{v:.2}×"))
            }),
            ("wrong pixels", |r| number(r.error_pixels.map(|v| v as f64), 0)),
            ("objects", |r| number(r.objects_drawn, 1)),
            ("triangles", |r| number(r.triangles_drawn, 1)),
            ("queries", |r| number(r.queries, 1)),
            ("round trips", |r| number(r.round_trips, 1)),
        ];
        for row in &run.modes {
            for (k, (metric, show)) in metrics.iter().enumerate() {
                let mode = if k == 0 { markdown(&row.mode) } else { String::new() };
                let _ = write!(w, "| {mode} | {metric} |");
                for (a, result) in run.adapters.iter().zip(&row.results) {
                    let cell = match result {
                        Some(r) => show(r),
                        None if a.skipped.iter().any(|s| s.mode == row.mode) => "skipped".into(),
                        None => "not run".into(),
                    };
                    let _ = write!(w, " {cell} |");
                }
                let _ = writeln!(w);
            }
        }
        let _ = writeln!(w);
        let unmeasured: Vec<String> = run
            .adapters
            .iter()
            .filter(|a| !a.error_measured)
            .map(|a| markdown(&a.label()))
            .collect();
        if !unmeasured.is_empty() {
            let _ = writeln!(
                w,
                "Wrong pixels not measured on {} (run with --no-error).\n",
                unmeasured.join(", ")
            );
        }
        match &run.chart {
            Some(chart) => {
                let _ = writeln!(w, "![ratio to the oracle per adapter]({chart})\n");
            }
            None => {
                let _ = writeln!(
                    w,
                    "No adapter ran the oracle, so there is no ratio to it (add `oracle` to the modes).\n"
                );
            }
        }
        for d in &run.disagreements {
            let _ = writeln!(
                w,
                "- **{}**: a counter that does not depend on the adapter, so one backend's path has a bug.",
                markdown(&d.describe())
            );
        }
        if !run.disagreements.is_empty() {
            let _ = writeln!(w);
        }
        let sources: Vec<String> = run
            .adapters
            .iter()
            .map(|a| format!("{} from {}", a.folder, markdown(&a.merged_from)))
            .collect();
        let _ = writeln!(w, "Run folders: {}.\n", sources.join("; "));
    }
    out
}

/// `v` with up to `decimals` decimals (none for whole numbers), `–` when
/// not measured.
fn number(v: Option<f64>, decimals: usize) -> String {
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
