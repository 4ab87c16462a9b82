//! `occlu compare BASE NEW`: what changed between two runs, and whether it
//! is a regression a CI job should fail on. Two merged folders (`occlu
//! merge`) compare run folder by run folder (each run on each adapter),
//! every change named `RUN--ADAPTER/MODE`; a run folder of the base that
//! the new merge lacks is missing.
//!
//! Deterministic counters (triangles drawn, box tests, round trips, wrong
//! pixels, missed objects) do not depend on machine noise: any increase is a
//! regression. Frame time does: it regresses only when its mean grows beyond
//! `--max-regression` percent *and* beyond the measured noise: the 95 %
//! interval of the ratio of the new mean to the base's, from the two runs'
//! frames paired by their place on the path ([`PairedRatio`]), lies above
//! one. What a view costs, which varies along a path far more than a run's
//! noise, cancels in a pair (the spread of either run's own frames measures
//! the path: a mode three times slower on every frame stayed within it).
//! Statistics are those [`read_results`] recomputes from each run's
//! checked frames.csv, as `occlu merge` and `occlu plot` take them.
//!
//! A comparison cannot pass by leaving things out: a mode or a measured
//! metric of the base missing from the new run fails it (unless
//! `allow_missing`), and runs on different adapters are refused (unless
//! `cross_adapter`: their counters compare, their times do not).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::merge::{Merged, one_run, read_merged};
use super::summary::{Fingerprint, paired_frame_ms, same_count};
use super::{ReportError, Summary, read_results, read_summary};
use crate::cull::{CountKind, ModeId};
use crate::measure::{Distribution, LEAST_PAIRS, ModeSummary, PairedRatio};

/// A metric compare can gate on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Metric {
    FrameMs,
    TrianglesDrawn,
    Queries,
    QueryBatches,
    ErrorPixels,
    MissedObjects,
}

impl Metric {
    pub const ALL: [Metric; 6] = [
        Metric::FrameMs,
        Metric::TrianglesDrawn,
        Metric::Queries,
        Metric::QueryBatches,
        Metric::ErrorPixels,
        Metric::MissedObjects,
    ];

