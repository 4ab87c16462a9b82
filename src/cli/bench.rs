//! `occlu bench`: one run, or a matrix's runs (or a shard's share of them)
//! one after the other, each with its progress and notes on stderr and its
//! report (or summary.json) on stdout.

use std::fmt::Write as _;
use std::path::Path;

use occlu::bench::{BenchOutcome, execute};
use occlu::config::{BenchConfig, BenchPlan};
use occlu::matrix::{Matrix, MatrixRun, Shard};
use occlu::scene::SceneSpec;

use super::args::BenchArgs;
use super::output::{emit, say};
use super::progress::{Progress, heard};
use super::signals::{self, go_on};

/// `occlu bench`: one run (its report.md or summary.json on stdout), or a
/// matrix's (a table of its runs, or their summaries, on stdout).
pub fn bench(args: BenchArgs) -> anyhow::Result<()> {
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
        return bench_single(&plan, args.config.as_deref(), &note, quiet, args.json);
    }
    // Every run is checked before any runs, on every shard alike.
    let runs = matrix.plan(&flags)?;
    bench_shard(&runs, args.shard.unwrap_or(Shard::WHOLE), &note, quiet, args.json)
}

/// Runs a configuration that lists no runs (read from `config`, if any):
/// its report.md, or its summary.json with `json`, on stdout.
fn bench_single(
    plan: &BenchPlan,
    config: Option<&Path>,
    note: &dyn Fn(String),
    quiet: bool,
    json: bool,
) -> anyhow::Result<()> {
    let model = match &plan.scene {
        SceneSpec::File(model) => Some(model.as_path()),
        SceneSpec::Builtin(_) => None,
    };
    let inputs: Vec<&Path> = [model, plan.path.as_deref(), config].into_iter().flatten().collect();
    for output in [&plan.export_github_benchmark, &plan.trace].into_iter().flatten() {
        occlu::report::refuse_input_as_output(output, &inputs)?;
    }
    if let Some(config) = config {
        occlu::report::refuse_input_among_results(config, &plan.out)?;
    }
    if let (Some(export), Some(trace)) = (&plan.export_github_benchmark, &plan.trace) {
        occlu::report::refuse_one_file_twice(export, trace)?;
    }
    let outcome = bench_one(plan, note, quiet, format!("{} modes", plan.modes.len()))?;
    if json {
        emit(&(serde_json::to_string_pretty(&outcome.summary)? + "\n"))
    } else {
        emit(&occlu::report::render_markdown(&outcome.summary))
    }
}

/// Runs `shard`'s share of a matrix's `runs`, one after the other: a table
/// of them, or a list of their summaries with `json`, on stdout.
fn bench_shard(runs: &[MatrixRun], shard: Shard, note: &dyn Fn(String), quiet: bool, json: bool) -> anyhow::Result<()> {
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
        return if json { emit("[]\n") } else { Ok(()) };
    }
    // Every run of a matrix shares its --out and identity.
    if let Some((out, matrix)) = mine[0].plan.out.parent().zip(mine[0].plan.matrix) {
        occlu::bench::refuse_other_results_in_matrix_out(out, matrix)?;
    }
    let mut summaries = Vec::new();
    let mut table = String::from("| run | scene | path | adapter | folder |\n|---|---|---|---|---|\n");
    let mut failed: Vec<(&str, anyhow::Error)> = Vec::new();
    for (k, run) in mine.iter().enumerate() {
        note(format!(
            "run {} of {} (shard {shard} of a matrix of {}): {}",
            k + 1,
            mine.len(),
            runs.len(),
            run.name
        ));
        // A run that fails (a model that only loading finds broken) ends
        // itself, not the matrix: the others run, and merge names it
        // missing. Ctrl-C ends the matrix.
        let outcome = match bench_one(&run.plan, note, quiet, run.name.clone()) {
            Ok(outcome) => outcome,
            Err(e) if !signals::heard() => {
                // The first is said with the matrix's error, at the end.
                if !failed.is_empty() {
                    say!("occlu: run {} failed: {e:#}", run.name);
                }
                failed.push((&run.name, e));
                continue;
            }
            Err(e) => return Err(e.context(format!("run {}", run.name))),
        };
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
    if json {
        emit(&(serde_json::to_string_pretty(&summaries)? + "\n"))?;
    } else if !summaries.is_empty() {
        emit(&table)?;
    }
    // The first failure's error decides the exit status.
    let names: Vec<&str> = failed.iter().map(|(name, _)| *name).collect();
    match failed.into_iter().next() {
        None => Ok(()),
        Some((name, first)) => Err(first.context(format!(
            "{} of this shard's {} failed ({}; the others' results are written): run {name}",
            names.len(),
            occlu::text::count(mine.len(), "run"),
            names.join(", ")
        ))),
    }
}

/// Runs one plan with its progress on stderr (`prefix` names it there) and
/// says where its results went.
fn bench_one(plan: &BenchPlan, note: &dyn Fn(String), quiet: bool, prefix: String) -> anyhow::Result<BenchOutcome> {
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
