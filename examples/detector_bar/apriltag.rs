//! AprilTag as the bar measures it: pupil-apriltags (tag36h11, one
//! thread) run by `apriltag.py` on the scenario's frames with tags printed
//! in our markers' places.

use std::path::{Path, PathBuf};
use std::process::Command;

use image::GrayImage;
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use crate::rival::{run_on_frames, Rival, Setup};
use whycode::simulate::Sighting;
use whycode_testkit::scenario::Print;

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
    /// The same detector without decimation (`quad_decimate` 1).
    pub fn full_resolution(&self) -> AprilTag {
        AprilTag {
            python: self.python.clone(),
            script: self.script.clone(),
            quad_decimate: 1.0,
        }
    }

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
        let python = crate::rival::find_python(
            "APRILTAG_PYTHON",
            "import pupil_apriltags, numpy",
            "pupil_apriltags",
            SETUP,
        )?;
        Ok(AprilTag {
            python,
            script,
            quad_decimate,
        })
    }
}

impl Rival for AprilTag {
    fn name(&self) -> &'static str {
        "AprilTag"
    }

    fn print(&self) -> Print {
        Print::AprilTag
    }

    /// Full pose included, as ours.
    fn detect(
        &self,
        setup: &Setup,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Sighting>, f64)>, String> {
        let camera = setup.camera;
        let mut command = Command::new(&self.python);
        command.arg(&self.script);
        let args = [
            "--fx".to_string(),
            camera.fx.to_string(),
            "--fy".into(),
            camera.fy.to_string(),
            // AprilTag's pixel centres are at half-integers (see `seen`).
            "--cx".into(),
            (camera.cx + 0.5).to_string(),
            "--cy".into(),
            (camera.cy + 0.5).to_string(),
            "--tag-size".into(),
            setup.size_m.to_string(),
            "--quad-decimate".into(),
            self.quad_decimate.to_string(),
        ];
        let reports: Vec<FrameReport> = run_on_frames(command, &args, frames)?;
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
fn seen(tag: &TagReport) -> Sighting {
    let shift = |p: [f64; 2]| [p[0] - 0.5, p[1] - 0.5];
    let c = tag.corners.map(shift);
    let [u, v] = shift(tag.center);
    // Corners 0, 1, 2, 3 are the tag's (-1, +1), (+1, +1), (+1, -1),
    // (-1, -1) with y down the tag: +x runs from the 0-3 edge to the 1-2 edge.
    let du = (c[1][0] + c[2][0] - c[0][0] - c[3][0]) / 2.0;
    let dv = (c[1][1] + c[2][1] - c[0][1] - c[3][1]) / 2.0;
    let rotation = tag.rotation.map(|r| {
        Matrix3::from_fn(|i, j| r[i][j]) * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
    });
    Sighting {
        u,
        v,
        id: Some(tag.id),
        yaw: Some(dv.atan2(du)),
        normal: rotation.map(|r| r.column(2).into_owned()),
        rotation,
        position: tag.t.map(Vector3::from),
    }
}