    fn name(self) -> &'static str {
        match self {
            Metric::FrameMs => "frame_ms",
            Metric::TrianglesDrawn => "triangles_drawn",
            Metric::Queries => "queries",
            Metric::QueryBatches => "query_batches",
            Metric::ErrorPixels => "error_pixels",
            Metric::MissedObjects => "missed_objects",
        }
    }

    /// Whether this count of the mode labelled `label` follows the times
    /// the mode measured ([`ModeId::counts_follow_time`]): it varies from
    /// run to run as they do.
    fn follows_time(self, label: &str) -> bool {
        self.count_kind()
            .is_some_and(|kind| ModeId::counts_follow_time(label, kind))
    }

    /// What a count measures; `None` for the frame time.
    fn count_kind(self) -> Option<CountKind> {
        match self {
            Metric::FrameMs => None,
            Metric::TrianglesDrawn | Metric::Queries | Metric::QueryBatches => Some(CountKind::Work),
            Metric::ErrorPixels | Metric::MissedObjects => Some(CountKind::Error),
        }
    }

    /// What is compared: the mean per frame, or the total over the run for
    /// the error counters (a single wrong pixel matters).
    fn value(self, m: &ModeSummary) -> Option<f64> {
        let mean = |col: &str| m.stats.get(col).map(|d| d.mean);
        match self {
            Metric::FrameMs => mean("frame_ms"),
            Metric::TrianglesDrawn => mean("triangles_drawn"),
            Metric::Queries => mean("queries"),
            Metric::QueryBatches => mean("query_batches"),
            Metric::ErrorPixels => m.error_pixels_total.map(|v| v as f64),
            Metric::MissedObjects => m.missed_objects_total.map(|v| v as f64),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Same,
    Better,
    /// Worse, but within the threshold or the measured spread.
    Noise,
    Regression,
    /// The base measured it and the new run did not (a mode left out, or
    /// `--no-error`): fails the comparison unless missing is allowed.
    Missing,
    /// The metric was not measured in one of the runs, and that is allowed.
    Unmeasured,
    /// Measured in both, but not comparable: frame times on two adapters.
    NotJudged,
}

impl Verdict {
    /// Whether it fails the comparison.
    pub fn fails(&self) -> bool {
        matches!(self, Verdict::Regression | Verdict::Missing)
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Change {
    pub mode: String,
    pub metric: &'static str,
    pub base: Option<f64>,
    pub new: Option<f64>,
    pub verdict: Verdict,
}

#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub changes: Vec<Change>,
    /// Modes in only one of the runs, small samples, and other differences
    /// worth a look.
    pub notes: Vec<String>,
}

impl Comparison {
    /// The changes that fail the comparison.
    pub fn regressions(&self) -> impl Iterator<Item = &Change> {
        self.changes.iter().filter(|c| c.verdict.fails())
    }
}

/// How strict a comparison is.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Allowed growth of mean frame time, percent.
    pub max_regression_pct: f64,
    pub metrics: Vec<Metric>,
    /// A mode or metric of the base missing from the new run is a note, not
    /// a failure.
    pub allow_missing: bool,
    /// Runs on different adapters or backends are compared (counters only
    /// mean something then).
    pub cross_adapter: bool,
}

/// Frames below which the frame-time noise test (the paired ratio's
/// interval) says little; comparisons of fewer carry a note.
pub const FEW_FRAMES: u32 = 30;

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Read(#[from] ReportError),
    #[error("the runs measured different workloads (their {0}): their counters are not comparable")]
    Different(String),
    #[error("--max-regression must be a percentage of 0 or more, got {0}")]
    Threshold(f64),
    #[error(
        "the runs used different adapters ({base} vs {new}); --cross-adapter compares them anyway (counters compare, times do not)"
    )]
    Adapters { base: String, new: String },
    #[error(
        "the runs used different adapters ({base} vs {new}), where only {judged} compare, and --metric names none of them: nothing would be judged"
    )]
    NothingToJudge {
        base: String,
        new: String,
        judged: &'static str,
    },
    #[error("{} is a merged folder and {} is not: compare two runs, or two merged folders", merged.display(), single.display())]
    MergedWithSingle { merged: PathBuf, single: PathBuf },
    #[error(
        "{}: run folder '{folder}' is not a folder in its runs/: not a merged.json occlu wrote, or edited since",
        merged.display()
    )]
    NotARunFolder { merged: PathBuf, folder: String },
    #[error(
        "{}: lists run {run} on {adapter} twice: not a merged.json occlu wrote, or edited since",
        merged.display()
    )]
    ListedTwice {
        merged: PathBuf,
        run: String,
        adapter: String,
    },
    #[error("{} against {}: {error}", base.display(), new.display())]
    InRun {
        base: PathBuf,
        new: PathBuf,
        error: Box<CompareError>,
    },
}

pub fn compare(base: &Path, new: &Path, options: &CompareOptions) -> Result<Comparison, CompareError> {
    let max_regression_pct = options.max_regression_pct;
    if !(max_regression_pct >= 0.0 && max_regression_pct.is_finite()) {
        return Err(CompareError::Threshold(max_regression_pct));
    }
    match (read_merged(base)?, read_merged(new)?) {
        (Some(b), Some(n)) => compare_merged((base, &b), (new, &n), options),
        (None, None) => compare_runs(base, new, options),
        (b, _) => {
            let (merged, single) = if b.is_some() { (base, new) } else { (new, base) };
            Err(CompareError::MergedWithSingle {
                merged: merged.into(),
                single: single.into(),
            })
        }
    }
}

