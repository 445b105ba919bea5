//! Where the CLI's text goes, with every write checked: standard output
//! (buffered) and standard error (warnings, summaries).
//!
//! The rule, as for Unix tools: when the reader of standard output goes away
//! (`aacmm … | head -1`), the write fails with a broken pipe and the program
//! stops quietly with success — [`Closed`] carries that to `main`. Any other
//! write error (a full disk, `> /dev/full`) is an error naming the stream.
//!
//! Standard error carries warnings and summaries. When its reader goes away
//! (`aacmm simulate … 2>&1 | head -3`), nobody wants more of them: later
//! ones are dropped and the work goes on. Any other failure to write it is
//! [`StderrFailed`], which `main` cannot report: it only exits with failure.

use std::fmt::{self, Display};
use std::io::{self, BufWriter, ErrorKind, StdoutLock, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// The reader of standard output has gone away: stop quietly, with success.
#[derive(Debug)]
pub struct Closed;

impl Display for Closed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("stdout: closed by its reader")
    }
}

impl std::error::Error for Closed {}

/// Standard error cannot be written: nothing more can be said.
#[derive(Debug)]
pub struct StderrFailed(pub io::Error);

impl Display for StderrFailed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "stderr: cannot write: {}", self.0)
    }
}

impl std::error::Error for StderrFailed {}

/// A failed write to standard output as the error `main` acts on: [`Closed`]
/// for a broken pipe, else a message naming stdout.
pub fn stdout_error(e: io::Error) -> anyhow::Error {
    if e.kind() == ErrorKind::BrokenPipe {
        anyhow::Error::new(Closed)
    } else {
        anyhow::anyhow!("stdout: cannot write: {e}")
    }
}

/// Standard output, locked and buffered. Nothing is guaranteed written until
/// [`Stdout::finish`], which must be called.
pub struct Stdout {
    w: BufWriter<StdoutLock<'static>>,
}

impl Stdout {
    /// Locks standard output for this command.
    pub fn new() -> Stdout {
        Stdout {
            w: BufWriter::new(io::stdout().lock()),
        }
    }

    /// Writes `text` as is.
    pub fn print(&mut self, text: impl Display) -> anyhow::Result<()> {
        write!(self.w, "{text}").map_err(stdout_error)
    }

    /// Runs a writer (e.g. a library's file writer) on standard output.
    pub fn write_with(
        &mut self,
        f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> anyhow::Result<()> {
        f(&mut self.w).map_err(stdout_error)
    }

    /// Flushes everything to the terminal, pipe or file.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.w.flush().map_err(stdout_error)?;
        self.w.get_mut().flush().map_err(stdout_error)
    }
}

/// Set once standard error's reader has gone away.
static STDERR_CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes one line to standard error (nothing once its reader has gone).
pub fn note(line: impl Display) -> anyhow::Result<()> {
    if STDERR_CLOSED.load(Ordering::Relaxed) {
        return Ok(());
    }
    match writeln!(io::stderr().lock(), "{line}") {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == ErrorKind::BrokenPipe => {
            STDERR_CLOSED.store(true, Ordering::Relaxed);
            Ok(())
        }
        Err(e) => Err(anyhow::Error::new(StderrFailed(e))),
    }
}

/// Writes `warning: …` to standard error.
pub fn warn(message: impl Display) -> anyhow::Result<()> {
    note(format_args!("warning: {message}"))
}

/// What `main` does with a command's error: the process's exit code, after
/// a one-line message on standard error where one can be written.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    let is = |f: fn(&(dyn std::error::Error + 'static)) -> bool| e.chain().any(f);
    if is(|c| c.is::<Closed>()) {
        return 0;
    }
    if !is(|c| c.is::<StderrFailed>()) {
        // If standard error fails too, there is no one left to tell.
        let _ = note(format_args!("error: {e:#}"));
    }
    1
}
