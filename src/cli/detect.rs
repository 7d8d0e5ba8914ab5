//! `whycode detect`: find markers in images and print IDs, yaw and pose.

use crate::camera::Camera;
use crate::detect::{load_gray, Detection, Detector, DetectorConfig};
use crate::family::{Family, DEFAULT_BITS, DEFAULT_DISTANCE};
use crate::units::Length;
use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

const EXAMPLES: &str = "\
Examples:
  whycode detect photo.jpg                           # 8-bit codes, distance 2
  whycode detect --bits 8 --distance 1 --format json sheet.png
  whycode detect --family family.json --diameter 122mm --camera cam.yaml --format json frames/
  whycode detect --legacy --annotate out/ many.png

Folders are sequences: their images are read in name order and markers are
tracked from frame to frame. Files named on the command line are independent
images, read in parallel.";

/// Image file extensions read from folders.
const IMAGE_EXTENSIONS: [&str; 9] = [
    "png", "jpg", "jpeg", "pgm", "ppm", "pnm", "pbm", "bmp", "pam",
];

/// A progress bar appears from this many images on (and only on a terminal).
const PROGRESS_MIN_IMAGES: usize = 20;

#[derive(Debug, clap::Args)]
#[command(after_help = EXAMPLES)]
pub struct DetectArgs {
    /// Images (PNG, JPEG, PGM/PPM, BMP; 8 or 16 bit; grey or colour) or
    /// folders of frames
    #[arg(required = true, value_name = "IMAGE|FOLDER")]
    inputs: Vec<PathBuf>,

    /// Code length of the markers' ID family [default: 8]
    #[arg(long, short = 'b', conflicts_with_all = ["family", "legacy"])]
    bits: Option<u32>,

    /// Minimum cyclic Hamming distance of the ID family [default: 2]
    #[arg(long, short = 'd', conflicts_with_all = ["family", "legacy"])]
    distance: Option<u32>,

    /// ID family from a family file (written by `whycode ids --format json`)
    #[arg(long, value_name = "FILE", conflicts_with = "legacy")]
    family: Option<PathBuf>,

    /// Legacy WhyCon markers (black and white discs, no ID ring)
    #[arg(long)]
    legacy: bool,

    /// Outer diameter of the black disc, for pose: 0.122 (metres), 122mm, 4.8in
    #[arg(long, value_name = "LENGTH", value_parser = parse_diameter, requires = "camera")]
    diameter: Option<Length>,

    /// Camera calibration (ROS camera_info or OpenCV YAML), for pose
    #[arg(long, value_name = "FILE", requires = "diameter")]
    camera: Option<PathBuf>,

    /// Output: table (for reading, sorted by ID), csv (one row per marker) or json (one
    /// object per image and line)
    #[arg(long, short = 'f', value_enum, default_value_t = Format::Table)]
    format: Format,

    /// Write each image with the markers' ellipses, IDs and +x axes drawn
    /// into DIR as <name>.annotated.png (never over an input)
    #[arg(long, value_name = "DIR")]
    annotate: Option<PathBuf>,

    /// Most markers to report per image
    #[arg(long, value_name = "N")]
    max_markers: Option<usize>,

