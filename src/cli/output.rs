//! Everything the command line prints goes through here, so that one rule
//! holds for every subcommand: a reader that goes away (`| head`) ends the
//! run quietly with success, any other failure to write standard output is
//! one line and exit 1, and a standard error that cannot be written to
//! (`2>/dev/full`) never turns into a panic.

use std::fmt::Display;
use std::io::{ErrorKind, Write};

/// Standard output was closed by its reader: what was wanted was read,
/// and the run ends with success.
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed")]
pub struct ReaderGone;

/// Writes `text` to standard output and flushes it.
pub fn print(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// Standard output for many writes (a stream of frames): buffered, with
/// the same rules as [`print`].
pub struct Stdout {
    inner: std::io::BufWriter<std::io::StdoutLock<'static>>,
}

impl Stdout {
    /// Standard output, locked for this writer.
    pub fn new() -> Stdout {
        Stdout {
            inner: std::io::BufWriter::new(std::io::stdout().lock()),
        }
    }

    /// Writes `text`.
    pub fn write(&mut self, text: &str) -> anyhow::Result<()> {
        self.inner.write_all(text.as_bytes()).map_err(stdout_error)
    }

    /// Writes `text` and a line break.
    pub fn line(&mut self, text: impl Display) -> anyhow::Result<()> {
        writeln!(self.inner, "{text}").map_err(stdout_error)
    }

    /// Sends what is buffered (before a message on standard error, so the
    /// two stay in order on a terminal).
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.inner.flush().map_err(stdout_error)
    }
}

fn stdout_error(err: std::io::Error) -> anyhow::Error {
    if err.kind() == ErrorKind::BrokenPipe {
        ReaderGone.into()
    } else {
        anyhow::anyhow!("cannot write to standard output: {err}")
    }
}

/// A line on standard error: `whycode: {text}`. Standard error is where
/// problems are reported, so a failure to write there has nowhere to go
/// and is dropped rather than allowed to end the run.
pub fn say(text: impl Display) {
    let _ = writeln!(std::io::stderr().lock(), "whycode: {text}");
}

/// `whycode: note: {text}` on standard error.
pub fn note(text: impl Display) {
    say(format_args!("note: {text}"));
}

/// `whycode: error: {text}` on standard error.
pub fn error(text: impl Display) {
    say(format_args!("error: {text}"));
}
