//! The commands that read result folders back: `plot` (a run's charts and
//! report again), `merge` (many folders into one report) and `compare` (two
//! runs or merged folders judged for CI).

use std::process::ExitCode;

use occlu::report::compare::{CompareOptions, Metric, Verdict, percent_change};
use occlu::text;

use super::args::{CompareArgs, MergeArgs, PlotArgs};
use super::output::{emit, say};

/// `occlu plot`: a run folder's charts and report.md drawn again.
pub fn plot(args: &PlotArgs) -> anyhow::Result<()> {
    let run_dir = &args.run_dir;
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

/// `occlu merge`: the merged report on stdout, where it went and its warnings on stderr.
pub fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    let out = &args.out;
    let merged = occlu::report::merge::merge(&args.dirs, out, args.allow_partial)?;
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

/// `occlu compare`: the verdicts on stdout; exit 1 on a regression.
pub fn compare(args: CompareArgs) -> anyhow::Result<ExitCode> {
    let options = CompareOptions {
        max_regression_pct: args.max_regression,
        metrics: if args.metric.is_empty() {
            Metric::ALL.to_vec()
        } else {
            args.metric
        },
        allow_missing: args.allow_missing,
        cross_adapter: args.cross_adapter,
    };
    let comparison = occlu::report::compare::compare(&args.base, &args.new, &options)?;
    if args.json {
        emit(&(serde_json::to_string_pretty(&comparison)? + "\n"))?;
    } else {
        emit(&occlu::report::compare::render(&comparison))?;
    }
    let regressions: Vec<String> = comparison
        .regressions()
        .map(|c| match (c.base, c.new) {
            _ if c.verdict == Verdict::Missing => format!("{} {} missing", c.mode, c.metric),
            (Some(b), Some(n)) if b != 0.0 => format!("{} {} {}", c.mode, c.metric, percent_change(b, n)),
            _ => format!("{} {}", c.mode, c.metric),
        })
        .collect();
    if regressions.is_empty() {
        say!("no regression");
        Ok(ExitCode::SUCCESS)
    } else {
        say!(
            "occlu: {} regressed or missing: {}",
            text::count(regressions.len(), "measure"),
            regressions.join(", ")
        );
        Ok(ExitCode::from(1))
    }
}