    /// Treat the frames of a folder as independent images (no tracking;
    /// processed in parallel)
    #[arg(long)]
    no_tracking: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Format {
    Table,
    Csv,
    Json,
}

fn parse_diameter(text: &str) -> Result<Length, String> {
    Length::parse_with_default_unit(text, "m")
}

/// The detections in one image.
struct Frame {
    image: PathBuf,
    width: u32,
    height: u32,
    elapsed_ms: f64,
    markers: Vec<Detection>,
}

/// One unit of work: an independent image, or a folder's frames in order.
enum Job {
    Image(PathBuf),
    Sequence(Vec<PathBuf>),
}

pub fn run(args: DetectArgs) -> Result<ExitCode> {
    let family = if args.legacy {
        None
    } else if let Some(path) = &args.family {
        Some(Family::load(path)?)
    } else {
        let bits = args.bits.unwrap_or(DEFAULT_BITS);
        let distance = args.distance.unwrap_or(DEFAULT_DISTANCE);
        Some(Family::generate(bits, distance).context("--bits/--distance")?)
    };
    let camera = args.camera.as_deref().map(Camera::load).transpose()?;
    let mut config = DetectorConfig {
        family,
        diameter_m: args.diameter.map(Length::m),
        camera,
        ..DetectorConfig::default()
    };
    if let Some(n) = args.max_markers {
        config.max_markers = n;
    }

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

    let process = |detector: &mut Detector, path: &Path| -> Result<Frame> {
        let result = detect_one(
            detector,
            path,
            annotate_names.get(path).map(PathBuf::as_path),
        );
        progress.inc(1);
        result
    };
    // Jobs run in parallel; a sequence's frames run in order on one detector.
    let results: Vec<Vec<Result<Frame>>> = jobs
        .par_iter()
        .map(|job| match job {
            Job::Image(path) => {
                let mut detector = Detector::new(config.clone());
                vec![process(&mut detector, path)]
            }
            Job::Sequence(frames) => {
                let mut detector = Detector::new(DetectorConfig {
                    tracking: true,
                    ..config.clone()
                });
                frames.iter().map(|f| process(&mut detector, f)).collect()
            }
        })
        .collect();
    progress.finish_and_clear();

    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let mut failures = 0;
    let several = total > 1;
    if args.format == Format::Csv {
        writeln!(out, "{}", CSV_HEADER)?;
    }
    for result in results.into_iter().flatten() {
        match result {
            Ok(frame) => match args.format {
                Format::Json => writeln!(out, "{}", frame_json(&frame))?,
                Format::Csv => write_csv(&mut out, &frame)?,
                Format::Table => write_table(&mut out, &frame, several)?,
            },
            Err(err) => {
                out.flush()?;
                eprintln!("whycode: error: {}", super::one_line(&err));
                failures += 1;
            }
        }
    }
    out.flush()?;
    Ok(if failures > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
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
            .filter(|p| {
                p.is_file()
                    && p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                        IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                    })
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

/// Output file for every image (see [`crate::io::annotation_paths`]).
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
    crate::io::annotation_paths(dir, &all).into_iter().collect()
}

fn detect_one(detector: &mut Detector, path: &Path, annotate: Option<&Path>) -> Result<Frame> {
    let image = load_gray(path)?;
    detector
        .fit_camera(image.width(), image.height())
        .map_err(|problem| anyhow::anyhow!("{}: {problem}", path.display()))?;
    let start = Instant::now();
    let markers = detector.detect(&image);
    let elapsed_ms = start.elapsed().as_secs_f64() * 1000.0;
    if let Some(out) = annotate {
        let png = crate::detect::annotate::annotated_png(&image, &markers)?;
        crate::io::write_atomic(out, &png)?;
    }
    Ok(Frame {
        image: path.to_path_buf(),
        width: image.width(),
        height: image.height(),
        elapsed_ms,
        markers,
    })
}

fn round(x: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (x * k).round() / k
}

/// JSON records, fields in the documented order.
#[derive(serde::Serialize)]
struct FrameRecord {
    image: String,
    width: u32,
    height: u32,
    elapsed_ms: f64,
    markers: Vec<MarkerRecord>,
}

#[derive(serde::Serialize)]
struct MarkerRecord {
    id: u32,
    code: Option<u32>,
    u: f64,
    v: f64,
    yaw: Option<f64>,
    axes: [f64; 2],
    confidence: f64,
    position: Option<[f64; 3]>,
    rotation: Option<[[f64; 3]; 3]>,
    quaternion: Option<[f64; 4]>,
}

fn frame_json(frame: &Frame) -> String {
    let markers = frame
        .markers
        .iter()
        .map(|m| {
            let pose = m.pose.as_ref();
            MarkerRecord {
                id: m.id,
                code: m.code,
                u: round(m.u, 3),
                v: round(m.v, 3),
                yaw: m.yaw.map(|y| round(y, 5)),
                axes: [round(m.axes[0], 3), round(m.axes[1], 3)],
                confidence: round(m.confidence, 3),
                position: pose.map(|p| {
                    [
                        round(p.position.x, 5),
                        round(p.position.y, 5),
                        round(p.position.z, 5),
                    ]
                }),
                rotation: pose.map(|p| {
                    std::array::from_fn(|r| std::array::from_fn(|c| round(p.rotation[(r, c)], 6)))
                }),
                quaternion: pose.map(|p| p.quaternion.map(|q| round(q, 6))),
            }
        })
        .collect();
    let record = FrameRecord {
        image: frame.image.display().to_string(),
        width: frame.width,
        height: frame.height,
        elapsed_ms: round(frame.elapsed_ms, 3),
        markers,
    };
    serde_json::to_string(&record).expect("plain records serialise")
}

const CSV_HEADER: &str = "image,id,code,u,v,yaw,axis_major,axis_minor,confidence,x,y,z,qx,qy,qz,qw";

fn write_csv(out: &mut impl Write, frame: &Frame) -> Result<()> {
    let opt = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    let image = csv_field(&frame.image.display().to_string());
    for m in &frame.markers {
        let pose = m.pose.as_ref();
        writeln!(
            out,
            "{image},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            m.id,
            m.code.map_or(String::new(), |c| c.to_string()),
            round(m.u, 3),
            round(m.v, 3),
            opt(m.yaw.map(|y| round(y, 5))),
            round(m.axes[0], 3),
            round(m.axes[1], 3),
            round(m.confidence, 3),
            opt(pose.map(|p| round(p.position.x, 5))),
            opt(pose.map(|p| round(p.position.y, 5))),
            opt(pose.map(|p| round(p.position.z, 5))),
            opt(pose.map(|p| round(p.quaternion[0], 6))),
            opt(pose.map(|p| round(p.quaternion[1], 6))),
            opt(pose.map(|p| round(p.quaternion[2], 6))),
            opt(pose.map(|p| round(p.quaternion[3], 6))),
        )?;
    }
    Ok(())
}

fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

fn write_table(out: &mut impl Write, frame: &Frame, with_heading: bool) -> Result<()> {
    if with_heading {
        writeln!(
            out,
            "{} ({}x{}, {} markers, {:.1} ms)",
            frame.image.display(),
            frame.width,
            frame.height,
            frame.markers.len(),
            frame.elapsed_ms
        )?;
    }
    if frame.markers.is_empty() {
        writeln!(out, "  no markers")?;
        if with_heading {
            writeln!(out)?;
        }
        return Ok(());
    }
    let has_pose = frame.markers.iter().any(|m| m.pose.as_ref().is_some());
    write!(
        out,
        "{:>5} {:>6} {:>9} {:>9} {:>8} {:>15} {:>5}",
        "id", "code", "u", "v", "yaw_deg", "axes_px", "conf"
    )?;
    if has_pose {
        write!(out, " {:>26}", "position_m (x, y, z)")?;
    }
    writeln!(out)?;
    // Sorted by ID for reading (unknown IDs last, then left to right); csv
    // and json keep the detector's order.
    let mut sorted: Vec<&Detection> = frame.markers.iter().collect();
    sorted.sort_by(|a, b| {
        (a.id == 0, a.id)
            .cmp(&(b.id == 0, b.id))
            .then(a.u.total_cmp(&b.u))
            .then(a.v.total_cmp(&b.v))
    });
    for m in sorted {
        let id = if m.id == 0 {
            "?".to_string()
        } else {
            m.id.to_string()
        };
        let code = m.code.map_or("-".to_string(), |c| c.to_string());
        let yaw = m
            .yaw
            .map_or("-".to_string(), |y| format!("{:.1}", y.to_degrees()));
        let axes = format!("{:.1} x {:.1}", m.axes[0], m.axes[1]);
        write!(
            out,
            "{id:>5} {code:>6} {:>9.2} {:>9.2} {yaw:>8} {axes:>15} {:>5.2}",
            m.u, m.v, m.confidence
        )?;
        if let Some(p) = m.pose.as_ref() {
            write!(
                out,
                " {:>26}",
                format!(
                    "{:.3}, {:.3}, {:.3}",
                    p.position.x, p.position.y, p.position.z
                )
            )?;
        }
        writeln!(out)?;
    }
    if with_heading {
        writeln!(out)?;
    }
    Ok(())
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