/// Two run folders (not merged ones).
fn compare_runs(base: &Path, new: &Path, options: &CompareOptions) -> Result<Comparison, CompareError> {
    let max_regression_pct = options.max_regression_pct;
    let (base_summary, base_rows) = read_results(base)?;
    let (new_summary, new_rows) = read_results(new)?;
    if let Some((what, x, y)) = different_workloads(&base_summary, &new_summary) {
        return Err(CompareError::Different(format!("{what}: {x} vs {y}")));
    }
    let mut notes = Vec::new();
    // The same names, other contents: a changed model or path file, or a
    // change in how occlu loads or generates them. Counters then change
    // for that reason too, which the user may want to compare all the
    // same, so it is said rather than refused.
    let fingerprints = [
        (
            "scene's geometry",
            base_summary.scene.facts.geometry,
            new_summary.scene.facts.geometry,
        ),
        ("path's cameras", base_summary.path.cameras, new_summary.path.cameras),
    ];
    for (what, base, new) in fingerprints {
        if let (Some(base), Some(new)) = (base, new)
            && base != new
        {
            notes.push(format!(
                "the {what} differ (#{:016x} vs #{:016x}): a changed file, or a change in how occlu reads it; counters may differ for that reason",
                base.fnv1a, new.fnv1a
            ));
        }
    }
    let (adapter_a, adapter_b) = (&base_summary.adapter, &new_summary.adapter);
    let same_adapter = adapter_a.times_compare_with(adapter_b);
    // On adapters that work differently, what a mode does differs too:
    // only what it got wrong compares (or, where only the GPU walks'
    // read-backs differ, all but their round trips).
    let work_apart = adapter_a.work_differs_from(adapter_b);
    let trips_apart = adapter_a.round_trips_differ_from(adapter_b);
    let compares = |metric: Metric, label: &str| match metric.count_kind() {
        None => same_adapter,
        Some(CountKind::Work) => {
            work_apart.is_none() && !(trips_apart && metric == Metric::QueryBatches && ModeId::walks_on_gpu(label))
        }
        Some(CountKind::Error) => true,
    };
    if !same_adapter {
        let (base, new) = (adapter_a.to_string(), adapter_b.to_string());
        if !options.cross_adapter {
            return Err(CompareError::Adapters { base, new });
        }
        let (judged, shown) = match (work_apart, trips_apart) {
            (Some(what), _) => (
                "error counters",
                format!(
                    "frame times and the counts of work are shown but not judged (the adapters' {what} differ, which changes what the modes do); error counters are judged"
                ),
            ),
            (None, true) => (
                "counters other than the GPU walks' round trips",
                "frame times and the GPU walks' round trips are shown but not judged (one adapter has no indirect counts: they read their lists' lengths back, a round trip a frame); the other counters are judged".to_string(),
            ),
            (None, false) => ("counters", "frame times are shown but not judged; counters are".to_string()),
        };
        let judged_somewhere = |m: Metric| base_summary.modes.iter().any(|b| compares(m, &b.name));
        if !options.metrics.iter().any(|&m| judged_somewhere(m)) {
            return Err(CompareError::NothingToJudge { base, new, judged });
        }
        notes.push(format!("different adapters ({adapter_a} vs {adapter_b}): {shown}"));
    }
    let frames = base_summary.frames.min(new_summary.frames);
    if frames < FEW_FRAMES {
        let spread = match frames as usize >= LEAST_PAIRS {
            true => "the 95 % interval of their ratio, from frames paired by their place on the path, reaches 1",
            false => "the new median − MAD does not clear the base median + MAD (too few frames to pair)",
        };
        notes.push(format!(
            "{frames} frames: frame_ms is 'within noise' when the new mean is at most {max_regression_pct}% above the base's or {spread}; on fewer than {FEW_FRAMES} frames that says little"
        ));
    }
    let (base_modes, new_modes) = (&base_summary.modes, &new_summary.modes);
    let missing = if options.allow_missing {
        Verdict::Unmeasured
    } else {
        Verdict::Missing
    };
    let mut changes = Vec::new();
    for b in base_modes {
        let n = new_modes.iter().find(|n| n.name == b.name);
        if n.is_none() {
            notes.push(format!("mode {} is in the base run only", b.name));
        }
        for &metric in &options.metrics {
            let (base_value, new_value) = (metric.value(b), n.and_then(|n| metric.value(n)));
            let verdict = match (base_value, new_value, n) {
                // Times on two adapters measure the adapters, not a change,
                // and so do the counts that follow them.
                (Some(_), Some(_), Some(_))
                    if !same_adapter && (!compares(metric, &b.name) || metric.follows_time(&b.name)) =>
                {
                    Verdict::NotJudged
                }
                (Some(x), Some(y), Some(n)) => {
                    let paired = (metric == Metric::FrameMs)
                        .then(|| PairedRatio::of(&paired_frame_ms((&new_rows, &n.name), (&base_rows, &b.name))))
                        .flatten();
                    verdict(metric, (x, y), (b, n), paired, max_regression_pct)
                }
                (Some(_), None, _) => missing.clone(),
                _ => Verdict::Unmeasured,
            };
            changes.push(Change {
                mode: b.name.clone(),
                metric: metric.name(),
                base: base_value,
                new: new_value,
                verdict,
            });
        }
    }
    for n in new_modes
        .iter()
        .filter(|n| !base_modes.iter().any(|b| b.name == n.name))
    {
        notes.push(format!("mode {} is in the new run only", n.name));
    }
    Ok(Comparison { changes, notes })
}

