//! `whycode detect` on recorded runs: a ROS 2 bag or a video read as one
//! tracked stream, a JSON line (or CSV rows, or a table) per frame on
//! stdout, the stream's summary on stderr, and optionally the detections
//! as a bag and the annotated frames as a video or a folder of images.

use super::args::Format;
use super::detect::Rows;
use super::output;
use anyhow::{anyhow, bail, Context, Result};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use whycode::recording::output::{AnnotatedVideo, DetectionsBag};
use whycode::recording::{Frame as RecordedFrame, Kind, ReadOptions, Recording, Summary};
use whycode::ros::describe::describe_frame;
use whycode::ros::msg::{Header, Time};
use whycode::session::report::{CsvColumns, FrameReport, StreamPosition};
use whycode::session::{Frame, FrameError, Session, SessionConfig};

/// Where the annotated frames go.
pub enum Annotate {
    /// Nowhere.
    None,
    /// Images `frame_000012.png` in a folder.
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

/// What one recording is read with.
pub struct Run<'a> {
    /// The session's configuration (tracking is turned on here); without
    /// `--camera`, a bag's camera_info brings the camera.
    pub config: SessionConfig,
    /// Frames to read.
    pub read: ReadOptions,
    /// How frames are printed.
    pub format: Format,
    /// Where the annotated frames go.
    pub annotate: &'a Annotate,
    /// The detections bag to write.
    pub output: Option<&'a Path>,
}

/// Whether a path (that exists as a file) is a recording.
pub fn is_recording(path: &Path) -> bool {
    Kind::of(path).is_some() && !path.is_dir()
}

/// Reads one recording; an error ends the stream (stdout keeps the frames
/// before it, the outputs are not written).
pub fn run(path: &Path, run: &Run, out: &mut output::Stdout) -> Result<()> {
    let recording = Recording::open(path)?;
    let mut frames = recording.frames(&run.read)?;
    let progress = progress_bar();
    let mut config = run.config.clone();
    config.detector.tracking = true;
    let mut session = Session::new(config);
    let mut outputs = Outputs::new(run)?;
    let rows = Rows::new(run.format, CsvColumns::of(&run.config), true);
    let mut summary = Summary::default();
    let shown = path.display().to_string();
    let mut result: Result<()> = Ok(());
    while let Some(frame) = frames.next() {
        let frame = match frame {
            Ok(frame) => frame,
            Err(e) => {
                result = Err(e.into());
                break;
            }
        };
        let report = process(&mut session, &frame, &shown)?;
        summary.observe(frame.index, &report.markers);
        outputs.frame(&frame, &report, &session)?;
        progress.suspend(|| rows.print(out, &report))?;
        progress.inc(1);
        if let (None, Some(n)) = (progress.length(), frames.expected()) {
            progress.set_length(n);
        }
    }
    progress.finish_and_clear();
    out.flush()?;
    let mut skipped = frames.skipped().clone();
    if !run.config.stream_cameras {
        // The bag's camera_info was not what the poses used.
        skipped.refused_calibrations = 0;
        skipped.first_refused_calibration = None;
    }
    drop(frames);
    result?;
    outputs.finish()?;
    for line in summary.lines(&skipped) {
        output::say(format_args!("{shown}: {line}"));
    }
    Ok(())
}

/// A bar of frames read when stderr is a terminal (its length comes once
/// the recording says how many frames it holds).
fn progress_bar() -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::no_length();
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{pos}/{len} frames, {per_sec}, {eta} left {wide_bar}",
        )
        .expect("a valid template"),
    );
    bar
}

/// One recorded frame through the session; a camera or arena that does
/// not fit ends the stream.
fn process(session: &mut Session, frame: &RecordedFrame, shown: &str) -> Result<FrameReport> {
    session
        .process(Frame {
            image: &frame.image,
            name: shown.to_string(),
            stream: Some(StreamPosition {
                frame: frame.index,
                stamp_ns: frame.stamp_ns,
                topic: frame.topic.clone(),
            }),
            camera: frame.camera,
        })
        .map_err(|problem| match problem {
            camera @ FrameError::Camera { .. } => anyhow!(
                "{shown}: frame {}: the camera does not fit: {camera}",
                frame.index
            ),
            FrameError::Arena(problem) => anyhow!("{shown}: frame {}: {problem}", frame.index),
        })
}

/// The files a recording's run writes besides stdout: the detections bag
/// and the annotated frames (a video, or images in a folder).
struct Outputs<'a> {
    /// The detections bag and where it goes.
    bag: Option<(DetectionsBag, &'a Path)>,
    pictures: Pictures<'a>,
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
    fn new(run: &Run<'a>) -> Result<Outputs<'a>> {
        let bag = match run.output {
            Some(target) => Some((
                DetectionsBag::new().context("cannot start the detections bag")?,
                target,
            )),
            None => None,
        };
        let pictures = match run.annotate {
            Annotate::None => Pictures::None,
            Annotate::Folder(dir) => Pictures::Folder(dir),
            Annotate::Video(target) => {
                let staged = whycode::io::StagedFile::new(target)?;
                let writer = Box::new(AnnotatedVideo::new(target, staged.path()));
                Pictures::Video {
                    writer,
                    staged,
                    target,
                }
            }
        };
        Ok(Outputs { bag, pictures })
    }

    /// Adds one frame's messages to the bag and its picture to the video
    /// or folder.
    fn frame(
        &mut self,
        frame: &RecordedFrame,
        report: &FrameReport,
        session: &Session,
    ) -> Result<()> {
        if let Some((bag, _)) = &mut self.bag {
            let header = Header {
                stamp: Time::from_nanos(frame.stamp_ns),
                frame_id: if frame.frame_id.is_empty() {
                    "camera".into()
                } else {
                    frame.frame_id.clone()
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
            bag.add(frame.stamp_ns, &described)
                .context("cannot write the detections bag")?;
        }
        match &mut self.pictures {
            Pictures::None => {}
            Pictures::Folder(dir) => {
                let png = whycode::session::annotate::annotated_png(&frame.image, &report.markers)?;
                let name = format!("frame_{:06}.png", frame.index);
                whycode::io::write_atomic(&dir.join(name), &png)?;
            }
            Pictures::Video { writer, .. } => {
                let rgb = whycode::session::annotate::annotated_rgb(&frame.image, &report.markers)?;
                writer.push(rgb, frame.stamp_ns)?;
            }
        }
        Ok(())
    }

    /// Writes the bag and the video, each whole or not at all.
    fn finish(self) -> Result<()> {
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

/// The CSV header, when the format has one.
pub fn header(run: &Run, out: &mut output::Stdout) -> Result<()> {
    if run.format == Format::Csv {
        out.line(CsvColumns::of(&run.config).header())?;
    }
    Ok(())
}

/// Checks the options that only recordings take were given with them.
pub fn check_inputs(inputs: &[PathBuf]) -> Result<bool> {
    let recordings = inputs.iter().filter(|p| is_recording(p)).count();
    if recordings > 0 && recordings < inputs.len() {
        bail!("bags and videos are read alone: give images and recordings to separate runs");
    }
    Ok(recordings > 0)
}
