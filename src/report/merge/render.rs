//! The merged report: report.md (per run, its modes on every adapter side
//! by side, the disagreements, the run folders) and each run's
//! ratio-to-oracle chart.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

use super::merged::{AdapterColumn, Merged, MergedRun, ModeResult, number, unique};
use crate::report::charts::{RatioBars, ratio_to_oracle_bars};
use crate::report::files::ReportError;
use crate::report::summary::Fingerprint;
use crate::text::{markdown, slug};

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
        run_section(w, run);
    }
    out
}

/// One run's section of report.md: what it measured, its table, what was
/// not measured, its chart, the counters adapters disagree on and where
/// each column came from.
fn run_section(w: &mut String, run: &MergedRun) {
    let _ = writeln!(w, "## {}\n", markdown(&run.name));
    let _ = writeln!(
        w,
        "Scene {}, path {}, {}, {} frames.\n",
        markdown(&run.scene),
        markdown(&run.path),
        run.resolution,
        run.frames
    );
    mode_table(w, run);
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

/// Shows one metric of a [`ModeResult`] in a table cell.
type Cell = fn(&ModeResult) -> String;

/// A run's table: a row per mode and metric, a column per adapter.
fn mode_table(w: &mut String, run: &MergedRun) {
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
}

/// Draws `run`'s ratio-to-oracle chart into `staging`'s charts folder and
/// records its name, when any adapter ran the oracle.
pub(super) fn draw_chart(staging: &Path, run: &mut MergedRun, used: &mut BTreeSet<String>) -> Result<(), ReportError> {
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
