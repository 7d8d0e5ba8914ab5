//! `whycode detect`: find markers in images and print IDs, yaw and pose.

use super::args::{spec_error, Format, FormatArg, MarkerKindArgs};
use super::output;
use super::outputs::{Annotate, Outputs, Plan};
use super::stream::{self, Input, Stream};
use anyhow::{anyhow, bail, Result};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use whycode::camera::Camera;
use whycode::detect::family_check::FamilyCheck;
use whycode::detect::{StageTimings, Target};
use whycode::recording::{ReadOptions, Skipped, Summary};
use whycode::session::report::{CsvColumns, FrameReport};
use whycode::session::{Frame, FrameError, Session, SessionConfig};
use whycode::spec::{DetectSpec, RecordingSpec};
use whycode::units::Length;

const EXAMPLES: &str = "\
Examples:
  whycode detect photo.jpg                           # 8-bit codes, distance 2
  whycode detect --bits 8 --distance 1 --format json sheet.png
  whycode detect --family family.json --diameter 122mm --camera cam.yaml --format json frames/
  whycode detect --legacy --annotate out/ many.png
  whycode detect --bits auto photo.jpg               # each ring's bit count and code
  whycode detect --bits auto --distance 2 photo.jpg  # and its ID in that family
  whycode detect --timings frames/                   # where the detector's time goes
  whycode detect --arena arena.yaml --diameter 8cm --format json frames/   # floor x, y, yaw
  whycode detect --diameter 122mm --output found.mcap run.mcap   # a ROS 2 bag
  whycode detect --every 2 --start 1:00 --annotate out.mp4 run.mp4  # a video

Formats: table (for reading), csv (one row per marker) or json (one object
per image and line).

Folders are sequences: their images are read in name order and markers are
tracked from frame to frame. Files named on the command line are independent
images, read in parallel. ROS 2 bags (.mcap: sensor_msgs Image and
CompressedImage, the camera from camera_info) and videos (.mp4, .mkv, .avi,
.mov, .webm, through ffmpeg) are tracked streams: each JSON line gains frame,
stamp_ns (and topic); a summary ends on stderr.";

/// A progress bar appears from this many images on (and only on a terminal).
const PROGRESS_MIN_IMAGES: usize = 20;

#[derive(Debug, clap::Args)]
#[command(after_help = EXAMPLES)]
pub struct DetectArgs {
    /// Images (PNG, JPEG, PGM/PPM, BMP; 8 or 16 bit; grey or colour),
    /// folders of frames, ROS 2 bags (.mcap) or videos
    #[arg(required = true, value_name = "IMAGE|FOLDER|RECORDING")]
    inputs: Vec<PathBuf>,

    #[command(flatten)]
    kind: MarkerKindArgs,

