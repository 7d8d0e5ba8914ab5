//! Recorded runs read as one stream of frames: ROS 2 bags (MCAP, rosbag2's
//! default storage; [`bag`]) and video files (through the `ffmpeg` program;
//! [`video`]). Each frame comes with its index in the stream, its stamp and,
//! for bags, its topic and the camera the bag's camera_info describes.
//! [`output`] writes the detections back as a bag in the ROS 2 node's
//! layout; [`summary`] tallies a stream's markers. Feature `recordings`.

pub mod bag;
pub mod output;
pub mod summary;
pub mod video;

use crate::camera::Camera;
use crate::ros::image::FrameError;
use image::GrayImage;
use std::path::{Path, PathBuf};

pub use summary::Summary;

/// Video file extensions (any codec ffmpeg decodes).
pub const VIDEO_EXTENSIONS: [&str; 5] = ["mp4", "mkv", "avi", "mov", "webm"];

/// What to read of a recording; built by [`crate::spec::RecordingSpec`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadOptions {
    /// A bag's image topic; needed when it has several.
    pub topic: Option<String>,
    /// Keep every n-th frame (1: all).
    pub every: u64,
    /// Skip the frames before this time, nanoseconds from the recording's
    /// first frame.
    pub start_ns: Option<i64>,
    /// Stop after this time, nanoseconds from the recording's first frame.
    pub end_ns: Option<i64>,
}

impl Default for ReadOptions {
    fn default() -> ReadOptions {
        ReadOptions {
            topic: None,
            every: 1,
            start_ns: None,
            end_ns: None,
        }
    }
}

/// One frame of a recording.
#[derive(Debug, Clone)]
pub struct Frame {
    /// 0-based index in the stream (within `--start`/`--end`, counted before
    /// thinning: with every 5th frame, 0, 5, 10, ...).
    pub index: u64,
    /// A bag's header stamp, or a video's presentation time, nanoseconds.
    pub stamp_ns: i64,
    /// The bag topic it came from.
    pub topic: Option<String>,
    /// The camera frame the image header names (empty for videos).
    pub frame_id: String,
    /// The pixels, 8-bit grey.
    pub image: GrayImage,
    /// The newest valid calibration from the bag's camera_info beside the
    /// image topic, at its own size.
    pub camera: Option<Camera>,
}

/// Which kind of recording a path is, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// An MCAP file.
    Bag,
    /// A video file.
    Video,
}

impl Kind {
    /// The kind of recording `path` names, or `None` for anything else
    /// (an image, a folder).
    pub fn of(path: &Path) -> Option<Kind> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        if ext == "mcap" {
            Some(Kind::Bag)
        } else if VIDEO_EXTENSIONS.contains(&ext.as_str()) {
            Some(Kind::Video)
        } else {
            None
        }
    }
}