/// Two merged folders, run folder by run folder: every change and note of
/// each pair, named by the base's folder. Folders pair by what they hold
/// (run name, adapter and backend as merged.json records them, or else
/// the same run as merge tells it on that adapter: [`renamed`]), never by
/// their folder names; a run of the base that the new merge lacks is
/// missing (a failure unless `allow_missing`).
fn compare_merged(
    (base_dir, base): (&Path, &Merged),
    (new_dir, new): (&Path, &Merged),
    options: &CompareOptions,
) -> Result<Comparison, CompareError> {
    let (base_columns, new_columns) = (columns(base_dir, base)?, columns(new_dir, new)?);
    let mut changes = Vec::new();
    let mut notes = Vec::new();
    let mut paired = Vec::new();
    // A new run folder named as a base one pairs with it alone.
    let named_alike = |i: &Identity| base_columns.iter().any(|(b, _)| b == i);
    let unnamed: Vec<(Identity, PathBuf)> = new_columns.iter().filter(|(i, _)| !named_alike(i)).cloned().collect();
    for (identity, base_folder) in &base_columns {
        let name = label(base_folder);
        let found = match new_columns.iter().find(|(i, _)| i == identity) {
            Some(found) => Some(found),
            None => renamed(identity, base_folder, &unnamed).filter(|(i, _)| !paired.contains(&i)),
        };
        let Some((new_identity, new_folder)) = found else {
            notes.push(format!("run {name} is in the base only"));
            changes.push(Change {
                mode: name,
                metric: "run",
                base: None,
                new: None,
                verdict: if options.allow_missing {
                    Verdict::Unmeasured
                } else {
                    Verdict::Missing
                },
            });
            continue;
        };
        paired.push(new_identity);
        let pair = compare_runs(base_folder, new_folder, options).map_err(|error| CompareError::InRun {
            base: base_folder.clone(),
            new: new_folder.clone(),
            error: Box::new(error),
        })?;
        changes.extend(pair.changes.into_iter().map(|c| Change {
            mode: format!("{name}/{}", c.mode),
            ..c
        }));
        notes.extend(pair.notes.into_iter().map(|n| format!("{name}: {n}")));
    }
    for (_, folder) in new_columns.iter().filter(|(i, _)| !paired.contains(&i)) {
        notes.push(format!("run {} is in the new merge only", label(folder)));
    }
    Ok(Comparison { changes, notes })
}