    /// Outer diameter of the black disc, for pose: 0.122 (metres), 122mm, 4.8in
    #[arg(
        long,
        value_name = "LENGTH",
        value_parser = Length::parse_metres,
        allow_hyphen_values = true
    )]
    diameter: Option<Length>,

    /// Camera calibration (ROS camera_info or OpenCV YAML), for pose with
    /// --diameter or a --board (whose markers give their diameters); a
    /// bag's camera_info gives it without this
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,

    /// A board (a sheet's manifest: each page a plane) or a bundle file
    /// (YAML: markers' IDs, diameters and poses): each frame's JSON gets
    /// its pose in `boards`. Repeatable; needs --camera (or a bag's
    /// camera_info)
    #[arg(long, value_name = "FILE")]
    board: Vec<PathBuf>,

    /// An arena file (`whycode arena`): each marker gets `arena` {x, y, z,
    /// yaw}, its place on the floor in metres. One measured with a camera
    /// brings that camera, and places markers without --diameter (each
    /// outline is read on the arena's known plane)
    #[arg(long, value_name = "FILE")]
    arena: Option<PathBuf>,

    /// Height above the arena's floor of the markers located (markers on
    /// robots), in place of the arena file's: 0.12 (metres), 12cm
    #[arg(
        long,
        value_name = "LENGTH",
        value_parser = Length::parse_height,
        requires = "arena",
        allow_hyphen_values = true
    )]
    marker_height: Option<Length>,

    #[command(flatten)]
    format: FormatArg,

    /// Write each image with the markers' ellipses, IDs and +x axes drawn
    /// into DIR as <name>.annotated.png (never over an input); for a bag
    /// or video, a video file (out.mp4) or a folder of frame_N.png
    #[arg(long, value_name = "DIR|VIDEO")]
    annotate: Option<PathBuf>,

    /// Write a bag or video's detections as a ROS 2 bag (MCAP): /tf and
    /// /whycode/markers as the ROS 2 node publishes them
    #[arg(long, value_name = "FILE.mcap")]
    output: Option<PathBuf>,

    /// The bag's image topic, when it has several
    #[arg(long, value_name = "TOPIC")]
    topic: Option<String>,

    /// Read every N-th frame of a bag or video
    #[arg(long, value_name = "N")]
    every: Option<u64>,

    /// Start a bag or video this long after its first frame: 12.5, 90s, 1:30
    #[arg(long, value_name = "TIME", value_parser = RecordingSpec::parse_time)]
    start: Option<f64>,

    /// End a bag or video this long after its first frame
    #[arg(long, value_name = "TIME", value_parser = RecordingSpec::parse_time)]
    end: Option<f64>,

    /// Most markers to report per image
    #[arg(long, value_name = "N")]
    max_markers: Option<usize>,

    /// Treat the frames of a folder as independent images (no tracking;
    /// processed in parallel)
    #[arg(long)]
    no_tracking: bool,

    /// Also report round candidates whose ring shows no code structure
    /// (marked "unreadable"); by default they are not taken for markers
    #[arg(long, conflicts_with = "legacy")]
    unreadable: bool,

    /// Smallest black ring of a legacy marker worth reporting, in pixels:
    /// by default the original WhyCon's (100, a marker 12.4 px across
    /// face-on); lower it for smaller markers, and bold letters 'o' may
    /// pass for markers
    #[arg(
        long,
        value_name = "PIXELS",
        requires = "legacy",
        allow_hyphen_values = true
    )]
    min_ink: Option<f64>,

    /// Time each stage of the detector: a "timings" object in each JSON
    /// line, and milliseconds per stage over all images on standard error
    #[arg(long)]
    timings: bool,
}

pub fn run(args: DetectArgs) -> Result<ExitCode> {
    let inputs = check_options(&args)?;
    let settings = Settings::new(&args, inputs)?;
    let streams = Stream::list(&args.inputs, args.no_tracking)?;
    let plan = Plan::new(
        Annotate::of(args.annotate.as_deref()),
        args.output.clone(),
        &streams,
    )?;
    let files: usize = streams.iter().map(|s| s.files().len()).sum();
    let several = files > 1 || inputs.recordings;
    let mut printer = Printer::new(&args, &settings, &plan, several)?;
    let progress = progress_bar(files, inputs.recordings);

    // Neighbouring images and folders run in parallel, one session per
    // worker thread, restarted for each stream (so results never depend on
    // which thread ran what), and are printed in input order; a stream on
    // its own (a recording, one image, one folder) runs on this thread and
    // is printed as it is read, with no thread pool to start.
    for group in streams.chunk_by(|a, b| !a.is_recording() && !b.is_recording()) {
        if let [stream] = group {
            let mut session = Session::new(settings.config(stream));
            let ended = run_stream(
                stream,
                &settings,
                &plan,
                &mut session,
                &progress,
                &mut |r| progress.suspend(|| printer.take(r)),
            )?;
            printer.ended(ended);
            continue;
        }
        let done: Vec<(Vec<Result<FrameReport>>, Ended)> = group
            .par_iter()
            .map_init(
                || Session::new(settings.any().clone()),
                |session, stream| {
                    let mut reports = Vec::new();
                    let ended =
                        run_stream(stream, &settings, &plan, session, &progress, &mut |r| {
                            reports.push(r);
                            Ok(())
                        })
                        .unwrap_or_else(|err| {
                            reports.push(Err(err));
                            Ended::default()
                        });
                    (reports, ended)
                },
            )
            .collect();
        for (reports, ended) in done {
            for report in reports {
                progress.suspend(|| printer.take(report))?;
            }
            printer.ended(ended);
        }
    }
    progress.finish_and_clear();
    printer.finish(&plan)
}

/// What ends a stream besides its frames.
#[derive(Default)]
struct Ended {
    /// A recording's summary, for standard error.
    summary: Vec<String>,
    /// Pictures written.
    drawn: usize,
}

