//! `occlu compare BASE NEW`: what changed between two runs, and whether it
//! is a regression a CI job should fail on.
//!
//! Deterministic counters (triangles drawn, box tests, round trips, wrong
//! pixels, missed objects) do not depend on machine noise: any increase is a
//! regression. Frame time does: it regresses only when its mean grows beyond
//! `--max-regression` percent *and* the new median minus its MAD lies above
//! the base median plus its MAD, so noise within the measured spread passes.
//! Statistics are recomputed from each run's frames.csv.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::{ReportError, Summary, read_results};
use crate::measure::{Distribution, FrameStats, ModeDescription, ModeSummary, summarize};

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
    /// The metric was not measured in one of the runs.
    Unmeasured,
}

#[derive(Clone, Debug, Serialize)]
pub struct Change {
    pub mode: String,
    pub metric: &'static str,
    pub base: Option<f64>,
    pub new: Option<f64>,
    pub verdict: Verdict,
}

pub struct Comparison {
    pub changes: Vec<Change>,
    /// Modes in only one of the runs, and other differences worth a look.
    pub notes: Vec<String>,
}

impl Comparison {
    pub fn regressions(&self) -> impl Iterator<Item = &Change> {
        self.changes.iter().filter(|c| c.verdict == Verdict::Regression)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Read(#[from] ReportError),
    #[error("the runs measured different workloads ({0}): their counters are not comparable")]
    Different(String),
    #[error("--max-regression must be a percentage of 0 or more, got {0}")]
    Threshold(f64),
}

pub fn compare(
    base: &Path,
    new: &Path,
    max_regression_pct: f64,
    metrics: &[Metric],
) -> Result<Comparison, CompareError> {
    if !(max_regression_pct >= 0.0 && max_regression_pct.is_finite()) {
        return Err(CompareError::Threshold(max_regression_pct));
    }
    let (base_summary, base_rows) = read_results(base)?;
    let (new_summary, new_rows) = read_results(new)?;
    let workload = |s: &Summary| {
        (
            s.scene.facts.source.clone(),
            s.path.source.clone(),
            s.resolution,
            s.frames,
        )
    };
    let (a, b) = (workload(&base_summary), workload(&new_summary));
    if a != b {
        return Err(CompareError::Different(format!(
            "{} {} {} {} frames vs {} {} {} {} frames",
            a.0, a.1, a.2, a.3, b.0, b.1, b.2, b.3
        )));
    }
    let mut notes = Vec::new();
    if base_summary.adapter != new_summary.adapter {
        notes.push(format!(
            "different adapters ({} vs {}): frame times are not comparable; counters are",
            base_summary.adapter, new_summary.adapter
        ));
    }
    let base_modes = recompute(&base_summary, &base_rows);
    let new_modes = recompute(&new_summary, &new_rows);
    let mut changes = Vec::new();
    for b in &base_modes {
        let Some(n) = new_modes.iter().find(|n| n.name == b.name) else {
            notes.push(format!("mode {} is in the base run only", b.name));
            continue;
        };
        for &metric in metrics {
            let (base_value, new_value) = (metric.value(b), metric.value(n));
            let verdict = match (base_value, new_value) {
                (Some(x), Some(y)) => verdict(metric, x, y, b, n, max_regression_pct),
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

/// Statistics from frames.csv, with the conservative flags and parameters
/// the summary recorded.
fn recompute(summary: &Summary, rows: &[FrameStats]) -> Vec<ModeSummary> {
    let modes: Vec<ModeDescription> = summary
        .modes
        .iter()
        .map(|m| ModeDescription {
            name: m.name.clone(),
            conservative: m.conservative,
            parameters: m.parameters.clone(),
        })
        .collect();
    summarize(rows, &modes, summary.resolution.pixels())
}

/// Relative tolerance for "unchanged" on means of deterministic counters
/// (they are sums of integers divided by the same frame count).
const SAME: f64 = 1e-9;

fn verdict(metric: Metric, base: f64, new: f64, b: &ModeSummary, n: &ModeSummary, pct: f64) -> Verdict {
    let tolerance = SAME * base.abs().max(1.0);
    if (new - base).abs() <= tolerance {
        return Verdict::Same;
    }
    if new < base {
        return Verdict::Better;
    }
    if metric != Metric::FrameMs {
        return Verdict::Regression;
    }
    let spread = |m: &ModeSummary| m.stats.get("frame_ms").copied();
    let beyond_spread = match (spread(b), spread(n)) {
        (
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
            (Some(b), Some(n)) if b != 0.0 => format!("{:+.1}%", (n - b) / b * 100.0),
            (Some(b), Some(n)) if n != b => "new".to_string(),
            (Some(_), Some(_)) => "0.0%".to_string(),
            _ => "–".to_string(),
        };
        let verdict = match ch.verdict {
            Verdict::Same => "same",
            Verdict::Better => "better",
            Verdict::Noise => "within noise",
            Verdict::Regression => "REGRESSION",
            Verdict::Unmeasured => "not measured",
        };
        let _ = writeln!(
            out,
            "{:<24} {:<16} {:>14} {:>14} {:>9}  {verdict}",
            ch.mode,
            ch.metric,
            num(ch.base),
            num(ch.new),
            change
        );
    }
    for note in &c.notes {
        let _ = writeln!(out, "note: {note}");
    }
    out
}
