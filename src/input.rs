//! Files a command reads: the one place they are opened.
//!
//! Two promises rest here. A file read as configuration (a family, a
//! manifest, a calibration, a template, a board, an arena file) must be a
//! regular file no larger than its kind ever is (an image or a recording a
//! regular file), so `--manifest /dev/zero`
//! or a FIFO nobody writes is one error line instead of memory exhausted or
//! a wait forever. And while a [`Recording`] is open (the command line
//! opens one for the whole command), every file read, and every file a
//! manifest names beside itself, is remembered, so that `io::check_outputs`
//! and the writers refuse an output that would land on any of them, not
//! only on the paths given on the command line.

use crate::error::{FileKind, LoadError, LoadProblem};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Files read (or named by what was read) while a recording is open: the
/// path as given and the file it resolves to.
struct Record {
    open: usize,
    files: Vec<(PathBuf, PathBuf)>,
    /// The resolved paths of `files`, so a folder of 100,000 frames is
    /// remembered in linear time.
    real: Option<std::collections::HashSet<PathBuf>>,
}

static RECORD: Mutex<Record> = Mutex::new(Record {
    open: 0,
    files: Vec::new(),
    real: None,
});

fn record() -> std::sync::MutexGuard<'static, Record> {
    RECORD.lock().unwrap_or_else(|p| p.into_inner())
}

thread_local! {
    /// Reads on this thread that are not inputs (a command reading its own
    /// old output to replace it) while above zero.
    static UNRECORDED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// The files read since it was opened remain remembered until it is
/// dropped (and, when several are open at once, until the last is). A
/// long-lived program (Python, the node) keeps nothing when it opens none.
#[must_use = "the files are remembered only while the recording lives"]
pub struct Recording {
    from: usize,
}

impl Recording {
    /// Starts remembering the files read.
    pub fn start() -> Recording {
        let mut record = record();
        record.open += 1;
        Recording {
            from: record.files.len(),
        }
    }

    /// The files read since this recording started, as they were given (a
    /// file another recording open at the same time had already read is
    /// not listed again).
    pub fn files(&self) -> Vec<PathBuf> {
        let record = record();
        record.files[self.from.min(record.files.len())..]
            .iter()
            .map(|(given, _)| given.clone())
            .collect()
    }
}

impl Drop for Recording {
    fn drop(&mut self) {
        let mut record = record();
        record.open -= 1;
        if record.open == 0 {
            record.files = Vec::new();
            record.real = None;
        }
    }
}

/// Remembers `path` as an input of the command running, if a recording is
/// open: a file that was read, or one whose contents what was read vouches
/// for (a manifest's pages). A path that does not resolve to a file is not
/// remembered: nothing would be lost by writing there.
pub fn note(path: &Path) {
    if UNRECORDED.with(|c| c.get()) > 0 {
        return;
    }
    let mut record = record();
    if record.open == 0 {
        return;
    }
    if let Ok(real) = std::fs::canonicalize(path) {
        if record.real.get_or_insert_default().insert(real.clone()) {
            record.files.push((path.to_path_buf(), real));
        }
    }
}

#[cfg_attr(not(feature = "files"), allow(dead_code))]
/// The input among those remembered that `real` (a resolved path) is, as
/// it was given.
pub(crate) fn recorded_as(real: &Path) -> Option<PathBuf> {
    let record = record();
    if !record.real.as_ref().is_some_and(|set| set.contains(real)) {
        return None;
    }
    record
        .files
        .iter()
        .find(|(_, r)| r == real)
        .map(|(given, _)| given.clone())
}

/// Runs `read` without remembering what it reads: for a command reading
/// the old version of a file it is about to replace (a sheet's old
/// manifest), which is an output, not an input.
pub fn unrecorded<T>(read: impl FnOnce() -> T) -> T {
    struct Restore;
    impl Drop for Restore {
        fn drop(&mut self) {
            UNRECORDED.with(|c| c.set(c.get() - 1));
        }
    }
    UNRECORDED.with(|c| c.set(c.get() + 1));
    let _restore = Restore;
    read()
}

/// The most bytes a file of `kind` is read to. Far beyond any real one (a
/// manifest of 100,000 markers is about 15 MB, a 24-bit family file about
/// 40 MB), and small enough that a wrong path costs no more memory than that.
pub fn max_bytes(kind: FileKind) -> u64 {
    match kind {
        FileKind::Family | FileKind::Manifest | FileKind::Board => 256 << 20,
        FileKind::Camera | FileKind::Template | FileKind::Arena | FileKind::Params => 16 << 20,
        // Not read whole: images are decoded within their size limit,
        // recordings mapped or streamed.
        FileKind::Image | FileKind::Recording => u64::MAX,
    }
}

/// Opens `path` as a regular file (links followed) of `kind`, refusing a
/// folder, FIFO, socket or device before opening it (opening a FIFO with no
/// writer waits forever), and remembers it as an input. Returns the file
/// and its length.
pub fn open(path: &Path, kind: FileKind) -> Result<(std::fs::File, u64), LoadError> {
    let meta = std::fs::metadata(path).map_err(|e| LoadError::read(path, kind, e))?;
    if let Some(what) = not_regular(&meta) {
        return Err(LoadError::new(
            path,
            kind,
            LoadProblem::Invalid(format!(
                "is {what}, not a file: give the {} itself",
                kind.noun()
            )),
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| LoadError::read(path, kind, e))?;
    note(path);
    Ok((file, meta.len()))
}

/// What a path that is not a regular file is, in words.
fn not_regular(meta: &std::fs::Metadata) -> Option<&'static str> {
    let kind = meta.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
        if kind.is_char_device() || kind.is_block_device() {
            return Some("a device");
        }
    }
    Some("not a regular file")
}

/// Reads a configuration file of `kind` whole as text: a regular file of at
/// most [`max_bytes`], remembered as an input.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String, LoadError> {
    let bytes = read_bytes(path, kind)?;
    String::from_utf8(bytes).map_err(|_| {
        LoadError::read(
            path,
            kind,
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "stream did not contain valid UTF-8",
            ),
        )
    })
}

