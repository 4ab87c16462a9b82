//! How the command line prints: `say!` to standard error (notes, warnings,
//! errors, one escaped line each, never failing) and [`emit`] to standard
//! output (what a command is asked for, ending quietly on a closed pipe).

/// Writes a line to standard error, its control and reordering characters
/// escaped ([`occlu::text::one_line`]) and then its middle left out past
/// [`occlu::text::MESSAGE_CHARACTERS`] ([`occlu::text::shortened`], which
/// may cut an escape in two: the bound is on what reaches the terminal):
/// file, object and parser names reach it from anyone's files, and must
/// neither drive the terminal nor break or flood the line. A closed or
/// full standard error is no reason to fail a run (and must not panic, as
/// `eprintln!` does): the line is dropped.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let line = occlu::text::one_line(&format!($($arg)*));
        let line = occlu::text::shortened(&line, occlu::text::MESSAGE_CHARACTERS);
        let _ = writeln!(std::io::stderr().lock(), "{line}");
    }};
}
pub(crate) use say;

/// Standard output could not take what a command printed (a full disk).
#[derive(Debug, thiserror::Error)]
#[error("cannot write to standard output: {0}")]
pub struct StdoutError(pub std::io::Error);

/// Writes `text` to standard output. A reader that went away (a closed
/// pipe, as in `occlu stress --list | head -1`) is not an error: the rest
/// is not wanted, and the command succeeds as other Unix tools do. Any
/// other failure is (exit 1).
pub fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(StdoutError(e).into()),
        _ => Ok(()),
    }
}
