//! File output that is written whole or not at all.
//!
//! What is guaranteed: an output file is either its old content or its
//! complete new content, never a mixture, a partial file or an input of
//! the same command; a set of files one command writes together (a
//! sheet's pages and manifest, a simulated image and its ground truth) is
//! staged whole before any is renamed into place; staged files are synced
//! to disk before the rename; a new file gets the permissions the umask
//! allows and a replaced one keeps its own; and the temporary files of a
//! run that was interrupted are removed (on SIGINT, SIGTERM and SIGHUP by
//! the command line's handler, which it installs through
//! [`before_first_staging`] as the first one is staged, after stopping the
//! programs that fill them, [`StagedWriter`]; after `kill -9` by the next
//! write into the same folder).

use crate::error::WriteError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, Once, OnceLock};

/// Prefix of every temporary file this crate stages an output in.
const TEMP_PREFIX: &str = ".whycode-";

/// A temporary file of ours this old is left over from a run that was
/// killed (staging takes milliseconds: the bytes are ready before it starts).
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// Temporary files staged and not yet renamed or removed, for a signal
/// handler to clean up ([`remove_staged`]).
static STAGED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What runs once, just before the first temporary file is staged.
static BEFORE_FIRST_STAGING: OnceLock<fn()> = OnceLock::new();
static STAGING_BEGUN: Once = Once::new();

/// Sets what runs once, just before this process stages its first
/// temporary file: the command line installs its signal handler there
/// (see [`remove_staged`]), so that a run which writes no file, a photo
/// detected to the terminal, starts no thread to wait for signals. Set
/// once; later calls change nothing.
pub fn before_first_staging(hook: fn()) {
    let _ = BEFORE_FIRST_STAGING.set(hook);
}

