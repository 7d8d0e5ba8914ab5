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

use image::GrayImage;
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::Deserialize;
use whycode::board::Board;
use whycode::calibrate::{calibrate, disagreement, CalibrationOptions};
use whycode::camera::Camera;
use whycode::detect::{DetectorConfig, Target};
use whycode::session::{Frame, Session, SessionConfig};
use whycode::simulate::Placement;
use whycode_testkit::calibration;

const SETUP: &str = "python3 -m venv target/calib-venv && \
target/calib-venv/bin/pip install opencv-python-headless numpy";

#[derive(Deserialize)]
struct OpenCvReport {
    found: Vec<bool>,
    rms: Option<f64>,
    camera_matrix: Option<Vec<f64>>,
    dist: Option<Vec<f64>>,
    pnp: Option<Vec<Option<PnpPose>>>,
    opencv: String,
}

#[derive(Deserialize)]
struct PnpPose {
    rvec: [f64; 3],
    tvec: [f64; 3],
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
        "pnp_camera": {
            "K": [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0],
            "dist": camera.distortion,
        },
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

/// The page's pose (board frame: top-left corner, x right, y down, z into
/// the page) from the simulator's placement of the page centre.
fn true_board_pose(placement: &Placement) -> (Matrix3<f64>, Vector3<f64>) {
    let [w, h] = calibration::PAGE_MM;
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    (
        placement.rotation * flip,
        placement.to_camera_mm(-w / 2.0, h / 2.0),
    )
}

/// Rotation error (degrees) and position error (fraction of the distance).
fn pose_error(
    truth: &(Matrix3<f64>, Vector3<f64>),
    rotation: &Matrix3<f64>,
    position: &Vector3<f64>,
) -> (f64, f64) {
    let angle = Rotation3::from_matrix(&(truth.0.transpose() * rotation))
        .angle()
        .to_degrees();
    (angle, (position - truth.1).norm() / truth.1.norm())
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

fn worst(values: &[f64]) -> f64 {
    values.iter().copied().fold(f64::NAN, f64::max)
}

/// Per view: rotation error (degrees), position error (fraction of the distance).
type PoseErrors = (Vec<f64>, Vec<f64>);

/// Board poses through the true camera: ours from the sheet's markers
/// (a session's board poses), one per view seen.
fn our_board_errors(
    truth: &Camera,
    manifest: &whycode::manifest::Manifest,
    sheets: &[(String, GrayImage)],
    poses: &[Placement],
) -> PoseErrors {
    let family = whycode::family::Family::generate(10, 2).expect("the sheet's family");
    let mut session = Session::new(SessionConfig {
        boards: vec![Board::from_manifest_page(manifest, 1, "sheet".into(), 1.0)],
        ..SessionConfig::detector(DetectorConfig {
            target: Target::WhyCode(family),
            camera: Some(*truth),
            diameter_m: Some(calibration::MARKER_DIAMETER_MM / 1000.0),
            max_markers: 100,
            ..Default::default()
        })
    });
    let (mut rotations, mut positions) = (Vec::new(), Vec::new());
    for ((name, image), placement) in sheets.iter().zip(poses) {
        session.reset();
        let report = session
            .process(Frame::new(image, name.as_str()))
            .expect("the views are of the camera's size");
        if let Some(pose) = report.boards.first() {
            let (r, p) = pose_error(&true_board_pose(placement), &pose.rotation, &pose.position);
            rotations.push(r);
            positions.push(p);
        }
    }
    (rotations, positions)
}

/// OpenCV's solvePnP poses on the chessboard's corners through the true
/// camera. Its corner order may start at either end of the board (a 180°
/// turn about the page centre): the labelling nearer the truth is taken.
fn opencv_board_errors(pnp: &[Option<PnpPose>], poses: &[Placement]) -> PoseErrors {
    let [w, h] = calibration::PAGE_MM;
    let centre = Vector3::new(w / 1000.0, h / 1000.0, 0.0);
    let half_turn = Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0));
    let (mut rotations, mut positions) = (Vec::new(), Vec::new());
    for (found, placement) in pnp.iter().zip(poses) {
        let Some(found) = found else { continue };
        let rotation = *Rotation3::new(Vector3::from(found.rvec)).matrix();
        let position = Vector3::from(found.tvec);
        let truth = true_board_pose(placement);
        let direct = pose_error(&truth, &rotation, &position);
        let turned = pose_error(
            &truth,
            &(rotation * half_turn),
            &(position + rotation * centre),
        );
        let best = if direct.0 <= turned.0 { direct } else { turned };
        rotations.push(best.0);
        positions.push(best.1);
    }
    (rotations, positions)
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
    let mut board_rows: Vec<(&str, PoseErrors)> = vec![(
        "whycode (markers)",
        our_board_errors(&truth, &manifest, &sheets, &poses),
    )];
    match opencv(&boards, &truth) {
        Ok(report) => {
            if let Some(pnp) = &report.pnp {
                board_rows.push(("OpenCV solvePnP", opencv_board_errors(pnp, &poses)));
            }
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
    println!();
    println!("Board pose through the true camera (page frame), per view:");
    println!(
        "{:<20} {:>6} {:>12} {:>12} {:>12} {:>12}",
        "", "views", "rot med °", "rot worst °", "pos med %", "pos worst %"
    );
    for (name, (mut rotations, mut positions)) in board_rows {
        let n = rotations.len();
        let (rw, pw) = (worst(&rotations), worst(&positions));
        println!(
            "{name:<20} {:>6} {:>12.4} {:>12.4} {:>12.4} {:>12.4}",
            format!("{n}/{count}"),
            median(&mut rotations),
            rw,
            100.0 * median(&mut positions),
            100.0 * pw
        );
    }
    println!("(pos: distance from the true board origin, % of its distance from the camera)");
}
