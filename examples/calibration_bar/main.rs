//! Calibration against OpenCV's chessboard, on the same simulated views in
//! one run: an A4 sheet of 35 markers and a chessboard of the same printed
//! footprint (7 × 11 squares of 25 mm), each seen from the same poses
//! 0.35-0.6 m from a 1280×960 camera with k1 = −0.26. Ours is
//! `whycode::calibrate`; OpenCV's is findChessboardCorners + cornerSubPix
//! + calibrateCamera (`opencv_chessboard.py`, opencv-python-headless).
//!
//! Printed: views used, reprojection RMS, the disagreement between the
//! recovered and the true camera over the whole image (mean and worst, on
//! a 4-pixel grid) and the focal lengths' errors.
//!
//! ```text
//! python3 -m venv target/calib-venv && target/calib-venv/bin/pip install opencv-python-headless numpy
//! cargo run --release --example calibration_bar [-- VIEWS [SEED]]
//! ```

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde::Deserialize;
use whycode::calibrate::{calibrate, disagreement, CalibrationOptions};
use whycode::camera::Camera;
use whycode_testkit::calibration;

const SETUP: &str = "python3 -m venv target/calib-venv && \
target/calib-venv/bin/pip install opencv-python-headless numpy";

#[derive(Deserialize)]
struct OpenCvReport {
    found: Vec<bool>,
    rms: Option<f64>,
    camera_matrix: Option<Vec<f64>>,
    dist: Option<Vec<f64>>,
    opencv: String,
}

fn python() -> Result<PathBuf, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let candidates: Vec<PathBuf> = match std::env::var_os("OPENCV_PYTHON") {
        Some(p) => vec![PathBuf::from(p)],
        None => vec![
            root.join("target/calib-venv/bin/python"),
            PathBuf::from("python3"),
        ],
    };
    candidates
        .into_iter()
        .find(|p| {
            Command::new(p)
                .args(["-c", "import cv2, numpy"])
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .ok_or_else(|| format!("no Python with cv2; set up with `{SETUP}` (or set OPENCV_PYTHON)"))
}

fn opencv(images: &[PathBuf], camera: &Camera) -> Result<OpenCvReport, String> {
    let python = python()?;
    let script =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/calibration_bar/opencv_chessboard.py");
    let (cols, rows) = calibration::CHESS_SQUARES;
    let job = serde_json::json!({
        "images": images,
        "pattern": [cols - 1, rows - 1],
        "corners_mm": calibration::chessboard_corners_mm(),
        "width": camera.width,
        "height": camera.height,
    });
    let mut child = Command::new(python)
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| e.to_string())?;
    serde_json::to_writer(child.stdin.take().expect("piped"), &job).map_err(|e| e.to_string())?;
    let out = child.wait_with_output().map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err("opencv_chessboard.py failed".into());
    }
    serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())
}

struct Row {
    views: String,
    rms: f64,
    mean: f64,
    worst: f64,
    fx: f64,
    fy: f64,
}

fn row(truth: &Camera, camera: &Camera, used: usize, total: usize, rms: f64) -> Row {
    let d = disagreement(truth, camera);
    Row {
        views: format!("{used}/{total}"),
        rms,
        mean: d.mean,
        worst: d.worst,
        fx: 100.0 * (camera.fx / truth.fx - 1.0),
        fy: 100.0 * (camera.fy / truth.fy - 1.0),
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let count: usize = args
        .next()
        .map_or(15, |a| a.parse().expect("VIEWS is a number"));
    let seed: u64 = args
        .next()
        .map_or(1, |a| a.parse().expect("SEED is a number"));
    let truth = calibration::lens();
    let manifest = calibration::a4_sheet();
    let poses = calibration::views(&truth, count, seed);
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mut sheets = Vec::new();
    let mut boards = Vec::new();
    for (k, placement) in poses.iter().enumerate() {
        let seed = seed * 1000 + k as u64;
        sheets.push((
            format!("sheet{k:02}.png"),
            calibration::sheet_view(&truth, &manifest, *placement, seed),
        ));
        let path = dir.path().join(format!("chess{k:02}.png"));
        calibration::chessboard_view(&truth, *placement, seed)
            .save(&path)
            .expect("a PNG in the temporary folder");
        boards.push(path);
    }
    if let Ok(folder) = std::env::var("CALIBRATION_BAR_SAVE") {
        for (name, image) in &sheets {
            image
                .save(Path::new(&folder).join(name))
                .expect("saved view");
        }
        for path in &boards {
            std::fs::copy(path, Path::new(&folder).join(path.file_name().unwrap()))
                .expect("copied view");
        }
    }

    let ours = calibrate(&manifest, &sheets, &CalibrationOptions::default());
    let mut rows: Vec<(&str, Option<Row>)> = Vec::new();
    match &ours {
        Ok(c) => {
            print!("{}", c.to_table());
            rows.push((
                "whycode (markers)",
                Some(row(&truth, &c.camera, c.views.len(), count, c.rms)),
            ));
        }
        Err(e) => {
            println!("whycode refused: {e}");
            rows.push(("whycode (markers)", None));
        }
    }
    let mut version = String::new();
    match opencv(&boards, &truth) {
        Ok(report) => {
            version = report.opencv.clone();
            let used = report.found.iter().filter(|&&f| f).count();
            let camera = report
                .camera_matrix
                .as_ref()
                .zip(report.dist.as_ref())
                .map(|(k, d)| Camera {
                    fx: k[0],
                    fy: k[4],
                    cx: k[2],
                    cy: k[5],
                    distortion: [d[0], d[1], d[2], d[3], d.get(4).copied().unwrap_or(0.0)],
                    width: truth.width,
                    height: truth.height,
                });
            rows.push((
                "OpenCV (chessboard)",
                camera.map(|c| row(&truth, &c, used, count, report.rms.unwrap_or(f64::NAN))),
            ));
        }
        Err(e) => println!("OpenCV not run: {e}"),
    }
    println!();
    println!(
        "{count} views of an A4 target 0.35-0.6 m from a 1280x960 camera, k1 = {}, seed {seed}{}",
        truth.distortion[0],
        if version.is_empty() {
            String::new()
        } else {
            format!("; OpenCV {version}")
        }
    );
    println!(
        "{:<20} {:>6} {:>9} {:>11} {:>11} {:>9} {:>9}",
        "", "views", "RMS px", "mean px", "worst px", "fx err %", "fy err %"
    );
    for (name, r) in rows {
        match r {
            Some(r) => println!(
                "{name:<20} {:>6} {:>9.4} {:>11.4} {:>11.4} {:>9.4} {:>9.4}",
                r.views, r.rms, r.mean, r.worst, r.fx, r.fy
            ),
            None => println!("{name:<20} no calibration"),
        }
    }
    println!("(mean/worst: distance between where the recovered and the true camera put each ray, over a 4-px grid of the whole image)");
}