impl Ended {
    /// A stream cut short after `drawn` pictures.
    fn drawn(drawn: usize) -> Ended {
        Ended {
            summary: Vec::new(),
            drawn,
        }
    }
}

/// One stream through the session, the frame loop of every input: each
/// frame read, measured, drawn and written to the outputs, and its report
/// (or why it failed) handed to `each`. A failed frame ends a recording
/// (its outputs unwritten), not a folder. Only an error of `each` itself
/// (standard output gone) ends the run.
fn run_stream(
    stream: &Stream,
    settings: &Settings,
    plan: &Plan,
    session: &mut Session,
    progress: &indicatif::ProgressBar,
    each: &mut dyn FnMut(Result<FrameReport>) -> Result<()>,
) -> Result<Ended> {
    let config = settings.config(stream);
    let stream_cameras = config.stream_cameras;
    session.restart(config);
    let opened = match stream.open() {
        Ok(opened) => opened,
        Err(err) => return each(Err(err)).map(|()| Ended::default()),
    };
    let (mut frames, mut outputs) = match opened
        .frames(&settings.read)
        .and_then(|f| Ok((f, Outputs::new(plan, stream)?)))
    {
        Ok(open) => open,
        Err(err) => return each(Err(err)).map(|()| Ended::default()),
    };
    let mut summary = Summary::default();
    let mut uncounted = true;
    while let Some(input) = frames.next() {
        let measured = input.and_then(|input| {
            let report = measure(session, &input)?;
            outputs.frame(&input, &report, session)?;
            let index = input.recorded.as_ref().map_or(0, |r| r.index);
            summary.observe(index, &report.markers);
            Ok(report)
        });
        let failed = measured.is_err();
        each(measured)?;
        progress.inc(1);
        if let (true, Some(n)) = (uncounted, frames.expected()) {
            progress.inc_length(n);
            uncounted = false;
        }
        if failed && !stream.goes_on_after_a_failed_frame() {
            return Ok(Ended::drawn(outputs.drawn));
        }
    }
    let lines = summary_lines(stream, frames.skipped(), &summary, stream_cameras);
    drop(frames);
    let drawn = outputs.drawn;
    if let Err(err) = outputs.finish() {
        each(Err(err))?;
        return Ok(Ended::drawn(drawn));
    }
    Ok(Ended {
        summary: lines,
        drawn,
    })
}

/// A recording's summary lines, each after its name (none for files).
fn summary_lines(
    stream: &Stream,
    skipped: Option<&Skipped>,
    summary: &Summary,
    stream_cameras: bool,
) -> Vec<String> {
    let (Stream::Recording(path), Some(skipped)) = (stream, skipped) else {
        return Vec::new();
    };
    let mut skipped = skipped.clone();
    if !stream_cameras {
        // The bag's camera_info was not what the poses used.
        skipped.refused_calibrations = 0;
        skipped.first_refused_calibration = None;
    }
    summary
        .lines(&skipped)
        .into_iter()
        .map(|line| format!("{}: {line}", path.display()))
        .collect()
}

/// One frame through the session; the error names the frame.
fn measure(session: &mut Session, input: &Input) -> Result<FrameReport> {
    session
        .process(Frame {
            image: &input.image,
            name: input.name.clone(),
            stream: input.position(),
            camera: input.recorded.as_ref().and_then(|r| r.camera),
        })
        .map_err(|problem| match problem {
            camera @ FrameError::Camera { .. } if input.recorded.is_some() => {
                anyhow!("{}: the camera does not fit: {camera}", input.shown())
            }
            problem => anyhow!("{}: {problem}", input.shown()),
        })
}

/// The session configurations and the reading options of a run.
struct Settings {
    /// For images and folders (a folder's frames are tracked), when there
    /// are some.
    files: Option<SessionConfig>,
    /// For bags and videos, when there are some: tracked, scanned each
    /// frame, their own camera from camera_info unless one was given.
    recordings: Option<SessionConfig>,
    read: ReadOptions,
}

