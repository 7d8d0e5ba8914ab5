//! `whycode detect`: find markers in images and print IDs, yaw and pose.

use super::args::{spec_error, Format, FormatArg, MarkerKindArgs};
use super::output;
use super::recording::{self, Annotate};
use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::camera::Camera;
use whycode::detect::family_check::FamilyCheck;
use whycode::detect::{StageTimings, Target};
use whycode::image_io::load_gray;
use whycode::recording::Kind;
use whycode::session::report::{CsvColumns, FrameReport};
use whycode::session::{Frame, Session, SessionConfig};
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

/// Image file extensions read from folders.
const IMAGE_EXTENSIONS: [&str; 9] = [
    "png", "jpg", "jpeg", "pgm", "ppm", "pnm", "pbm", "bmp", "pam",
];

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
        value_parser = parse_diameter,
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
        value_parser = parse_height,
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

/// A height above a floor: a length whose bare numbers are metres, or 0
/// (on the floor) with or without a unit.
pub(super) fn parse_height(text: &str) -> Result<Length, whycode::units::LengthError> {
    let t = text.trim();
    let number = t.trim_end_matches(|c: char| c.is_ascii_alphabetic());
    if number.parse::<f64>().is_ok_and(|v| v == 0.0) {
        return Ok(Length::from_mm(0.0));
    }
    parse_diameter(text)
}

/// A length whose bare numbers are metres.
pub(super) fn parse_diameter(text: &str) -> Result<Length, whycode::units::LengthError> {
    Length::parse_with_default_unit(text, "m")
}

/// One unit of work: an independent image, or a folder's frames in order.
enum Job {
    Image(PathBuf),
    Sequence(Vec<PathBuf>),
}

