//! `occlu stress`: the built-in hard cases run through every mode, a bar
//! per case, the report on stdout (and in --out), exit 1 on any failure.

use std::process::ExitCode;

use indicatif::{ProgressBar, ProgressStyle};
use occlu::cull::{ModeParams, parse_modes};
use occlu::gpu::Resolution;
use occlu::stress::StressEvent;

use super::args::StressArgs;
use super::output::{emit, say};
use super::signals::go_on;

/// `occlu stress`: the cases' report; exit 1 when any failed.
pub fn stress(args: StressArgs) -> anyhow::Result<ExitCode> {
    let modes = parse_modes(args.modes.as_deref().unwrap_or(&["all".to_string()]))?;
    let given = ModeParams::parse(&args.params, &modes)?;
    let cases = occlu::stress::select(&args.cases)?;
    if args.list {
        let list: String = cases
            .iter()
            .map(|case| format!("{:<15} {} frames: {}\n", case.name, case.cameras.len(), case.summary))
            .collect();
        emit(&list)?;
        return Ok(ExitCode::SUCCESS);
    }
    let backend = args.backend.unwrap_or_default();
    backend.backends()?;
    let _claim = args.out.as_deref().map(occlu::report::prepare_output).transpose()?;
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    say!("adapter: {}", gpu.adapter);
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{prefix:<15} [{bar:32}] {pos}/{len} frames, {elapsed} elapsed")
            .expect("static template")
            .progress_chars("=> "),
    );
    let resolution = args.resolution.unwrap_or(STRESS_RESOLUTION);
    let report = occlu::stress::run(&gpu, &cases, &modes, &given, resolution, &mut |event| {
        match event {
            StressEvent::Skipped { mode, reason } => say!("skipped: {mode}: {reason}"),
            StressEvent::CaseSkipped { case, reason } => say!("skipped case: {case}: {reason}"),
            StressEvent::Case { case } => bar.set_prefix(case.name.clone()),
            StressEvent::Frame { done, total } => {
                bar.set_length(u64::from(total));
                bar.set_position(u64::from(done));
            }
        }
        go_on()
    })?;
    bar.finish_and_clear();
    let markdown = occlu::stress::render_markdown(&report);
    emit(&markdown)?;
    if let Some(out) = &args.out {
        let json = serde_json::to_string_pretty(&report)? + "\n";
        occlu::report::publish_files(
            out,
            &[("stress.md", markdown.as_bytes()), ("stress.json", json.as_bytes())],
        )?;
        say!("results: stress.md and stress.json in {}", out.display());
    }
    let (_, failed) = report.verdicts();
    Ok(if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Small: the cases are about precision, not pixel throughput.
const STRESS_RESOLUTION: Resolution = Resolution {
    width: 400,
    height: 300,
};
