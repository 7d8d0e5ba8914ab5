//! What `whycode detect` reads, as streams of frames: an image on its own,
//! a folder's frames in name order, a ROS 2 bag or a video. Every input
//! becomes a [`Stream`], and every stream's frames come as [`Input`]s, so
//! one frame loop (`detect::run_stream`) serves them all.

use anyhow::{anyhow, bail, Context, Result};
use image::GrayImage;
use std::path::{Path, PathBuf};
use whycode::camera::Camera;
use whycode::image_io::load_gray;
use whycode::recording::{Kind, ReadOptions, Recording, Skipped};
use whycode::session::report::StreamPosition;

/// Image file extensions read from folders.
const IMAGE_EXTENSIONS: [&str; 9] = [
    "png", "jpg", "jpeg", "pgm", "ppm", "pnm", "pbm", "bmp", "pam",
];

/// One input's frames.
pub enum Stream {
    /// An image on its own (also each frame of a folder read with
    /// `--no-tracking`).
    Image(PathBuf),
    /// A folder's frames in name order, tracked.
    Folder(Vec<PathBuf>),
    /// A bag or a video, tracked.
    Recording(PathBuf),
}

impl Stream {
    /// The streams `inputs` name, each checked to exist before any work
    /// starts, with the folders listed.
    pub fn list(inputs: &[PathBuf], no_tracking: bool) -> Result<Vec<Stream>> {
        let mut streams = Vec::new();
        for input in inputs {
            let meta = std::fs::metadata(input)
                .with_context(|| format!("{}: cannot read", input.display()))?;
            if !meta.is_dir() {
                streams.push(if names_a_recording(input) {
                    Stream::Recording(input.clone())
                } else {
                    Stream::Image(input.clone())
                });
                continue;
            }
            let frames = folder_frames(input)?;
            if no_tracking {
                streams.extend(frames.into_iter().map(Stream::Image));
            } else {
                streams.push(Stream::Folder(frames));
            }
        }
        Ok(streams)
    }

    /// Whether the stream is a bag or a video.
    pub fn is_recording(&self) -> bool {
        matches!(self, Stream::Recording(_))
    }

    /// Whether a frame that fails leaves the rest of the stream readable:
    /// an image file does, a recording's reader or camera does not.
    pub fn goes_on_after_a_failed_frame(&self) -> bool {
        !self.is_recording()
    }

    /// The image files it reads (none for a recording).
    pub fn files(&self) -> &[PathBuf] {
        match self {
            Stream::Image(path) => std::slice::from_ref(path),
            Stream::Folder(frames) => frames,
            Stream::Recording(_) => &[],
        }
    }

    /// Opens the stream (a bag's index is read here).
    pub fn open(&self) -> Result<Opened<'_>> {
        Ok(match self {
            Stream::Recording(path) => Opened::Recording(path, Recording::open(path)?),
            files => Opened::Files(files.files()),
        })
    }
}

/// A stream opened for reading.
pub enum Opened<'a> {
    Files(&'a [PathBuf]),
    Recording(&'a Path, Recording),
}

impl Opened<'_> {
    /// Its frames, in order.
    pub fn frames(&self, read: &ReadOptions) -> Result<Frames<'_>> {
        Ok(match self {
            Opened::Files(paths) => Frames::Files(paths.iter()),
            Opened::Recording(path, recording) => Frames::Recording {
                shown: path.display().to_string(),
                frames: Box::new(recording.frames(read)?),
            },
        })
    }
}

/// A stream's frames, one at a time.
pub enum Frames<'a> {
    Files(std::slice::Iter<'a, PathBuf>),
    Recording {
        shown: String,
        frames: Box<whycode::recording::Frames<'a>>,
    },
}

/// One frame of any stream.
pub struct Input {
    /// The pixels, 8-bit grey.
    pub image: GrayImage,
    /// The frame's name in reports and messages (its file, or the
    /// recording's).
    pub name: String,
    /// The image file it was read from.
    pub file: Option<PathBuf>,
    /// Where a recorded frame sits in its recording.
    pub recorded: Option<Recorded>,
}

/// What a recording says of one of its frames besides its pixels.
pub struct Recorded {
    /// 0-based index in the stream.
    pub index: u64,
    /// A bag's header stamp, or a video's presentation time, nanoseconds.
    pub stamp_ns: i64,
    /// The bag topic it came from.
    pub topic: Option<String>,
    /// The camera frame the image header names (empty for videos).
    pub frame_id: String,
    /// The calibration from the bag's camera_info.
    pub camera: Option<Camera>,
}