/// A recording that cannot be read; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file cannot be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The recording.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A bag that is cut short or damaged.
    #[error("{}: truncated or corrupt bag: {problem}", path.display())]
    CorruptBag {
        /// The bag.
        path: PathBuf,
        /// What the MCAP reader found.
        problem: String,
    },
    /// A bag without sensor_msgs Image or CompressedImage messages.
    #[error("{}: no image topic (sensor_msgs/msg/Image or CompressedImage){}", path.display(), listed(topics))]
    NoImageTopic {
        /// The bag.
        path: PathBuf,
        /// The topics it has, with their types.
        topics: Vec<String>,
    },
    /// A bag with several image topics and none chosen.
    #[error("{}: several image topics, choose one: {}", path.display(), topics.join(", "))]
    SeveralImageTopics {
        /// The bag.
        path: PathBuf,
        /// The image topics.
        topics: Vec<String>,
    },
    /// The chosen topic is not an image topic of the bag.
    #[error("{}: no image topic {topic}; its image topics: {}", path.display(), topics.join(", "))]
    UnknownTopic {
        /// The bag.
        path: PathBuf,
        /// The topic asked for.
        topic: String,
        /// The image topics there are.
        topics: Vec<String>,
    },
    /// A message that is not what its channel says, or an image in an
    /// encoding that is not read.
    #[error("{}: {topic}, message {message}: {problem}", path.display())]
    BadMessage {
        /// The bag.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// 0-based index of the message on its topic.
        message: u64,
        /// What is wrong.
        problem: String,
    },
    /// A raw image the detector cannot read (an unknown encoding, a data
    /// length that does not match).
    #[error("{}: {topic}, frame {frame}: {problem}", path.display())]
    BadImage {
        /// The bag.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// The frame's index.
        frame: u64,
        /// What is wrong.
        problem: FrameError,
    },
    /// The `ffmpeg` program is not installed.
    #[error(
        "{}: reading videos needs the ffmpeg program, which is not installed \
         (Debian/Ubuntu: apt-get install ffmpeg; macOS: brew install ffmpeg; \
         or set WHYCODE_FFMPEG to its path)",
        path.display()
    )]
    FfmpegMissing {
        /// The video.
        path: PathBuf,
    },
    /// The recording is not a regular file (a FIFO, a device, a folder).
    #[error(transparent)]
    File(#[from] crate::error::LoadError),
    /// `--start` (and `--end`) leave no frame: past the recording's end, or
    /// a window between two frames.
    #[error("{}: no frame {}", path.display(), window_words(*start_ns, *end_ns))]
    EmptyWindow {
        /// The recording.
        path: PathBuf,
        /// The window's start, nanoseconds from the first frame.
        start_ns: Option<i64>,
        /// The window's end, nanoseconds from the first frame.
        end_ns: Option<i64>,
    },
    /// ffmpeg could not read the video (or write one).
    #[error("{}: {problem}", path.display())]
    Video {
        /// The video.
        path: PathBuf,
        /// ffmpeg's own words.
        problem: String,
    },
}

/// Opens a recording as a regular file (never a FIFO or device, which
/// would wait for a writer or never end) and remembers it as an input.
fn open_file(path: &Path) -> Result<std::fs::File, RecordingError> {
    use crate::error::{FileKind, LoadError, LoadProblem};
    match crate::input::open(path, FileKind::Recording) {
        Ok((file, _)) => Ok(file),
        Err(LoadError {
            problem: LoadProblem::Read(source),
            ..
        }) => Err(RecordingError::Io {
            path: path.to_path_buf(),
            source,
        }),
        Err(err) => Err(err.into()),
    }
}

/// "from 1:00 to 1:30 into it", "from 1:00 on", "up to 0:05".
fn window_words(start_ns: Option<i64>, end_ns: Option<i64>) -> String {
    let at = |ns: i64| {
        let seconds = ns as f64 / 1e9;
        if seconds >= 60.0 {
            let minutes = (seconds / 60.0).floor();
            format!("{minutes}:{:06.3}", seconds - 60.0 * minutes)
        } else {
            format!("{} s", crate::units::format_number(seconds))
        }
    };
    match (start_ns, end_ns) {
        (Some(s), Some(e)) => format!("between {} and {}", at(s), at(e)),
        (Some(s), None) => format!("at or after {}", at(s)),
        (None, Some(e)) => format!("up to {}", at(e)),
        (None, None) => "at all".to_string(),
    }
}

fn listed(topics: &[String]) -> String {
    if topics.is_empty() {
        "; it holds no messages".into()
    } else {
        format!("; its topics: {}", topics.join(", "))
    }
}

/// CompressedImages that did not decode: skipped, counted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Skipped {
    /// How many frames were skipped.
    pub count: u64,
    /// The first skipped frame's index and why.
    pub first: Option<(u64, String)>,
    /// camera_info messages refused (no image size, not a real lens), and
    /// the first one's reason: frames before a sound one have no poses.
    pub refused_calibrations: u64,
    /// Why the first refused camera_info was refused.
    pub first_refused_calibration: Option<String>,
}

impl Skipped {
    fn add(&mut self, index: u64, reason: String) {
        self.count += 1;
        if self.first.is_none() {
            self.first = Some((index, reason));
        }
    }
}

