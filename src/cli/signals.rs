//! Ctrl-C, SIGTERM and SIGHUP: heard as a request to stop while a step
//! listens ([`go_on`] to [`stop_listening`]), so a run stops between frames
//! and writes nothing; otherwise (and at a second one) the process ends at
//! once, as killed by SIGINT ([`end_by_sigint`], this module's `unsafe`).

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU8, Ordering};

/// What Ctrl-C does now: [`ENDS_AT_ONCE`], [`LISTENED`] or [`HEARD`]. One
/// value, so that the handler and a step that stops listening cannot both
/// miss a Ctrl-C between them.
static CTRL_C: AtomicU8 = AtomicU8::new(ENDS_AT_ONCE);

/// No step that stops cleanly is running: Ctrl-C ends the process at once,
/// as it would without a handler. Nothing is half-written then: the
/// operating system drops the claim on --out, and result files are moved
/// into place whole.
const ENDS_AT_ONCE: u8 = 0;
/// A step that stops cleanly on Ctrl-C is running (see [`go_on`]): the
/// first Ctrl-C asks it to stop.
const LISTENED: u8 = 1;
/// Ctrl-C came while a step listened: the work stops at its next frame
/// (bench), case (stress) or stretch of ray casts (planning), writes
/// nothing, and ends the process.
const HEARD: u8 = 2;

/// The first Ctrl-C (or SIGTERM, or SIGHUP: a terminal closed, a job
/// cancelled) asks a listening step to stop (see [`CTRL_C`]); a second
/// one, or one while nothing listens, ends the process at once.
pub fn listen_for_ctrl_c() {
    let _ = ctrlc::set_handler(|| {
        if CTRL_C
            .compare_exchange(LISTENED, HEARD, Ordering::SeqCst, Ordering::SeqCst)
            .is_err()
        {
            end_by_sigint();
        }
    });
}

/// Ends the process as killed by SIGINT, so a calling shell or script sees
/// the interruption (status 130) and stops as well, which an exit code
/// alone would not make it do. A results folder this process made and
/// wrote no results into goes first.
pub fn end_by_sigint() -> ! {
    occlu::report::abandon_unfinished();
    #[cfg(unix)]
    // SAFETY: restores SIGINT's default action and raises it; neither call
    // touches memory, and the default action ends the process.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
        libc::raise(libc::SIGINT);
    }
    std::process::exit(130)
}

/// Whether the work should go on (no Ctrl-C yet); from its first call on,
/// Ctrl-C asks the work to stop instead of ending the process, until
/// [`stop_listening`].
pub fn go_on() -> ControlFlow<()> {
    match CTRL_C.compare_exchange(ENDS_AT_ONCE, LISTENED, Ordering::SeqCst, Ordering::SeqCst) {
        Err(HEARD) => ControlFlow::Break(()),
        _ => ControlFlow::Continue(()),
    }
}

/// A command heard Ctrl-C while a step of it listened, and stopped before
/// writing anything.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: nothing written")]
pub struct Interrupted;

/// Ends a step that listened for Ctrl-C (path planning in `render`,
/// `export` and `path gen`), for a command whose later steps do not ask
/// [`go_on`]: from here on Ctrl-C ends the process at once again, rather
/// than being heard by nothing while the command runs to its end and
/// writes. A Ctrl-C that the step heard after it last asked stops the
/// command here.
pub fn stop_listening() -> Result<(), Interrupted> {
    match CTRL_C.compare_exchange(LISTENED, ENDS_AT_ONCE, Ordering::SeqCst, Ordering::SeqCst) {
        Err(HEARD) => Err(Interrupted),
        _ => Ok(()),
    }
}

/// Whether a Ctrl-C was heard (and not yet acted on): one that came while
/// the results were written, which are whole, and which must still reach
/// the caller.
pub fn heard() -> bool {
    CTRL_C.load(Ordering::SeqCst) == HEARD
}