impl Input {
    /// Where the frame sits in its stream, for its report.
    pub fn position(&self) -> Option<StreamPosition> {
        self.recorded.as_ref().map(|r| StreamPosition {
            frame: r.index,
            stamp_ns: r.stamp_ns,
            topic: r.topic.clone(),
        })
    }

    /// The frame's name in a message about it.
    pub fn shown(&self) -> String {
        match &self.recorded {
            Some(r) => format!("{}: frame {}", self.name, r.index),
            None => self.name.clone(),
        }
    }
}

impl Frames<'_> {
    /// How many frames a recording will give, once it says (image files
    /// are counted before any is read: none here).
    pub fn expected(&self) -> Option<u64> {
        match self {
            Frames::Files(_) => None,
            Frames::Recording { frames, .. } => frames.expected(),
        }
    }

    /// A recording's frames skipped so far (CompressedImages that do not
    /// decode); none for files.
    pub fn skipped(&self) -> Option<&Skipped> {
        match self {
            Frames::Files(_) => None,
            Frames::Recording { frames, .. } => Some(frames.skipped()),
        }
    }
}

impl Iterator for Frames<'_> {
    type Item = Result<Input>;

    fn next(&mut self) -> Option<Result<Input>> {
        match self {
            Frames::Files(paths) => {
                let path = paths.next()?;
                Some(load_gray(path).map_err(Into::into).map(|image| Input {
                    image,
                    name: path.display().to_string(),
                    file: Some(path.clone()),
                    recorded: None,
                }))
            }
            Frames::Recording { shown, frames } => {
                Some(frames.next()?.map_err(|e| anyhow!(e)).map(|frame| Input {
                    image: frame.image,
                    name: shown.clone(),
                    file: None,
                    recorded: Some(Recorded {
                        index: frame.index,
                        stamp_ns: frame.stamp_ns,
                        topic: frame.topic,
                        frame_id: frame.frame_id,
                        camera: frame.camera,
                    }),
                }))
            }
        }
    }
}

/// Whether `path` is read as a bag or a video (by its extension; a folder
/// never is).
pub fn names_a_recording(path: &Path) -> bool {
    Kind::of(path).is_some() && !path.is_dir()
}

/// A folder's images in name order.
fn folder_frames(folder: &Path) -> Result<Vec<PathBuf>> {
    let mut frames: Vec<PathBuf> = std::fs::read_dir(folder)
        .with_context(|| format!("{}: cannot list folder", folder.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        // Everything named like a frame is a frame: one that is a folder
        // or a broken link is reported as a failed frame, not skipped
        // without a word.
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    if frames.is_empty() {
        bail!("{}: folder holds no images", folder.display());
    }
    // Cameras and scripts number frames without zero padding as often
    // as with it: frame2 comes before frame10.
    frames.sort_by(|a, b| natural_order(a, b));
    Ok(frames)
}

/// Compares paths with runs of digits taken as numbers ("f2" < "f10");
/// equal numbers with different padding fall back to the plain order.
fn natural_order(a: &Path, b: &Path) -> std::cmp::Ordering {
    fn chunks(text: &str) -> Vec<(bool, &str)> {
        let mut out = Vec::new();
        let mut start = 0;
        let bytes = text.as_bytes();
        for i in 1..=bytes.len() {
            if i == bytes.len() || bytes[i].is_ascii_digit() != bytes[start].is_ascii_digit() {
                out.push((bytes[start].is_ascii_digit(), &text[start..i]));
                start = i;
            }
        }
        out
    }
    let (ta, tb) = (a.to_string_lossy(), b.to_string_lossy());
    let (ca, cb) = (chunks(&ta), chunks(&tb));
    for ((da, xa), (db, xb)) in ca.iter().zip(&cb) {
        let order = if *da && *db {
            let (na, nb) = (xa.trim_start_matches('0'), xb.trim_start_matches('0'));
            na.len().cmp(&nb.len()).then_with(|| na.cmp(nb))
        } else {
            xa.cmp(xb)
        };
        if order.is_ne() {
            return order;
        }
    }
    ca.len().cmp(&cb.len()).then_with(|| ta.cmp(&tb))
}

#[cfg(test)]
mod tests {
    use super::natural_order;
    use std::path::PathBuf;

    #[test]
    fn frames_sort_by_their_numbers() {
        let mut frames: Vec<PathBuf> = [
            "f10.png",
            "f2.png",
            "f1.png",
            "f02b.png",
            "g.png",
            "f0010.png",
        ]
        .iter()
        .map(PathBuf::from)
        .collect();
        frames.sort_by(|a, b| natural_order(a, b));
        let names: Vec<_> = frames.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(
            names,
            [
                "f1.png",
                "f2.png",
                "f02b.png",
                "f0010.png",
                "f10.png",
                "g.png"
            ]
        );
    }
}
