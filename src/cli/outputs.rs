//! The files `whycode detect` writes besides its rows on stdout: each
//! frame's picture with the markers drawn (into a folder, or a video made
//! of a recording's frames) and a recording's detections as a ROS 2 bag.

use super::output;
use super::stream::{Input, Stream};
use anyhow::{anyhow, Context, Result};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use whycode::recording::output::{AnnotatedVideo, DetectionsBag};
use whycode::recording::Kind;
use whycode::ros::describe::describe_frame;
use whycode::ros::msg::{Header, Time};
use whycode::session::report::FrameReport;
use whycode::session::Session;

/// Where the annotated frames go.
pub enum Annotate {
    /// Nowhere.
    None,
    /// Images in a folder.
    Folder(PathBuf),
    /// A video file.
    Video(PathBuf),
}

impl Annotate {
    /// A path with a video's extension is a video, anything else a folder.
    pub fn of(path: Option<&Path>) -> Annotate {
        match path {
            None => Annotate::None,
            Some(p) if Kind::of(p) == Some(Kind::Video) => Annotate::Video(p.to_path_buf()),
            Some(p) => Annotate::Folder(p.to_path_buf()),
        }
    }
}

/// The files a run writes, and the name of every picture.
pub struct Plan {
    pub annotate: Annotate,
    /// The detections bag (one recording).
    pub bag: Option<PathBuf>,
    /// Each image file's picture in the folder, and each recording's
    /// (see [`whycode::io::annotation_paths`]; a recording's pictures are
    /// named by frame after it, when there are several).
    names: HashMap<PathBuf, PathBuf>,
    several_recordings: bool,
}

impl Plan {
    /// The outputs of a run over `streams`, checked against the inputs
    /// (never written over one) and with the folder made.
    pub fn new(annotate: Annotate, bag: Option<PathBuf>, streams: &[Stream]) -> Result<Plan> {
        let recordings: Vec<&Path> = streams
            .iter()
            .filter_map(|s| match s {
                Stream::Recording(path) => Some(path.as_path()),
                _ => None,
            })
            .collect();
        let mut outputs: Vec<&Path> = bag.iter().map(PathBuf::as_path).collect();
        let mut names = HashMap::new();
        match &annotate {
            Annotate::Video(path) => outputs.push(path),
            Annotate::Folder(dir) => {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("{}: cannot create folder", dir.display()))?;
                let read: Vec<PathBuf> = streams
                    .iter()
                    .flat_map(|s| match s {
                        Stream::Recording(path) => std::slice::from_ref(path),
                        files => files.files(),
                    })
                    .cloned()
                    .collect();
                names = whycode::io::annotation_paths(dir, &read)
                    .into_iter()
                    .collect();
            }
            Annotate::None => {}
        }
        whycode::io::check_outputs(&recordings, &outputs)?;
        for out in &outputs {
            whycode::io::check_output_dir(out)?;
        }
        Ok(Plan {
            annotate,
            bag,
            names,
            several_recordings: recordings.len() > 1,
        })
    }

    /// Whether the run writes files (so a reader of stdout that goes away
    /// must not end it).
    pub fn writes_files(&self) -> bool {
        self.bag.is_some() || !matches!(self.annotate, Annotate::None)
    }

    /// The folder's file for a frame's picture: an image's own name, a
    /// recording's frame `frame_000012.png`, or with several recordings
    /// `<recording>.frame_000012.png`.
    fn picture_name(&self, dir: &Path, stream: &Stream, input: &Input) -> Option<PathBuf> {
        let read = match stream {
            Stream::Recording(path) => path,
            _ => input.file.as_ref()?,
        };
        let name = self.names.get(read)?;
        let Some(recorded) = &input.recorded else {
            return Some(name.clone());
        };
        let frame = format!("frame_{:06}.png", recorded.index);
        if !self.several_recordings {
            return Some(dir.join(frame));
        }
        let prefix = name.file_name()?.to_string_lossy();
        let prefix = prefix.trim_end_matches(".annotated.png");
        Some(dir.join(format!("{prefix}.{frame}")))
    }
}

