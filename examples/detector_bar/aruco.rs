//! OpenCV's ArUco as the bar measures it: `cv2.aruco` (DICT_4X4_50,
//! default parameters, one thread) run by `aruco.py` on the scenario's
//! frames with 4x4 tags printed in our markers' places.

use std::path::{Path, PathBuf};
use std::process::Command;

use image::GrayImage;
use serde::Deserialize;

use crate::rival::{run_on_frames, Rival, Setup};
use whycode::simulate::Sighting;
use whycode_testkit::scenario::Print;

/// The one-line setup the bar prints when ArUco cannot be run.
pub const SETUP: &str =
    "python3 -m venv target/bench-venv && target/bench-venv/bin/pip install opencv-python-headless";

/// A Python that can import cv2 with its aruco module, and the script.
pub struct Aruco {
    python: PathBuf,
    script: PathBuf,
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
}

impl Aruco {
    /// `$ARUCO_PYTHON`, else `target/bench-venv` of this checkout, else
    /// `python3`: the first that imports cv2.aruco. The error says why
    /// none did.
    pub fn find() -> Result<Aruco, String> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let script = root.join("examples/detector_bar/aruco.py");
        let python = crate::rival::find_python(
            "ARUCO_PYTHON",
            "import cv2; cv2.aruco.ArucoDetector",
            "cv2.aruco",
            SETUP,
        )?;
        Ok(Aruco { python, script })
    }
}

impl Rival for Aruco {
    fn name(&self) -> &'static str {
        "ArUco"
    }

    fn print(&self) -> Print {
        Print::Aruco4x4
    }

    /// IDs and centres; no pose (the bar's ArUco rows count IDs).
    fn detect(
        &self,
        _setup: &Setup,
        frames: &[&GrayImage],
    ) -> Result<Vec<(Vec<Sighting>, f64)>, String> {
        let mut command = Command::new(&self.python);
        command.arg(&self.script);
        let reports: Vec<FrameReport> = run_on_frames(command, &[], frames)?;
        Ok(reports
            .into_iter()
            .map(|r| (r.tags.iter().map(seen).collect(), r.ms))
            .collect())
    }
}

/// An ArUco report in our terms. OpenCV's pixel centres are at integers,
/// as ours; its corners run top left, top right, bottom right, bottom left
/// of the tag as printed, so +x runs from the 0-3 edge to the 1-2 edge.
fn seen(tag: &TagReport) -> Sighting {
    let c = tag.corners;
    let du = (c[1][0] + c[2][0] - c[0][0] - c[3][0]) / 2.0;
    let dv = (c[1][1] + c[2][1] - c[0][1] - c[3][1]) / 2.0;
    Sighting {
        u: tag.center[0],
        v: tag.center[1],
        id: Some(tag.id),
        yaw: Some(dv.atan2(du)),
        normal: None,
        rotation: None,
        position: None,
    }
}
