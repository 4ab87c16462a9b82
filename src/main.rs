//! The `occlu` command line: parses arguments, hands each command to its
//! handler in [`cli`], and maps errors to one line and an exit code (2: bad
//! input, 1: a failure while running, 130: interrupted).

mod cli;

use std::process::ExitCode;

use clap::Parser as _;
use occlu::animation::AnimationError;
use occlu::bench::BenchError;
use occlu::camera::path::PathError;
use occlu::config::ConfigError;
use occlu::cull::ModeError;
use occlu::matrix::MatrixError;
use occlu::picture::PictureError;
use occlu::report::ReportError;
use occlu::report::compare::CompareError;
use occlu::report::merge::MergeError;
use occlu::scene::SceneError;
use occlu::stress::StressError;

use cli::args::{Cli, Command, PathCommand};
use cli::output::{StdoutError, say};
use cli::runtime_folder::give_wayland_a_runtime_folder;
use cli::signals::{Interrupted, end_by_sigint, listen_for_ctrl_c};
use cli::{bench, pictures, results, scene, signals, stress};

fn main() -> ExitCode {
    give_wayland_a_runtime_folder();
    listen_for_ctrl_c();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version, written as `cli::output::emit` writes:
            // a closed pipe ends them quietly, a full disk is a failure.
            use std::io::Write as _;
            return match e.print().and_then(|()| std::io::stdout().flush()) {
                Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
                    say!("occlu: error: {}", StdoutError(error));
                    ExitCode::from(if std::env::args_os().nth(1).is_some_and(|a| a == "compare") {
                        2
                    } else {
                        1
                    })
                }
                _ => ExitCode::SUCCESS,
            };
        }
        Err(e) => {
            // The message with the lines that complete it (the values a
            // flag takes, the arguments missing), up to the usage.
            let text = e.render().to_string();
            let lines: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.is_empty()).collect();
            let message = lines.join(" ");
            say!("occlu: {}", message.trim_start_matches("error: "));
            return ExitCode::from(2);
        }
    };
    let done = |()| ExitCode::SUCCESS;
    // compare's exit 1 is its verdict (a regression), so any failure of its
    // own is 2, as diff's "trouble" is (its --help's too, above): a CI gate
    // must not take a full disk for a slower build.
    let failure_is_trouble = matches!(cli.command, Command::Compare(_));
    let result = match cli.command {
        Command::Bench(args) => bench::bench(*args).map(done),
        Command::Info(args) => scene::info(&args).map(done),
        Command::Path {
            command: PathCommand::Gen(args),
        } => scene::path_gen(&args).map(done),
        Command::Stress(args) => stress::stress(args),
        Command::Export(args) => scene::export(&args).map(done),
        Command::Plot(args) => results::plot(&args).map(done),
        Command::Render(args) => pictures::render(args).map(done),
        Command::Flythrough(args) => pictures::flythrough(*args).map(done),
        Command::Merge(args) => results::merge(&args).map(done),
        Command::Compare(args) => results::compare(args),
    };
    let code = match result {
        Err(e) if was_interrupted(&e) => {
            say!("occlu: {e:#}");
            end_by_sigint()
        }
        Ok(code) => code,
        Err(e) => {
            say!("occlu: error: {e:#}");
            ExitCode::from(if failure_is_trouble || is_input_error(&e) { 2 } else { 1 })
        }
    };
    // Ctrl-C while the results were written: they are whole, and the
    // interruption still reaches the caller.
    if signals::heard() {
        say!("occlu: interrupted");
        end_by_sigint();
    }
    code
}

fn was_interrupted(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.is::<Interrupted>()
            || matches!(c.downcast_ref::<BenchError>(), Some(BenchError::Interrupted))
            || matches!(c.downcast_ref::<StressError>(), Some(StressError::Interrupted))
            || matches!(c.downcast_ref::<AnimationError>(), Some(AnimationError::Interrupted))
            || matches!(c.downcast_ref::<PathError>(), Some(PathError::Interrupted))
    })
}

fn is_input_error(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<BenchError>().is_some_and(BenchError::is_input_error)
            || c.is::<SceneError>()
            || c.is::<PathError>()
            || c.is::<ConfigError>()
            || c.is::<MatrixError>()
            || c.downcast_ref::<MergeError>().is_some_and(MergeError::is_input_error)
            || c.downcast_ref::<ReportError>().is_some_and(ReportError::is_input_error)
            || c.is::<CompareError>()
            || c.is::<ModeError>()
            || c.is::<occlu::export::ExportError>()
            || c.downcast_ref::<StressError>().is_some_and(StressError::is_input_error)
            || c.downcast_ref::<occlu::gpu::GpuError>()
                .is_some_and(occlu::gpu::GpuError::is_input_error)
            || c.downcast_ref::<PictureError>()
                .is_some_and(PictureError::is_input_error)
            || c.downcast_ref::<AnimationError>()
                .is_some_and(AnimationError::is_input_error)
    })
}