/// The new merge's run folder of the base's run `identity` (in
/// `base_folder`) under another name, on its adapter and backend: the one
/// merge would take for the same run ([`one_run`]). Merge names a run
/// outside a matrix by its scene's and path's sources as they were given
/// (`city, path.json` in one merge, `city, /ci/checkout/path.json` in
/// another), and tags the name (`#` and a hash of their contents) where
/// another run it merged shares it.
fn renamed<'a>(
    (_, adapter, backend): &Identity,
    base_folder: &Path,
    new_columns: &'a [(Identity, PathBuf)],
) -> Option<&'a (Identity, PathBuf)> {
    // A summary that cannot be read matches nothing here: the run is then
    // missing, or named in a note, as without this search.
    let base = read_summary(base_folder).ok()?;
    new_columns
        .iter()
        .filter(|((_, a, b), _)| a == adapter && b == backend)
        .find(|(_, folder)| read_summary(folder).is_ok_and(|new| one_run(&base, &new)))
}

/// What a merged folder's run folder holds: the run's name (unique in a
/// merge), the adapter's name and backend.
type Identity = (String, String, String);

/// Every run folder of a merged folder with what it holds; its folder must
/// be a folder directly in `dir`'s runs/, and no run on one adapter may be
/// listed twice (merged.json is read, not trusted).
fn columns(dir: &Path, merged: &Merged) -> Result<Vec<(Identity, PathBuf)>, CompareError> {
    let runs = dir.join("runs");
    let mut found: Vec<(Identity, PathBuf)> = Vec::new();
    for run in &merged.runs {
        for a in &run.adapters {
            let bad = || CompareError::NotARunFolder {
                merged: dir.join("merged.json"),
                folder: a.folder.clone(),
            };
            let name = a.folder.strip_prefix("runs/").ok_or_else(bad)?;
            let mut parts = Path::new(name).components();
            let plain = matches!(
                (parts.next(), parts.next()),
                (Some(std::path::Component::Normal(_)), None)
            );
            let folder = runs.join(name);
            let is_folder = std::fs::symlink_metadata(&folder).is_ok_and(|m| m.is_dir());
            if !plain || name.starts_with('.') || !is_folder {
                return Err(bad());
            }
            let identity = (run.name.clone(), a.name.clone(), a.backend.clone());
            if found.iter().any(|(i, _)| *i == identity) {
                return Err(CompareError::ListedTwice {
                    merged: dir.join("merged.json"),
                    run: run.name.clone(),
                    adapter: a.label(),
                });
            }
            found.push((identity, folder));
        }
    }
    Ok(found)
}

/// The first thing two runs measured differently that makes their
/// counters incomparable, if any: what it is and each run's value. What
/// the user set comes first ([`Summary::settings_differing_from`]): a
/// path's fingerprint holds its frame count, so the message names the real
/// difference. The scene and the path are one where their names or their
/// contents' fingerprints agree (`path.json` and `/ci/checkout/path.json`);
/// one name with other contents is compared, with a note ([`compare_runs`]).
fn different_workloads(a: &Summary, b: &Summary) -> Option<(&'static str, String, String)> {
    let same_source = |(name_a, fa): (&String, Option<Fingerprint>), (name_b, fb): (&String, Option<Fingerprint>)| {
        name_a == name_b || fa.is_some() && fa == fb
    };
    let (scene_a, scene_b) = (&a.scene.facts, &b.scene.facts);
    let (path_a, path_b) = (&a.path, &b.path);
    a.settings_differing_from(b)
        .or_else(|| {
            (!same_source((&scene_a.source, scene_a.geometry), (&scene_b.source, scene_b.geometry)))
                .then(|| ("scenes", scene_a.source.clone(), scene_b.source.clone()))
        })
        .or_else(|| {
            (!same_source((&path_a.source, path_a.cameras), (&path_b.source, path_b.cameras)))
                .then(|| ("paths", path_a.source.clone(), path_b.source.clone()))
        })
}