impl Settings {
    fn new(args: &DetectArgs, inputs: Inputs) -> Result<Settings> {
        let spec = DetectSpec {
            target: args.kind.spec()?,
            diameter: args.diameter,
            camera: args.camera.as_deref().map(Camera::load).transpose()?,
            max_markers: args.max_markers,
            tracking: false,
            unreadable: args.unreadable,
            min_ink: args.min_ink,
            boards: args
                .board
                .iter()
                .map(|path| whycode::board::Board::load(path))
                .collect::<Result<Vec<_>, _>>()?
                .into_iter()
                .flatten()
                .collect(),
            timings: args.timings,
            scan_every_frame: false,
            camera_later: false,
            arena: args
                .arena
                .as_deref()
                .map(whycode::arena::Arena::load)
                .transpose()?,
            marker_height: args.marker_height,
        };
        let recordings = inputs
            .recordings
            .then(|| {
                DetectSpec {
                    tracking: true,
                    scan_every_frame: true,
                    camera_later: args.camera.is_none(),
                    ..spec.clone()
                }
                .build()
                .map_err(spec_error)
            })
            .transpose()?;
        let files = inputs
            .files
            .then(|| spec.build().map_err(spec_error))
            .transpose()?;
        let read = RecordingSpec {
            topic: args.topic.clone(),
            every: args.every,
            start: args.start,
            end: args.end,
        }
        .build()
        .map_err(spec_error)?;
        Ok(Settings {
            files,
            recordings,
            read,
        })
    }

    /// The session `stream` is read with.
    fn config(&self, stream: &Stream) -> SessionConfig {
        let (files, recordings) = (self.files.as_ref(), self.recordings.as_ref());
        let config = match stream {
            Stream::Recording(_) => recordings.or(files),
            _ => files.or(recordings),
        };
        let mut config = config
            .expect("a configuration for every kind of input")
            .clone();
        if let Stream::Folder(_) = stream {
            config.detector.tracking = true;
        }
        config
    }

    /// Either configuration: what the two share (the target, the arena).
    fn any(&self) -> &SessionConfig {
        self.files
            .as_ref()
            .or(self.recordings.as_ref())
            .expect("a configuration for every kind of input")
    }
}

/// Which kinds of input a run has.
#[derive(Clone, Copy)]
struct Inputs {
    /// Images or folders.
    files: bool,
    /// Bags or videos.
    recordings: bool,
}

/// Checks the options fit the inputs, and says which kinds there are.
fn check_options(args: &DetectArgs) -> Result<Inputs> {
    let recordings = args
        .inputs
        .iter()
        .filter(|p| stream::names_a_recording(p))
        .count();
    if recordings == 0 {
        for (given, option) in [
            (args.output.is_some(), "--output"),
            (args.topic.is_some(), "--topic"),
            (args.every.is_some(), "--every"),
            (args.start.is_some(), "--start"),
            (args.end.is_some(), "--end"),
        ] {
            if given {
                bail!(
                    "{option}: applies to bags and videos (.mcap, .mp4, .mkv, .avi, .mov, .webm)"
                );
            }
        }
    }
    let annotate = Annotate::of(args.annotate.as_deref());
    if let (Annotate::Video(path), 0) = (&annotate, recordings) {
        bail!(
            "--annotate {}: an annotated video is made from a bag or video; for images give a folder",
            path.display()
        );
    }
    let single_output = matches!(annotate, Annotate::Video(_)) || args.output.is_some();
    if single_output && args.inputs.len() > 1 {
        bail!("--output and --annotate VIDEO take one recording at a time");
    }
    if let Some(out) = &args.output {
        if out.extension().and_then(|e| e.to_str()) != Some("mcap") {
            bail!(
                "--output: {}: the detections bag is an MCAP file (name it .mcap)",
                out.display()
            );
        }
    }
    if recordings > 0 && args.no_tracking {
        bail!("--no-tracking: a bag or video is read as one tracked stream");
    }
    Ok(Inputs {
        files: recordings < args.inputs.len(),
        recordings: recordings > 0,
    })
}

/// A bar of frames read when stderr is a terminal and the run is long:
/// many images, or a recording (whose length comes once it says how many
/// frames it holds).
fn progress_bar(files: usize, recordings: bool) -> indicatif::ProgressBar {
    if !(files >= PROGRESS_MIN_IMAGES || recordings) || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(files as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{pos}/{len} frames, {per_sec}, {eta} left {wide_bar}",
        )
        .expect("a valid template"),
    );
    bar
}

