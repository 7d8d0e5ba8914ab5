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
    /// The run writes files too, so a reader that goes away ends the
    /// printing, not the run: `| head -c1` must not cost the bag.
    outlives_reader: bool,
    /// The reader went away (with `outlives_reader`): writes are dropped.
    gone: bool,
}

impl Stdout {
    /// Standard output, locked for this writer.
    pub fn new() -> Stdout {
        Stdout {
            inner: std::io::BufWriter::new(std::io::stdout().lock()),
            outlives_reader: false,
            gone: false,
        }
    }

    /// Standard output for a run that also writes files: once its reader
    /// has gone, what is printed is dropped and the run goes on to write
    /// them (any other failure of standard output is still an error).
    pub fn outliving_its_reader() -> Stdout {
        Stdout {
            outlives_reader: true,
            ..Stdout::new()
        }
    }

    /// Writes `text`.
    pub fn write(&mut self, text: &str) -> anyhow::Result<()> {
        if self.gone {
            return Ok(());
        }
        let result = self.inner.write_all(text.as_bytes());
        self.settle(result)
    }

    /// Writes `text` and a line break.
    pub fn line(&mut self, text: impl Display) -> anyhow::Result<()> {
        if self.gone {
            return Ok(());
        }
        let result = writeln!(self.inner, "{text}");
        self.settle(result)
    }

    /// Sends what is buffered (before a message on standard error, so the
    /// two stay in order on a terminal).
    pub fn flush(&mut self) -> anyhow::Result<()> {
        if self.gone {
            return Ok(());
        }
        let result = self.inner.flush();
        self.settle(result)
    }

    fn settle(&mut self, result: std::io::Result<()>) -> anyhow::Result<()> {
        match result {
            Err(err) if err.kind() == ErrorKind::BrokenPipe && self.outlives_reader => {
                self.gone = true;
                Ok(())
            }
            other => other.map_err(stdout_error),
        }
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

/// `whycode: error: {text}` on standard error; nothing once a signal's
/// clean-up has begun ([`whycode::io::stopping`]): what fails then (a
/// write to the ffmpeg it stopped) is the stop, which the exit status
/// tells.
pub fn error(text: impl Display) {
    if whycode::io::stopping() {
        return;
    }
    say(format_args!("error: {text}"));
}