/// A run folder's name as changes and notes show it.
fn label(folder: &Path) -> String {
    folder
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

/// The verdict on `metric` of mode `b` in the base and `n` in the new run,
/// `base` and `new` its values; `paired`, for frame time, the new run's
/// mean over the base's from their frames paired along the path.
fn verdict(
    metric: Metric,
    (base, new): (f64, f64),
    (b, n): (&ModeSummary, &ModeSummary),
    paired: Option<PairedRatio>,
    pct: f64,
) -> Verdict {
    if same_count(base, new) {
        return Verdict::Same;
    }
    if new < base {
        return Verdict::Better;
    }
    // Frame times vary with the machine, and so does the work of a mode
    // whose work follows them; any other count, and every error count,
    // is the same in every run of one code.
    if metric != Metric::FrameMs && !metric.follows_time(&b.name) {
        return Verdict::Regression;
    }
    // Frame time: beyond the noise of paired frames. A count that follows
    // the times, or a frame time with no paired interval (under four
    // frames): the new median less its MAD above the base median plus its
    // MAD.
    let spread = |m: &ModeSummary| m.stats.get(metric.name()).copied();
    let beyond_spread = match (paired, spread(b), spread(n)) {
        (Some(paired), ..) => paired.interval[0] > 1.0,
        (
            _,
            Some(Distribution {
                median: mb, mad: db, ..
            }),
            Some(Distribution {
                median: mn, mad: dn, ..
            }),
        ) => mn - dn > mb + db,
        _ => true,
    };
    if new > base * (1.0 + pct / 100.0) && beyond_spread {
        Verdict::Regression
    } else {
        Verdict::Noise
    }
}

/// `new`'s change from `base` (not 0) in percent, to a tenth; a change
/// that rounds to none there (ten triangles more over 3 000 frames of
/// 400 000), in as many digits as it takes to show, so that no change
/// reads as "+0.0%".
pub fn percent_change(base: f64, new: f64) -> String {
    let percent = (new - base) / base * 100.0;
    if percent.abs() >= 0.05 || new == base {
        format!("{percent:+.1}%")
    } else {
        format!("{percent:+.1e}%")
    }
}

/// The table printed by `occlu compare`.
pub fn render(c: &Comparison) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<24} {:<16} {:>14} {:>14} {:>9}  verdict",
        "mode", "metric", "base", "new", "change"
    );
    for ch in &c.changes {
        let num = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.2}"));
        let change = match (ch.base, ch.new) {
            (Some(b), Some(n)) if b != 0.0 => percent_change(b, n),
            (Some(b), Some(n)) if n != b => "new".to_string(),
            (Some(_), Some(_)) => "0.0%".to_string(),
            _ => "–".to_string(),
        };
        let verdict = match ch.verdict {
            Verdict::Same => "same",
            Verdict::Better => "better",
            Verdict::Noise => "within noise",
            Verdict::Regression => "REGRESSION",
            Verdict::Missing => "MISSING",
            Verdict::Unmeasured => "not measured",
            Verdict::NotJudged => "not judged",
        };
        let _ = writeln!(
            out,
            "{:<24} {:<16} {:>14} {:>14} {:>9}  {verdict}",
            crate::text::one_line(&ch.mode),
            ch.metric,
            num(ch.base),
            num(ch.new),
            change
        );
    }
    for note in &c.notes {
        let _ = writeln!(out, "note: {}", crate::text::one_line(note));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_too_small_for_a_tenth_of_a_percent_is_shown_all_the_same() {
        assert_eq!(percent_change(417_012.33, 417_012.34), "+2.4e-6%");
        assert_eq!(percent_change(100.0, 99.999), "-1.0e-3%");
        assert_eq!(percent_change(100.0, 100.0), "+0.0%");
        assert_eq!(percent_change(100.0, 100.06), "+0.1%");
        assert_eq!(percent_change(100.0, 150.0), "+50.0%");
    }
}