/// Programs filling staged files by their paths, by [`StagedWriter`]
/// number.
static WRITERS: Mutex<Vec<(u64, std::process::Child)>> = Mutex::new(Vec::new());
static NEXT_WRITER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A program that fills a staged file by its path (ffmpeg writing a
/// video), held here so that [`remove_staged`] stops it before it removes
/// the file: left running after this process ends, it would create the
/// file again under its temporary name. Killed when dropped unwaited.
pub struct StagedWriter {
    id: u64,
}

impl StagedWriter {
    /// Starts `command` and holds the program here at once, handing
    /// `take` the child to take its pipes out of (the caller writes to the
    /// program and reads its messages itself). A signal's clean-up waits
    /// meanwhile: one that came between the start and the holding would
    /// miss the program, which would then create its file after this
    /// process ended. Starts nothing once that clean-up has begun.
    pub fn spawn<T>(
        command: &mut std::process::Command,
        take: impl FnOnce(&mut std::process::Child) -> T,
    ) -> std::io::Result<(StagedWriter, T)> {
        let mut writers = lock(&WRITERS);
        refuse_once_stopping()?;
        let mut child = command.spawn()?;
        let taken = take(&mut child);
        let id = NEXT_WRITER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        writers.push((id, child));
        Ok((StagedWriter { id }, taken))
    }

    /// Waits for the program to end by itself (its input closed) and
    /// returns how it ended. A signal's clean-up waits meanwhile: the
    /// program may not have opened its file yet.
    pub fn wait(self) -> std::io::Result<std::process::ExitStatus> {
        let mut writers = lock(&WRITERS);
        let at = writers.iter().position(|(id, _)| *id == self.id);
        let Some(at) = at else {
            return Err(std::io::Error::other("the program was stopped"));
        };
        let status = writers[at].1.wait();
        writers.remove(at);
        status
    }
}

impl Drop for StagedWriter {
    fn drop(&mut self) {
        let mut writers = lock(&WRITERS);
        if let Some(at) = writers.iter().position(|(id, _)| *id == self.id) {
            let (_, mut child) = writers.remove(at);
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// A lock that a panic elsewhere does not poison for the clean-up.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|p| p.into_inner())
}

/// Set once [`remove_staged`] has begun: the process is being stopped.
static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a signal's clean-up ([`remove_staged`]) has begun. What fails
/// meanwhile (a write to the ffmpeg it stopped, an ffmpeg that got the
/// terminal's Ctrl-C too) is that stop, not a fault to report: the command
/// line leaves the process's end and exit status to the signal handler.
pub fn stopping() -> bool {
    STOPPING.load(std::sync::atomic::Ordering::SeqCst)
}

/// The error of a file staged or a program started once a signal's
/// clean-up has begun: the process is about to end, and what was started
/// now would outlive it.
fn refuse_once_stopping() -> std::io::Result<()> {
    if stopping() {
        return Err(std::io::Error::other("the run is being stopped"));
    }
    Ok(())
}

/// Stops the programs filling staged files, then removes every temporary
/// file staged and not yet committed: what a signal handler calls before
/// the process ends, since a signal does not unwind and run the temporary
/// files' own clean-up. For the rest of the process nothing is staged and
/// no such program started ([`stopping`]).
pub fn remove_staged() {
    STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
    for (_, child) in lock(&WRITERS).iter_mut() {
        let _ = child.kill();
        let _ = child.wait();
    }
    let staged = lock(&STAGED);
    for path in staged.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// A staged temporary file, listed for [`remove_staged`] while it exists.
struct Staged {
    tmp: Option<tempfile::NamedTempFile>,
    path: PathBuf,
}

impl Staged {
    /// Creates the temporary file `builder` makes in `dir` and lists it,
    /// as one step for a signal's clean-up, which waits meanwhile (a file
    /// created before it and listed after it would be left behind); none
    /// once that clean-up has begun.
    fn create(builder: &tempfile::Builder, dir: &Path) -> std::io::Result<Staged> {
        let mut staged = lock(&STAGED);
        refuse_once_stopping()?;
        let tmp = builder.tempfile_in(dir)?;
        let path = tmp.path().to_path_buf();
        staged.push(path.clone());
        Ok(Staged {
            tmp: Some(tmp),
            path,
        })
    }

    fn file(&mut self) -> &mut std::fs::File {
        self.tmp
            .as_mut()
            .expect("a staged file is present until committed")
            .as_file_mut()
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        lock(&STAGED).retain(|p| *p != self.path);
    }
}

/// Refuses outputs that are inputs of the same command (compared as the
/// files they are, so `./fam.json`, `fam.json` and a link to it are one),
/// or that appear twice among the outputs. Called before any work, with
/// every path a command reads and every path it would write, derived names
/// (the manifest beside a sheet, the ground truth beside an image)
/// included. The inputs are `inputs` and every file read so far under an
/// open [`crate::input::Recording`] (with the pages a manifest read lists),
/// so a file the command reads counts even when no flag named it.
pub fn check_outputs(inputs: &[&Path], outputs: &[&Path]) -> Result<(), WriteError> {
    let read: Vec<(PathBuf, &Path)> = inputs
        .iter()
        .filter_map(|p| std::fs::canonicalize(p).ok().map(|c| (c, *p)))
        .collect();
    let mut written: Vec<PathBuf> = Vec::new();
    for &output in outputs {
        let real = real_path(output);
        if let Some((_, input)) = read.iter().find(|(c, _)| *c == real) {
            return Err(WriteError::WouldOverwriteInput {
                output: output.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
        refuse_recorded_input(output, &real)?;
        if written.contains(&real) {
            return Err(WriteError::SameFileTwice {
                output: output.to_path_buf(),
            });
        }
        written.push(real);
    }
    Ok(())
}

/// Refuses `output` (resolved to `real`) when it is a file the running
/// command has read: checked again by every writer, so an input stays
/// whole even when a command's early check could not know it yet.
fn refuse_recorded_input(output: &Path, real: &Path) -> Result<(), WriteError> {
    match crate::input::recorded_as(real) {
        Some(input) => Err(WriteError::WouldOverwriteInput {
            output: output.to_path_buf(),
            input,
        }),
        None => Ok(()),
    }
}

/// The file a path names once links and `.`/`..` are resolved, also for a
/// file that does not exist yet (its folder resolved, its name kept).
fn real_path(path: &Path) -> PathBuf {
    let target = resolve_links(path);
    if let Ok(real) = std::fs::canonicalize(&target) {
        return real;
    }
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (std::fs::canonicalize(dir), target.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => target,
    }
}

/// Removes temporary files of ours in `dir` left by a run that was killed
/// before it could clean up; only names of our own pattern, and only old
/// ones, so a concurrent run's staging is never touched.
fn sweep_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else {
            continue;
        };
        let ours = name
            .strip_prefix(TEMP_PREFIX)
            .is_some_and(|rest| rest.len() == 6 && rest.bytes().all(|b| b.is_ascii_alphanumeric()));
        if !ours {
            continue;
        }
        let stale = entry
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > STALE_AFTER);
        if stale {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Writes a file through a temporary file in the same folder and a rename,
/// so that a failure never leaves a partial file under `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], with the content produced by a writer callback.
///
/// A symbolic link is followed, so the file it points at is replaced and the
/// link kept. A FIFO, device or socket (`/dev/stdout`, `/dev/null`, a pipe)
/// cannot be renamed over without destroying it, so the content is produced
/// in memory first and then written to it in one go.
pub fn write_atomic_with(
    path: &Path,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let fail = |e| WriteError::io(path, without_temp_path(e));
    match destination(path)? {
        Destination::Special(target) => {
            let mut bytes = Vec::new();
            produce(&mut bytes).map_err(fail)?;
            write_in_place(path, &target, &bytes)
        }
        Destination::Regular(target) => {
            let mut tmp = stage_beside(path, &target)?;
            {
                let mut buffered = std::io::BufWriter::new(tmp.file());
                produce(&mut buffered).map_err(fail)?;
                buffered.flush().map_err(fail)?;
            }
            commit(path, &target, tmp)
        }
    }
}

/// An output that a program fills by its path (ffmpeg writing a video):
/// staged beside the target like [`write_atomic`]'s, renamed into place by
/// [`StagedFile::commit`], removed when dropped uncommitted. A FIFO or
/// device target is handed over as it is.
pub struct StagedFile {
    path: PathBuf,
    target: PathBuf,
    staged: Option<Staged>,
}

impl StagedFile {
    /// Stages an output for `path`.
    pub fn new(path: &Path) -> Result<StagedFile, WriteError> {
        let (target, staged) = match destination(path)? {
            Destination::Special(target) => (target, None),
            Destination::Regular(target) => {
                let staged = stage_beside(path, &target)?;
                (target, Some(staged))
            }
        };
        Ok(StagedFile {
            path: path.to_path_buf(),
            target,
            staged,
        })
    }

    /// Where to write: the temporary file (or the device itself).
    pub fn path(&self) -> &Path {
        match &self.staged {
            Some(staged) => &staged.path,
            None => &self.target,
        }
    }

    /// Renames the finished file into place.
    pub fn commit(mut self) -> Result<(), WriteError> {
        match self.staged.take() {
            Some(staged) => commit(&self.path, &self.target, staged),
            None => Ok(()),
        }
    }
}

/// Writes several files as one: each is staged in a temporary file beside
/// its target, and only when all are staged are they renamed into place. A
/// failure while staging (a full disk, a missing folder) or while writing
/// to a device leaves every regular target as it was, old outputs included.
pub fn write_all_atomic(files: &[(PathBuf, Vec<u8>)]) -> Result<(), WriteError> {
    let mut staged = Vec::with_capacity(files.len());
    let mut in_place = Vec::new();
    for (path, bytes) in files {
        match destination(path)? {
            Destination::Special(target) => in_place.push((path, target, bytes)),
            Destination::Regular(target) => {
                let mut tmp = stage_beside(path, &target)?;
                let file = tmp.file();
                file.write_all(bytes)
                    .and_then(|()| file.flush())
                    .map_err(|e| WriteError::io(path, without_temp_path(e)))?;
                staged.push((path, target, tmp));
            }
        }
    }
    // Devices and pipes cannot be staged, so they are written before any
    // staged file is renamed into place: when one fails (a link to
    // /dev/full), the temporary files are dropped and no target changes.
    for (path, target, bytes) in in_place {
        write_in_place(path, &target, bytes)?;
    }
    let _locks = lock_folders(&staged)?;
    for (path, target, tmp) in staged {
        commit(path, &target, tmp)?;
    }
    Ok(())
}

/// Exclusive locks on the folders a set of staged files is renamed into,
/// held until dropped: two runs writing the same set at once (four
/// `simulate`s with one `-o`) then leave one run's files whole, never one
/// run's image beside another's ground truth. Taken in path order, so two
/// runs never wait for each other's second folder.
fn lock_folders(staged: &[(&PathBuf, PathBuf, Staged)]) -> Result<Vec<std::fs::File>, WriteError> {
    if staged.len() < 2 {
        return Ok(Vec::new());
    }
    let mut folders: Vec<(PathBuf, &Path)> = staged
        .iter()
        .map(|(path, target, _)| {
            let dir = match target.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            (
                std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf()),
                path.as_path(),
            )
        })
        .collect();
    folders.sort();
    folders.dedup_by(|a, b| a.0 == b.0);
    folders
        .into_iter()
        .map(|(dir, path)| {
            let folder = std::fs::File::open(&dir).map_err(|e| WriteError::io(path, e))?;
            folder.lock().map_err(|e| WriteError::io(path, e))?;
            Ok(folder)
        })
        .collect()
}

/// Output files for annotated copies of `inputs`, one per distinct input,
/// in input order: `DIR/<stem>.annotated.png`, with `-2`, `-3`, ... before
/// `.annotated` when two inputs share a stem (two phones' IMG_0001) or when
/// the name is taken by one of the inputs themselves (annotating
/// `view.annotated.png` beside `view.png`). An input is never an output.
pub fn annotation_paths(dir: &Path, inputs: &[PathBuf]) -> Vec<(PathBuf, PathBuf)> {
    // Compared canonically, so `./view.png` and `view.png` are one file.
    let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let taken_by_inputs: std::collections::HashSet<PathBuf> =
        inputs.iter().map(|p| same_file(p)).collect();
    let dir_real = same_file(dir);
    let mut used = std::collections::HashSet::new();
    let mut out: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for input in inputs {
        if !seen.insert(input.clone()) {
            continue;
        }
        let stem = input
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        let mut name = format!("{stem}.annotated.png");
        let mut k = 2;
        while taken_by_inputs.contains(&dir_real.join(&name)) || !used.insert(name.clone()) {
            name = format!("{stem}-{k}.annotated.png");
            k += 1;
        }
        out.push((input.clone(), dir.join(name)));
    }
    out
}

/// Where an output's bytes end up.
enum Destination {
    /// A FIFO, device or socket: written to, never replaced.
    Special(PathBuf),
    /// A regular file, existing or not: replaced by a rename.
    Regular(PathBuf),
}

fn destination(path: &Path) -> Result<Destination, WriteError> {
    refuse_recorded_input(path, &real_path(path))?;
    let target = resolve_links(path);
    match std::fs::metadata(&target) {
        Ok(meta) if meta.is_dir() => Err(WriteError::IsAFolder {
            path: path.to_path_buf(),
        }),
        Ok(meta) if !meta.is_file() => Ok(Destination::Special(target)),
        _ => Ok(Destination::Regular(target)),
    }
}

fn write_in_place(path: &Path, target: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let fail = |e| WriteError::io(path, without_temp_path(e));
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .open(target)
        .map_err(fail)?;
    file.write_all(bytes)
        .and_then(|()| file.flush())
        .map_err(fail)
}

/// Fails early, before any work, when the output's folder is missing or is
/// not a folder at all (a path under a regular file).
pub fn check_output_dir(path: &Path) -> Result<(), WriteError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match folder_problem(path, dir) {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

fn folder_problem(path: &Path, dir: &Path) -> Option<WriteError> {
    if dir.is_dir() {
        return None;
    }
    // The nearest existing ancestor tells a missing folder from a file in the way.
    let blocker = dir.ancestors().find(|a| a.exists() && !a.is_dir());
    Some(match blocker {
        Some(file) => WriteError::FileInTheWay {
            path: path.to_path_buf(),
            file: file.to_path_buf(),
        },
        None => WriteError::NoFolder {
            path: path.to_path_buf(),
            dir: dir.to_path_buf(),
        },
    })
}

/// A temporary file in the target's folder, so that the final rename stays
/// on one file system and is atomic.
fn stage_beside(path: &Path, target: &Path) -> Result<Staged, WriteError> {
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if let Some(err) = folder_problem(path, dir) {
        return Err(err);
    }
    sweep_stale(dir);
    if let Some(hook) = BEFORE_FIRST_STAGING.get() {
        STAGING_BEGUN.call_once(hook);
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(TEMP_PREFIX).rand_bytes(6);
    // Created as an ordinary file would be, so the umask decides who may
    // read it (tempfile's own default is private to the owner).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    Staged::create(&builder, dir).map_err(|e| WriteError::io(path, without_temp_path(e)))
}

fn commit(path: &Path, target: &Path, mut staged: Staged) -> Result<(), WriteError> {
    let fail = |e| WriteError::io(path, without_temp_path(e));
    // A file replaced keeps its permissions (a shared 0666 log stays shared).
    if let Ok(old) = std::fs::metadata(target) {
        staged
            .file()
            .set_permissions(old.permissions())
            .map_err(fail)?;
    }
    // On disk before the rename: after a crash the name holds the old
    // content or the new, not an empty file.
    staged.file().sync_all().map_err(fail)?;
    let tmp = staged.tmp.take().expect("committed once");
    tmp.persist(target).map_err(|e| fail(e.error))?;
    Ok(())
}

/// Follows a chain of symbolic links (also a dangling one, whose target is
/// then created), so that the rename replaces the file and not the link.
fn resolve_links(path: &Path) -> PathBuf {
    let mut current = path.to_path_buf();
    // A bound, because a link loop would otherwise never end.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => match std::fs::read_link(&current) {
                Ok(next) if next.is_absolute() => current = next,
                Ok(next) => {
                    current = current.parent().map(|p| p.join(&next)).unwrap_or(next);
                }
                Err(_) => return current,
            },
            _ => return current,
        }
    }
    current
}

/// The temporary file's name means nothing to a user and would only make
/// them look for a file that never appears, so it is cut from OS errors.
fn without_temp_path(err: std::io::Error) -> std::io::Error {
    let text = err.to_string();
    match text.find(" at path ") {
        Some(cut) => std::io::Error::new(err.kind(), text[..cut].to_string()),
        None => err,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hook_runs_once_as_the_first_file_is_staged() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static RUNS: AtomicUsize = AtomicUsize::new(0);
        fn count() {
            RUNS.fetch_add(1, Ordering::SeqCst);
        }
        before_first_staging(count);
        let dir = tempfile::tempdir().unwrap();
        write_atomic(&dir.path().join("a.txt"), b"a").unwrap();
        assert_eq!(RUNS.load(Ordering::SeqCst), 1);
        let staged = StagedFile::new(&dir.path().join("b.txt")).unwrap();
        write_atomic(&dir.path().join("c.txt"), b"c").unwrap();
        drop(staged);
        assert_eq!(RUNS.load(Ordering::SeqCst), 1);
    }

    #[test]
    fn concurrent_writers_of_one_set_leave_one_writers_files() {
        let dir = tempfile::tempdir().unwrap();
        let (image, truth) = (dir.path().join("view.png"), dir.path().join("view.json"));
        for round in 0..40 {
            let barrier = std::sync::Barrier::new(4);
            std::thread::scope(|scope| {
                for writer in 0..4u8 {
                    let (image, truth, barrier) = (&image, &truth, &barrier);
                    scope.spawn(move || {
                        // Large enough that staging and renaming overlap.
                        let bytes = vec![writer; 256 * 1024];
                        barrier.wait();
                        write_all_atomic(&[(image.clone(), bytes.clone()), (truth.clone(), bytes)])
                            .unwrap();
                    });
                }
            });
            let (a, b) = (
                std::fs::read(&image).unwrap(),
                std::fs::read(&truth).unwrap(),
            );
            assert_eq!(
                a[0], b[0],
                "round {round}: image of writer {}, truth of writer {}",
                a[0], b[0]
            );
        }
    }

    #[test]
    fn symlink_is_followed_and_kept() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("real.txt");
        let link = dir.path().join("link.txt");
        std::fs::write(&target, "old").unwrap();
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("real.txt", &link).unwrap();
            write_atomic(&link, b"new").unwrap();
            assert!(std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink());
            assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        }
    }

    #[cfg(unix)]
    #[test]
    fn fifo_is_written_to_not_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !matches!(made, Ok(s) if s.success()) {
            eprintln!("skipped: mkfifo is not available");
            return;
        }
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        write_atomic(&fifo, b"through the pipe").unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
        assert!(!kind.is_file(), "the FIFO was replaced by a regular file");
    }

    #[test]
    fn missing_folder_is_named_without_the_temporary_file() {
        let err = write_atomic(Path::new("/nonexistent-whycode-dir/f.json"), b"x").unwrap_err();
        let text = format!("{err:#}");
        assert!(text.contains("/nonexistent-whycode-dir"), "{text}");
        assert!(!text.contains(".whycode-"), "{text}");
    }

    #[test]
    fn a_failing_set_of_files_leaves_the_old_outputs_alone() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("sheet.pdf");
        std::fs::write(&good, "old pdf").unwrap();
        let files = vec![
            (good.clone(), b"new pdf".to_vec()),
            (dir.path().join("missing/sheet.json"), b"{}".to_vec()),
        ];
        assert!(write_all_atomic(&files).is_err());
        assert_eq!(std::fs::read_to_string(&good).unwrap(), "old pdf");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "temporary files left behind: {left:?}");
    }

    #[test]
    fn annotations_never_take_an_input_name() {
        let dir = tempfile::tempdir().unwrap();
        let view = dir.path().join("view.png");
        let already = dir.path().join("view.annotated.png");
        std::fs::write(&view, "x").unwrap();
        std::fs::write(&already, "x").unwrap();
        let other = dir.path().join("sub/view.png");
        let names = annotation_paths(dir.path(), &[view.clone(), already.clone(), other]);
        let files: Vec<String> = names
            .iter()
            .map(|(_, out)| out.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            files,
            [
                "view-2.annotated.png",
                "view.annotated.annotated.png",
                "view-3.annotated.png"
            ]
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_full_device_among_the_files_leaves_the_others_alone() {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("m.json");
        std::fs::write(&manifest, "old manifest").unwrap();
        let pages = dir.path().join("m.pdf");
        std::os::unix::fs::symlink("/dev/full", &pages).unwrap();
        let files = vec![
            (pages, b"new pdf".to_vec()),
            (manifest.clone(), b"new manifest".to_vec()),
        ];
        let err = write_all_atomic(&files).unwrap_err();
        assert!(format!("{err:#}").contains("m.pdf"), "{err:#}");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), "old manifest");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn a_path_under_a_regular_file_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("plain");
        std::fs::write(&file, "x").unwrap();
        let err = write_atomic(&file.join("out.png"), b"x").unwrap_err();
        let text = format!("{err:#}");
        assert!(text.contains("plain/out.png"), "{text}");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    }

    #[test]
    fn folder_as_output_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let err = write_atomic(dir.path(), b"x").unwrap_err();
        assert!(format!("{err:#}").contains("is a folder"));
    }
}
