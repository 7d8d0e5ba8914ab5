//! Errors shared by every reader, and the one-line text every front end
//! shows for any error.

use std::path::{Path, PathBuf};

/// The kinds of file the library reads, as their errors name them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A photo or rendered image.
    Image,
    /// A family file (`whycode ids --format json`).
    Family,
    /// A sheet's manifest.
    Manifest,
    /// A camera calibration.
    Camera,
    /// A page template.
    Template,
    /// A board: a sheet's manifest or a marker bundle.
    Board,
    /// An arena file (`whycode arena`).
    Arena,
    /// A recorded run: a bag or a video.
    Recording,
    /// A ROS 2 params file (the node's `--params-file`).
    Params,
}

impl FileKind {
    /// The kind in words, as in "cannot read camera calibration".
    pub fn noun(self) -> &'static str {
        match self {
            FileKind::Image => "image",
            FileKind::Family => "family file",
            FileKind::Manifest => "sheet manifest",
            FileKind::Camera => "camera calibration",
            FileKind::Template => "template",
            FileKind::Board => "board",
            FileKind::Arena => "arena file",
            FileKind::Recording => "recording",
            FileKind::Params => "params file",
        }
    }
}

/// Why a file (or text handed over in memory) could not be used: one shape
/// for every reader, so that a front end tells a file it could not read
/// from one whose contents are wrong by [`LoadError::is_io`], and every
/// message starts with the file's name.
#[derive(Debug)]
pub struct LoadError {
    /// The file; `None` for text handed over without a name.
    pub path: Option<PathBuf>,
    /// What the file was read as.
    pub kind: FileKind,
    /// What is wrong.
    pub problem: LoadProblem,
}

/// What is wrong with a file a reader was given.
#[derive(Debug, thiserror::Error)]
pub enum LoadProblem {
    /// The operating system could not read it.
    #[error("{0}")]
    Read(#[source] std::io::Error),
    /// Its contents are not what the reader takes, in words.
    #[error("{0}")]
    Invalid(String),
    /// An image the decoders do not understand, or a damaged one.
    #[error("{0}")]
    Decode(#[source] image::ImageError),
    /// An image larger than the reader accepts: refused before decoding,
    /// so a hostile header cannot exhaust memory.
    #[error(
        "image of {width}x{height} pixels is larger than the supported {} px a side and {} megapixels",
        limit.max_side,
        limit.max_pixels / 1_000_000
    )]
    TooLarge {
        /// Width in the header, pixels.
        width: u32,
        /// Height in the header, pixels.
        height: u32,
        /// What the reader accepts.
        limit: crate::limits::SizeLimit,
    },
}

impl LoadError {
    /// `path` could not be used as a `kind`.
    pub fn new(path: &Path, kind: FileKind, problem: LoadProblem) -> LoadError {
        LoadError {
            path: Some(path.to_path_buf()),
            kind,
            problem,
        }
    }

    /// `path` could not be read.
    pub fn read(path: &Path, kind: FileKind, err: std::io::Error) -> LoadError {
        LoadError::new(path, kind, LoadProblem::Read(err))
    }

    /// Text of a `kind` handed over without a file is wrong.
    pub fn invalid_text(kind: FileKind, problem: impl Into<String>) -> LoadError {
        LoadError {
            path: None,
            kind,
            problem: LoadProblem::Invalid(problem.into()),
        }
    }

    /// The same error, now naming the file its text came from.
    pub fn in_file(mut self, path: &Path) -> LoadError {
        self.path = Some(path.to_path_buf());
        self
    }

    /// Whether the file could not be read at all (an `OSError` to Python)
    /// rather than read and found wrong.
    pub fn is_io(&self) -> bool {
        matches!(self.problem, LoadProblem::Read(_))
    }
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(path) = &self.path {
            write!(f, "{}: ", path.display())?;
        }
        match &self.problem {
            LoadProblem::Read(err) => write!(f, "cannot read {}: {err}", self.kind.noun()),
            problem => write!(f, "{problem}"),
        }
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.problem)
    }
}

/// Why an output could not be written. Every message starts by naming the
/// output.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The output is also an input of the same command.
    #[error("{}: would overwrite {}, which this command reads; write the output elsewhere", output.display(), input.display())]
    WouldOverwriteInput {
        /// The output.
        output: PathBuf,
        /// The input it would replace.
        input: PathBuf,
    },
    /// Two outputs of one command name the same file.
    #[error("{}: two outputs of this command would land in the same file", output.display())]
    SameFileTwice {
        /// The second output naming it.
        output: PathBuf,
    },
    /// The output names a folder.
    #[error("cannot write {}: it is a folder", path.display())]
    IsAFolder {
        /// The output.
        path: PathBuf,
    },
    /// A regular file stands where the output's folder should be.
    #[error("cannot write {}: {} is a file, not a folder", path.display(), file.display())]
    FileInTheWay {
        /// The output.
        path: PathBuf,
        /// The file in the way.
        file: PathBuf,
    },
    /// The output's folder does not exist.
    #[error("cannot write {}: folder {} does not exist", path.display(), dir.display())]
    NoFolder {
        /// The output.
        path: PathBuf,
        /// The missing folder.
        dir: PathBuf,
    },
    /// The operating system refused the write.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The output.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
}

impl WriteError {
    /// The operating system refused writing `path`.
    pub fn io(path: &Path, source: std::io::Error) -> WriteError {
        WriteError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Returns early from a reader's checks with the problem in words, a
/// [`LoadProblem::Invalid`] for the reader to put its file's name to.
macro_rules! refuse {
    ($($arg:tt)*) => {
        return Err($crate::error::LoadProblem::Invalid(format!($($arg)*)))
    };
}
pub(crate) use refuse;

/// An error's causes joined with ": " on one line, white space folded, a
/// cause its parent already quotes (image decoding errors do) left out.
/// This is the line the command line prints after `whycode: error:`, the
/// message of a Python `WhycodeError` and of the browser page's errors.
pub fn one_line(err: &(dyn std::error::Error + 'static)) -> String {
    let mut parts: Vec<String> = Vec::new();
    let chain = std::iter::successors(Some(err), |e| e.source());
    for cause in chain {
        let text = shorten_words(
            &cause
                .to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" "),
        );
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

/// The longest run without white space an error quotes whole: a 50 MB string
/// in a family file is shown by its ends, not echoed to the terminal.
const MAX_QUOTED: usize = 100;

/// `text` with every run of more than `MAX_QUOTED` characters between
/// spaces cut to its first and last few, and how long it was.
pub fn shorten_words(text: &str) -> String {
    text.split(' ')
        .map(|word| {
            let count = word.chars().count();
            if count <= MAX_QUOTED {
                return word.to_string();
            }
            let head: String = word.chars().take(MAX_QUOTED / 2).collect();
            let tail: String = word.chars().skip(count - 20).collect();
            format!("{head}...{tail} ({count} characters)")
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_huge_quoted_value_is_cut_to_its_ends() {
        let huge = "x".repeat(50_000_000);
        let err = super::LoadError::new(
            std::path::Path::new("fam.json"),
            super::FileKind::Family,
            super::LoadProblem::Invalid(format!("invalid type: string \"{huge}\", expected u32")),
        );
        let line = super::one_line(&err);
        assert!(line.len() < 300, "{}", line.len());
        assert!(
            line.starts_with("fam.json: invalid type: string \"xxxx"),
            "{line}"
        );
        assert!(line.ends_with("characters) expected u32"), "{line}");
    }
}
