//! Detectors the bar compares ours with, each run as a separate program
//! (AprilTag through Python, the original WhyCode as a C++ build) on the
//! scenario's frames written as PGM into a temporary folder. Each prints a
//! JSON line per frame; its reports become [`Sighting`]s scored by the
//! same code as ours.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use image::GrayImage;
use serde::de::DeserializeOwned;
use whycode::camera::Camera;
use whycode::simulate::Sighting;
use whycode_testkit::scenario::{Frame, Print, Scenario, DIAMETER_M};
use whycode_testkit::tally::Counts;

/// What a rival is told about the frames besides the pixels.
pub struct Setup<'a> {
    pub camera: &'a Camera,
    /// Printed size: the marker's outer diameter, the tag's black square, m.
    pub size_m: f64,
    /// Code bits and family distance of our markers in the frames (the
    /// original reads the same rings); `None`: legacy WhyCon.
    pub family: Option<(u32, u32)>,
    /// How many targets each frame shows (the original tracks a fixed number).
    pub targets: usize,
}

pub trait Rival {
    fn name(&self) -> &'static str;
    /// What it reads: its own markers printed in ours' places, or ours.
    fn print(&self) -> Print;
    /// Whether it carries markers over from one run to the next (then its
    /// repeated runs of a frame are tracked frames).
    fn tracks(&self) -> bool {
        false
    }
    /// Each frame's reports and the detector's time for it, ms.
    fn detect(
        &self,
        setup: &Setup,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Sighting>, f64)>, String>;
}

/// The scenario's frames read by `rival` (all at once: one process per
/// scenario), with its own markers printed in ours' places if it has any;
/// like `Scenario::run`, and gives its time per frame, ms.
pub fn run(
    scenario: &Scenario,
    rival: &dyn Rival,
    counts: &mut Counts,
    mut visit: impl FnMut(&Frame, &[Sighting]),
) -> Result<Vec<f64>, String> {
    let frames: Vec<Frame> = (0..scenario.frames)
        .map(|f| scenario.frame(f, rival.print()))
        .collect();
    let images: Vec<&GrayImage> = frames.iter().map(|f| &f.image).collect();
    let setup = Setup {
        camera: &scenario.camera(),
        size_m: DIAMETER_M,
        family: scenario.family.map(|f| (f.bits(), f.distance())),
        targets: scenario.spread.count,
    };
    let results = rival.detect(&setup, &images)?;
    let mut times = Vec::with_capacity(frames.len());
    for (frame, (found, ms)) in frames.iter().zip(results) {
        counts.add(frame.seed, &frame.targets, &found);
        visit(frame, &found);
        times.push(ms);
    }
    Ok(times)
}

/// A rival's counts on the scenario's frames; `None` when it cannot be run
/// (the reason was said once, at the start).
pub fn counts(scenario: &Scenario, rival: Option<&dyn Rival>) -> Option<Counts> {
    let rival = rival?;
    let mut counts = Counts::default();
    match run(scenario, rival, &mut counts, |_, _| {}) {
        Ok(_) => Some(counts),
        Err(e) => {
            eprintln!("{} failed: {e}", rival.name());
            None
        }
    }
}

/// Writes `frames` into a temporary folder as `000000.pgm`, ... (the
/// order the rivals read them in).
pub fn write_frames(frames: &[&GrayImage]) -> Result<tempfile::TempDir, String> {
    let dir = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    for (k, image) in frames.iter().enumerate() {
        write_pgm(&dir.path().join(format!("{k:06}.pgm")), image)
            .map_err(|e| format!("writing frame {k}: {e}"))?;
    }
    Ok(dir)
}

/// Parses a rival's JSON lines, one per frame.
pub fn parse_reports<T: DeserializeOwned>(
    program: &str,
    lines: &[String],
    frames: usize,
) -> Result<Vec<T>, String> {
    let reports: Vec<T> = lines
        .iter()
        .map(|l| serde_json::from_str(l))
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{program}: bad output: {e}"))?;
    if reports.len() != frames {
        return Err(format!(
            "{program} read {} of {frames} frames",
            reports.len()
        ));
    }
    Ok(reports)
}

/// Writes `frames` into a temporary folder, runs `command` with the folder
/// as its first argument and then `args`, and parses one JSON line per
/// frame.
pub fn run_on_frames<T: DeserializeOwned>(
    mut command: Command,
    args: &[String],
    frames: &[&GrayImage],
) -> Result<Vec<T>, String> {
    let dir = write_frames(frames)?;
    let program = command.get_program().to_string_lossy().into_owned();
    let output = command
        .arg(dir.path())
        .args(args)
        .output()
        .map_err(|e| format!("{program}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "{program} failed: {}",
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    let lines: Vec<String> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(str::to_string)
        .collect();
    parse_reports(&program, &lines, frames.len())
}

fn write_pgm(path: &Path, image: &GrayImage) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(out, "P5\n{} {}\n255\n", image.width(), image.height())?;
    out.write_all(image.as_raw())?;
    out.flush()
}

/// `$env_var`, else `target/bench-venv` of this checkout, else `python3`:
/// the first Python that runs `check` (an import line). The error names
/// every candidate tried, `what` was missing and how to set one up.
pub fn find_python(env_var: &str, check: &str, what: &str, setup: &str) -> Result<PathBuf, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let candidates: Vec<PathBuf> = match std::env::var_os(env_var) {
        Some(p) => vec![PathBuf::from(p)],
        None => vec![
            root.join("target/bench-venv/bin/python"),
            PathBuf::from("python3"),
        ],
    };
    for python in &candidates {
        let ok = Command::new(python)
            .args(["-c", check])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Ok(python.clone());
        }
    }
    Err(format!(
        "no Python with {what} among {}; set up with `{setup}` (or point {env_var} at one)",
        candidates
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}