/// Where every frame's report goes: its rows on stdout, the run's tallies
/// (failures, the family check, the stage timings, pictures written) and
/// the closing lines on stderr.
struct Printer {
    out: output::Stdout,
    rows: Rows,
    check: FamilyCheck,
    /// In auto mode with a distance the IDs are there already; legacy
    /// circles carry no ring.
    wants_note: bool,
    timings: Option<StageTimings>,
    failures: usize,
    /// The first failure's line, which closes a failed run when other
    /// lines came after the last failure.
    first_failure: Option<String>,
    said_since_failure: bool,
    drawn: usize,
}

impl Printer {
    fn new(args: &DetectArgs, settings: &Settings, plan: &Plan, several: bool) -> Result<Printer> {
        let target = &settings.any().detector.target;
        let columns = CsvColumns::of(settings.any());
        let mut out = if plan.writes_files() {
            output::Stdout::outliving_its_reader()
        } else {
            output::Stdout::new()
        };
        if args.format.format == Format::Csv {
            out.line(columns.header())?;
        }
        Ok(Printer {
            out,
            rows: Rows::new(args.format.format, columns, several),
            check: FamilyCheck::new(target.family().map(|f| f.bits())),
            wants_note: matches!(
                target,
                Target::WhyCode(_) | Target::AnyBits { distance: None }
            ),
            timings: args.timings.then(StageTimings::default),
            failures: 0,
            first_failure: None,
            said_since_failure: false,
            drawn: 0,
        })
    }

    /// One frame's report, or why it failed.
    fn take(&mut self, result: Result<FrameReport>) -> Result<()> {
        match result {
            Ok(frame) => {
                self.check.observe(&frame.markers);
                self.check.legacy_looking += frame.legacy_looking;
                if let (Some(all), Some(frame_timings)) = (&mut self.timings, &frame.timings) {
                    *all += frame_timings;
                }
                self.rows.print(&mut self.out, &frame)
            }
            Err(err) if err.is::<output::ReaderGone>() => Err(err),
            Err(err) => {
                self.out.flush()?;
                let line = super::one_line(&err);
                output::error(&line);
                self.failures += 1;
                self.first_failure.get_or_insert(line);
                self.said_since_failure = false;
                Ok(())
            }
        }
    }

    /// The end of one stream.
    fn ended(&mut self, ended: Ended) {
        self.drawn += ended.drawn;
        for line in ended.summary {
            output::say(line);
            self.said_since_failure = true;
        }
    }

    /// The closing lines; failure when any frame or stream failed. A failed
    /// run ends on an error line: when other lines follow its last failure
    /// (a stream's summary, the closing lines), the first failure is named
    /// again last.
    fn finish(mut self, plan: &Plan) -> Result<ExitCode> {
        self.out.flush()?;
        if let Some(timings) = self.timings.filter(|t| t.frames() > 0) {
            output::say(format_args!("time per stage:\n{timings}"));
            self.said_since_failure = true;
        }
        if let Annotate::Folder(dir) = &plan.annotate {
            let drawn = self.drawn;
            output::say(format_args!(
                "wrote {drawn} annotated image{} to {}",
                if drawn == 1 { "" } else { "s" },
                dir.display()
            ));
            self.said_since_failure = true;
        }
        if self.wants_note {
            if let Some(note) = self.check.note() {
                output::note(note);
                self.said_since_failure = true;
            }
        }
        let Some(first) = self.first_failure else {
            return Ok(ExitCode::SUCCESS);
        };
        if self.said_since_failure {
            match self.failures {
                1 => output::error(format_args!("the run failed: {first}")),
                n => output::error(format_args!("{n} failures, the first: {first}")),
            }
        }
        Ok(ExitCode::FAILURE)
    }
}

/// How each frame's report is printed.
struct Rows {
    format: Format,
    columns: CsvColumns,
    /// Whether the table names each frame (more than one is printed).
    several: bool,
}

impl Rows {
    fn new(format: Format, columns: CsvColumns, several: bool) -> Rows {
        Rows {
            format,
            columns,
            several,
        }
    }

    /// One frame's JSON line, CSV rows or table.
    fn print(&self, out: &mut output::Stdout, report: &FrameReport) -> Result<()> {
        match self.format {
            Format::Json => out.line(report.to_json()),
            Format::Csv => out.write(&report.to_csv_rows(self.columns)),
            Format::Table => out.write(&report.to_table(self.several)),
        }
    }
}