/// Reads a file of `kind` whole as bytes, as [`read_text`] does.
pub fn read_bytes(path: &Path, kind: FileKind) -> Result<Vec<u8>, LoadError> {
    let (file, len) = open(path, kind)?;
    let cap = max_bytes(kind);
    let too_large = |size: String| {
        LoadError::new(
            path,
            kind,
            LoadProblem::Invalid(format!(
                "is {size}, more than any {} ({} MB); is it the right file?",
                kind.noun(),
                cap >> 20
            )),
        )
    };
    if len > cap {
        return Err(too_large(format!("{} MB", len >> 20)));
    }
    // Read to one byte past the cap: a file growing while it is read stops there.
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| LoadError::read(path, kind, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_large("growing past that".to_string()));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_or_an_oversized_file_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let err = read_text(dir.path(), FileKind::Camera).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("is a folder, not a file"), "{text}");
        let big = dir.path().join("big.yaml");
        let file = std::fs::File::create(&big).unwrap();
        file.set_len(max_bytes(FileKind::Camera) + 1).unwrap();
        let text = read_text(&big, FileKind::Camera).unwrap_err().to_string();
        assert!(
            text.starts_with(&format!("{}: is 16 MB", big.display())),
            "{text}"
        );
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_refused_before_reading() {
        let text = read_text(Path::new("/dev/zero"), FileKind::Manifest)
            .unwrap_err()
            .to_string();
        assert_eq!(
            text,
            "/dev/zero: is a device, not a file: give the sheet manifest itself"
        );
    }

    #[test]
    fn only_an_open_recording_remembers_and_unrecorded_reads_are_not_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
        std::fs::write(&a, "{}").unwrap();
        std::fs::write(&b, "{}").unwrap();
        let recording = Recording::start();
        read_text(&a, FileKind::Family).unwrap();
        unrecorded(|| read_text(&b, FileKind::Family).unwrap());
        let files = recording.files();
        assert!(files.contains(&a), "{files:?}");
        assert!(!files.contains(&b), "{files:?}");
    }
}