/// One stream's outputs, open while it is read.
pub struct Outputs<'a> {
    plan: &'a Plan,
    stream: &'a Stream,
    /// The detections bag and where it goes.
    bag: Option<(DetectionsBag, &'a Path)>,
    pictures: Pictures<'a>,
    /// Pictures written.
    pub drawn: usize,
}

/// Where the annotated frames go, opened.
enum Pictures<'a> {
    None,
    Folder(&'a Path),
    Video {
        writer: Box<AnnotatedVideo>,
        staged: whycode::io::StagedFile,
        target: &'a Path,
    },
}

impl<'a> Outputs<'a> {
    /// Opens what `stream` writes: a recording the bag and the video, any
    /// stream its pictures in the folder.
    pub fn new(plan: &'a Plan, stream: &'a Stream) -> Result<Outputs<'a>> {
        let recording = stream.is_recording();
        let bag = match &plan.bag {
            Some(target) if recording => Some((
                DetectionsBag::new().context("cannot start the detections bag")?,
                target.as_path(),
            )),
            _ => None,
        };
        let pictures = match &plan.annotate {
            Annotate::None => Pictures::None,
            Annotate::Folder(dir) => Pictures::Folder(dir),
            Annotate::Video(target) if recording => {
                let staged = whycode::io::StagedFile::new(target)?;
                let writer = Box::new(AnnotatedVideo::new(target, staged.path()));
                Pictures::Video {
                    writer,
                    staged,
                    target,
                }
            }
            Annotate::Video(_) => Pictures::None,
        };
        Ok(Outputs {
            plan,
            stream,
            bag,
            pictures,
            drawn: 0,
        })
    }

    /// Adds one frame's messages to the bag and its picture to the video
    /// or folder.
    pub fn frame(&mut self, input: &Input, report: &FrameReport, session: &Session) -> Result<()> {
        if let (Some((bag, _)), Some(recorded)) = (&mut self.bag, &input.recorded) {
            let header = Header {
                stamp: Time::from_nanos(recorded.stamp_ns),
                frame_id: if recorded.frame_id.is_empty() {
                    "camera".into()
                } else {
                    recorded.frame_id.clone()
                },
            };
            let computed_for = session.detector_config().diameter_m;
            let prefix = whycode::ros::DEFAULT_FRAME_PREFIX;
            let described = describe_frame(
                report,
                &header,
                computed_for,
                |id| (Some(format!("{prefix}{id}")), computed_for),
                session
                    .arena()
                    .map(|arena| (arena, whycode::ros::DEFAULT_ARENA_FRAME)),
            );
            bag.add(recorded.stamp_ns, &described)
                .context("cannot write the detections bag")?;
        }
        match &mut self.pictures {
            Pictures::None => return Ok(()),
            Pictures::Folder(dir) => {
                let png = whycode::session::annotate::annotated_png(&input.image, &report.markers)?;
                let name = self
                    .plan
                    .picture_name(dir, self.stream, input)
                    .ok_or_else(|| anyhow!("{}: no name for its picture", input.shown()))?;
                whycode::io::write_atomic(&name, &png)?;
            }
            Pictures::Video { writer, .. } => {
                let rgb = whycode::session::annotate::annotated_rgb(&input.image, &report.markers)?;
                let stamp_ns = input.recorded.as_ref().map_or(0, |r| r.stamp_ns);
                writer.push(rgb, stamp_ns)?;
            }
        }
        self.drawn += 1;
        Ok(())
    }

    /// Writes the bag and the video, each whole or not at all.
    pub fn finish(self) -> Result<()> {
        if let Some((bag, target)) = self.bag {
            let bytes = bag.finish().context("cannot finish the detections bag")?;
            whycode::io::write_atomic(target, &bytes)?;
            output::say(format_args!("wrote the detections to {}", target.display()));
        }
        if let Pictures::Video {
            writer,
            staged,
            target,
        } = self.pictures
        {
            writer.finish()?;
            staged.commit()?;
            output::say(format_args!(
                "wrote the annotated video {}",
                target.display()
            ));
        }
        Ok(())
    }
}
