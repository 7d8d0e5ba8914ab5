//! AprilTag as the bar measures it: pupil-apriltags (tag36h11, one
//! thread) run by `apriltag.py` on the scenario's frames, written as PGM
//! into a temporary folder. Its reports become [`Seen`]s scored by the
//! same code as ours.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use image::GrayImage;
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use whycode::camera::Camera;

use crate::scenario::Seen;

/// The one-line setup the bar prints when AprilTag cannot be run.
pub const SETUP: &str =
    "python3 -m venv target/bench-venv && target/bench-venv/bin/pip install pupil-apriltags numpy";

/// A Python that can import pupil_apriltags, and the script.
pub struct AprilTag {
    python: PathBuf,
    script: PathBuf,
    /// pupil-apriltags' `quad_decimate`: its default 2.0 unless
    /// `$APRILTAG_DECIMATE` says otherwise (1.0 finds smaller tags, slower).
    pub quad_decimate: f64,
}

#[derive(Deserialize)]
struct FrameReport {
    ms: f64,
    tags: Vec<TagReport>,
}

#[derive(Deserialize)]
struct TagReport {
    id: u32,
    center: [f64; 2],
    corners: [[f64; 2]; 4],
    #[serde(rename = "R")]
    rotation: Option<[[f64; 3]; 3]>,
    t: Option<[f64; 3]>,
}

impl AprilTag {
    /// `$APRILTAG_PYTHON`, else `target/bench-venv` of this checkout, else
    /// `python3`: the first that imports pupil_apriltags. The error says
    /// why none did.
    pub fn find() -> Result<AprilTag, String> {
        let quad_decimate = match std::env::var("APRILTAG_DECIMATE") {
            Ok(v) => v
                .parse::<f64>()
                .ok()
                .filter(|d| *d >= 1.0)
                .ok_or(format!("APRILTAG_DECIMATE={v}: not a number of at least 1"))?,
            Err(_) => 2.0,
        };
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let script = root.join("examples/detector_bar/apriltag.py");
        let candidates: Vec<PathBuf> = match std::env::var_os("APRILTAG_PYTHON") {
            Some(p) => vec![PathBuf::from(p)],
            None => vec![
                root.join("target/bench-venv/bin/python"),
                PathBuf::from("python3"),
            ],
        };
        for python in &candidates {
            let ok = Command::new(python)
                .args(["-c", "import pupil_apriltags, numpy"])
                .output()
                .is_ok_and(|o| o.status.success());
            if ok {
                return Ok(AprilTag {
                    python: python.clone(),
                    script,
                    quad_decimate,
                });
            }
        }
        Err(format!(
            "no Python with pupil_apriltags among {}; set up with `{SETUP}` (or point APRILTAG_PYTHON at one)",
            candidates
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    }

    /// Reads `frames` (all taken with `camera`, tags whose black square is
    /// `tag_size_m` wide): each frame's reports, with full pose, and the
    /// detect call's time in ms.
    pub fn detect(
        &self,
        camera: &Camera,
        tag_size_m: f64,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Seen>, f64)>, String> {
        let dir = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
        for (k, image) in frames.iter().enumerate() {
            write_pgm(&dir.path().join(format!("{k:06}.pgm")), image)
                .map_err(|e| format!("writing frame {k}: {e}"))?;
        }
        let output = Command::new(&self.python)
            .arg(&self.script)
            .arg(dir.path())
            .args([
                "--fx",
                &camera.fx.to_string(),
                "--fy",
                &camera.fy.to_string(),
            ])
            // AprilTag's pixel centres are at half-integers (see `seen`).
            .args([
                "--cx",
                &(camera.cx + 0.5).to_string(),
                "--cy",
                &(camera.cy + 0.5).to_string(),
            ])
            .args(["--tag-size", &tag_size_m.to_string()])
            .args(["--quad-decimate", &self.quad_decimate.to_string()])
            .output()
            .map_err(|e| format!("{}: {e}", self.python.display()))?;
        if !output.status.success() {
            return Err(format!(
                "{} failed: {}",
                self.script.display(),
                String::from_utf8_lossy(&output.stderr).trim()
            ));
        }
        let reports: Vec<FrameReport> = String::from_utf8_lossy(&output.stdout)
            .lines()
            .map(serde_json::from_str)
            .collect::<Result<_, _>>()
            .map_err(|e| format!("{}: bad output: {e}", self.script.display()))?;
        if reports.len() != frames.len() {
            return Err(format!(
                "{} read {} of {} frames",
                self.script.display(),
                reports.len(),
                frames.len()
            ));
        }
        Ok(reports
            .into_iter()
            .map(|r| (r.tags.iter().map(seen).collect(), r.ms))
            .collect())
    }
}

/// An AprilTag report in our terms. AprilTag's pixel centres are at
/// half-integers (ours: integers; its centres come out 0.5 px off in u and
/// v otherwise); its tag frame has y down the tag and z into it, ours y up
/// and z out of the print.
fn seen(tag: &TagReport) -> Seen {
    let shift = |p: [f64; 2]| [p[0] - 0.5, p[1] - 0.5];
    let c = tag.corners.map(shift);
    let [u, v] = shift(tag.center);
    // Corners 0, 1, 2, 3 are the tag's (-1, +1), (+1, +1), (+1, -1),
    // (-1, -1) with y down the tag: +x runs from the 0-3 edge to the 1-2 edge.
    let du = (c[1][0] + c[2][0] - c[0][0] - c[3][0]) / 2.0;
    let dv = (c[1][1] + c[2][1] - c[0][1] - c[3][1]) / 2.0;
    let pose = tag.rotation.zip(tag.t).map(|(r, t)| {
        let r = Matrix3::from_fn(|i, j| r[i][j]);
        (
            r * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
            Vector3::from(t),
        )
    });
    Seen {
        u,
        v,
        id: Some(tag.id),
        yaw: Some(dv.atan2(du)),
        pose,
    }
}

fn write_pgm(path: &Path, image: &GrayImage) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(out, "P5\n{} {}\n255\n", image.width(), image.height())?;
    out.write_all(image.as_raw())?;
    out.flush()
}