pub fn run(args: DetectArgs) -> Result<ExitCode> {
    if recording::check_inputs(&args.inputs)? {
        return run_recordings(args);
    }
    for (given, option) in [
        (args.output.is_some(), "--output"),
        (args.topic.is_some(), "--topic"),
        (args.every.is_some(), "--every"),
        (args.start.is_some(), "--start"),
        (args.end.is_some(), "--end"),
    ] {
        if given {
            bail!("{option}: applies to bags and videos (.mcap, .mp4, .mkv, .avi, .mov, .webm)");
        }
    }
    if let Some(path) = &args.annotate {
        if Kind::of(path) == Some(Kind::Video) {
            bail!(
                "--annotate {}: an annotated video is made from a bag or video; for images give a folder",
                path.display()
            );
        }
    }
    let config = detector_config(&args, false)?;
    let family_bits = config.detector.target.family().map(|f| f.bits());
    // In auto mode with a distance the IDs are there already; legacy
    // circles carry no ring.
    let wants_note = matches!(
        config.detector.target,
        Target::WhyCode(_) | Target::AnyBits { distance: None }
    );
    let jobs = collect_jobs(&args.inputs, args.no_tracking)?;
    if let Some(dir) = &args.annotate {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    }
    let annotate_names = annotation_names(&jobs, args.annotate.as_deref());
    let total: usize = jobs
        .iter()
        .map(|j| match j {
            Job::Image(_) => 1,
            Job::Sequence(frames) => frames.len(),
        })
        .sum();
    let progress = if total >= PROGRESS_MIN_IMAGES && std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(total as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };

    let process = |session: &mut Session, path: &Path| -> Result<FrameReport> {
        let result = detect_one(
            session,
            path,
            annotate_names.get(path).map(PathBuf::as_path),
        );
        progress.inc(1);
        result
    };
    // Jobs run in parallel, one session per worker thread, restarted for
    // each job (so results never depend on which thread ran what); a
    // sequence's frames run in order, tracked, in one session.
    let results: Vec<Vec<Result<FrameReport>>> = jobs
        .par_iter()
        .map_init(
            || Session::new(config.clone()),
            |session, job| match job {
                Job::Image(path) => {
                    session.restart(config.clone());
                    vec![process(session, path)]
                }
                Job::Sequence(frames) => {
                    let mut tracked = config.clone();
                    tracked.detector.tracking = true;
                    session.restart(tracked);
                    frames.iter().map(|f| process(session, f)).collect()
                }
            },
        )
        .collect();
    progress.finish_and_clear();

    let mut out = output::Stdout::new();
    let mut failures = 0;
    let several = total > 1;
    let columns = CsvColumns::of(&config);
    if args.format.format == Format::Csv {
        out.line(columns.header())?;
    }
    let mut check = FamilyCheck::new(family_bits);
    let mut timings = StageTimings::default();
    for result in results.into_iter().flatten() {
        match result {
            Ok(frame) => {
                check.observe(&frame.markers);
                check.legacy_looking += frame.legacy_looking;
                if let Some(frame_timings) = &frame.timings {
                    timings += frame_timings;
                }
                match args.format.format {
                    Format::Json => out.line(frame.to_json())?,
                    Format::Csv => out.write(&frame.to_csv_rows(columns))?,
                    Format::Table => out.write(&frame.to_table(several))?,
                }
            }
            Err(err) => {
                out.flush()?;
                output::error(super::one_line(&err));
                failures += 1;
            }
        }
    }
    out.flush()?;
    if args.timings && timings.frames() > 0 {
        output::say(format_args!("time per stage:\n{timings}"));
    }
    if let Some(dir) = &args.annotate {
        let written = total - failures;
        output::say(format_args!(
            "wrote {written} annotated image{} to {}",
            if written == 1 { "" } else { "s" },
            dir.display()
        ));
    }
    if wants_note {
        if let Some(note) = check.note() {
            output::note(note);
        }
    }
    Ok(if failures > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// The session the options ask for; a recording's camera may come later
/// (a bag's camera_info), and its frames are tracked.
fn detector_config(args: &DetectArgs, recording: bool) -> Result<SessionConfig> {
    DetectSpec {
        target: args.kind.spec()?,
        diameter: args.diameter,
        camera: args.camera.as_deref().map(Camera::load).transpose()?,
        max_markers: args.max_markers,
        tracking: recording,
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
        scan_every_frame: recording,
        camera_later: recording && args.camera.is_none(),
        arena: args
            .arena
            .as_deref()
            .map(whycode::arena::Arena::load)
            .transpose()?,
        marker_height: args.marker_height,
    }
    .build()
    .map_err(spec_error)
}

/// Bags and videos, each one tracked stream, one after the other.
fn run_recordings(args: DetectArgs) -> Result<ExitCode> {
    if args.no_tracking {
        bail!("--no-tracking: a bag or video is read as one tracked stream");
    }
    // A bag's camera_info brings the camera.
    let config = detector_config(&args, true)?;
    let read = RecordingSpec {
        topic: args.topic.clone(),
        every: args.every,
        start: args.start,
        end: args.end,
    }
    .build()
    .map_err(spec_error)?;
    let annotate = Annotate::of(args.annotate.as_deref());
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
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    let mut outputs: Vec<&Path> = args.output.iter().map(PathBuf::as_path).collect();
    match &annotate {
        Annotate::Video(path) => outputs.push(path),
        Annotate::Folder(dir) => std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create folder", dir.display()))?,
        Annotate::None => {}
    }
    whycode::io::check_outputs(&inputs, &outputs)?;
    for out in &outputs {
        whycode::io::check_output_dir(out)?;
    }
    let run = recording::Run {
        config,
        read,
        format: args.format.format,
        annotate: &annotate,
        output: args.output.as_deref(),
    };
    let mut out = if run.output.is_some() || !matches!(annotate, Annotate::None) {
        output::Stdout::outliving_its_reader()
    } else {
        output::Stdout::new()
    };
    recording::header(&run, &mut out)?;
    for input in &args.inputs {
        if let Err(err) = recording::run(input, &run, &mut out) {
            out.flush()?;
            return Err(err);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Checks every input exists before any work starts, and lists folders.
fn collect_jobs(inputs: &[PathBuf], no_tracking: bool) -> Result<Vec<Job>> {
    let mut jobs = Vec::new();
    for input in inputs {
        let meta = std::fs::metadata(input)
            .with_context(|| format!("{}: cannot read", input.display()))?;
        if !meta.is_dir() {
            jobs.push(Job::Image(input.clone()));
            continue;
        }
        let mut frames: Vec<PathBuf> = std::fs::read_dir(input)
            .with_context(|| format!("{}: cannot list folder", input.display()))?
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
            bail!("{}: folder holds no images", input.display());
        }
        // Cameras and scripts number frames without zero padding as often
        // as with it: frame2 comes before frame10.
        frames.sort_by(|a, b| natural_order(a, b));
        if no_tracking {
            jobs.extend(frames.into_iter().map(Job::Image));
        } else {
            jobs.push(Job::Sequence(frames));
        }
    }
    Ok(jobs)
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

/// Output file for every image (see [`whycode::io::annotation_paths`]).
fn annotation_names(
    jobs: &[Job],
    dir: Option<&Path>,
) -> std::collections::HashMap<PathBuf, PathBuf> {
    let Some(dir) = dir else {
        return std::collections::HashMap::new();
    };
    let all: Vec<PathBuf> = jobs
        .iter()
        .flat_map(|j| match j {
            Job::Image(p) => std::slice::from_ref(p).iter(),
            Job::Sequence(frames) => frames.iter(),
        })
        .cloned()
        .collect();
    whycode::io::annotation_paths(dir, &all)
        .into_iter()
        .collect()
}

fn detect_one(session: &mut Session, path: &Path, annotate: Option<&Path>) -> Result<FrameReport> {
    let image = load_gray(path)?;
    let report = session
        .process(Frame::new(&image, path.display().to_string()))
        .map_err(|problem| anyhow::anyhow!("{}: {problem}", path.display()))?;
    if let Some(out) = annotate {
        let png = whycode::session::annotate::annotated_png(&image, &report.markers)?;
        whycode::io::write_atomic(out, &png)?;
    }
    Ok(report)
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