/// An open recording.
pub enum Recording {
    /// A bag, mapped into memory.
    Bag(bag::Bag),
    /// A video, read when its frames are asked for.
    Video(PathBuf),
}

impl Recording {
    /// Opens `path` as the recording [`Kind::of`] says it is: a bag's
    /// index is read now (a truncated bag fails here), a video is only
    /// checked to exist.
    pub fn open(path: &Path) -> Result<Recording, RecordingError> {
        match Kind::of(path) {
            Some(Kind::Bag) => Ok(Recording::Bag(bag::Bag::open(path)?)),
            _ => {
                // A FIFO would leave ffmpeg waiting for a writer forever.
                open_file(path)?;
                Ok(Recording::Video(path.to_path_buf()))
            }
        }
    }

    /// The frames, in order.
    pub fn frames(&self, options: &ReadOptions) -> Result<Frames<'_>, RecordingError> {
        let (source, path) = match self {
            Recording::Bag(bag) => (Source::Bag(Box::new(bag.frames(options)?)), bag.path()),
            Recording::Video(path) => (
                Source::Video(video::VideoFrames::open(path, options)?),
                path.as_path(),
            ),
        };
        Ok(Frames {
            source,
            path: path.to_path_buf(),
            window: (options.start_ns.is_some() || options.end_ns.is_some())
                .then_some((options.start_ns, options.end_ns)),
            given: 0,
        })
    }
}

/// A recording's frames, one at a time. A window (`--start`, `--end`) that
/// holds no frame ends the stream with [`RecordingError::EmptyWindow`],
/// so a run past the recording's end writes nothing rather than empty
/// outputs.
pub struct Frames<'a> {
    source: Source<'a>,
    path: PathBuf,
    window: Option<(Option<i64>, Option<i64>)>,
    given: u64,
}

enum Source<'a> {
    Bag(Box<bag::BagFrames<'a>>),
    Video(video::VideoFrames),
}

impl Frames<'_> {
    /// How many frames the stream will give, when the recording says
    /// (a bag's message count, a video's duration times its rate).
    pub fn expected(&self) -> Option<u64> {
        match &self.source {
            Source::Bag(b) => b.expected(),
            Source::Video(v) => v.expected(),
        }
    }

    /// The frames skipped so far (CompressedImages that do not decode).
    pub fn skipped(&self) -> &Skipped {
        match &self.source {
            Source::Bag(b) => b.skipped(),
            Source::Video(v) => v.skipped(),
        }
    }
}

impl Iterator for Frames<'_> {
    type Item = Result<Frame, RecordingError>;

    fn next(&mut self) -> Option<Self::Item> {
        let next = match &mut self.source {
            Source::Bag(b) => b.next(),
            Source::Video(v) => v.next(),
        };
        match (&next, self.window) {
            (Some(Ok(_)), _) => self.given += 1,
            (None, Some((start_ns, end_ns))) if self.given == 0 => {
                self.window = None;
                return Some(Err(RecordingError::EmptyWindow {
                    path: self.path.clone(),
                    start_ns,
                    end_ns,
                }));
            }
            _ => {}
        }
        next
    }
}

/// The next item of a stream that ends at its first error: `done` is set
/// once `next` gave an error or nothing.
fn fused<T, E>(
    done: &mut bool,
    next: impl FnOnce() -> Result<Option<T>, E>,
) -> Option<Result<T, E>> {
    if *done {
        return None;
    }
    let result = next().transpose();
    if !matches!(result, Some(Ok(_))) {
        *done = true;
    }
    result
}

/// Whether a frame at `offset_ns` from the first one falls in the window.
fn in_window(options: &ReadOptions, offset_ns: i64) -> Window {
    if options.start_ns.is_some_and(|s| offset_ns < s) {
        Window::Before
    } else if options.end_ns.is_some_and(|e| offset_ns > e) {
        Window::After
    } else {
        Window::In
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Window {
    Before,
    In,
    After,
}
