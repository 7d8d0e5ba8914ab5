//! Board and bundle poses on simulated photos through a distorting lens:
//! a sheet with half its markers painted over (through `detect --board`),
//! and a bundle of markers on three faces of a cube.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::support::run_ok;
use whycode::board::Board;
use whycode::detect::{DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::session::{Frame, Session, SessionConfig};
use whycode::simulate::{self, Blot, LooseMarker, Placement, Scene, SceneObject, SheetPage};
use whycode_testkit::calibration;

fn angle_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    Rotation3::from_matrix(&(a.transpose() * b))
        .angle()
        .to_degrees()
}

#[test]
fn a_sheet_with_half_its_markers_covered_gives_the_page_pose() {
    let dir = tempfile::tempdir().unwrap();
    let truth = calibration::lens();
    let manifest = calibration::a4_sheet();
    let placement = calibration::views(&truth, 3, 11)[2];
    let mut page = SheetPage::new(manifest.clone(), 1, placement);
    // White paint over every other marker: half the board unseen.
    for m in manifest.markers.iter().filter(|m| m.id % 2 == 0) {
        page.blots.push(Blot {
            x_mm: m.x_mm,
            y_mm: m.y_mm,
            radius_mm: m.diameter_mm * 0.7,
            black: false,
        });
    }
    let mut scene = Scene::new(truth);
    scene.objects.push(SceneObject::Page(page));
    scene.focus_blur_px = 0.6;
    scene.noise = 1.5;
    let image = simulate::render(&scene).0;
    let photo = dir.path().join("view.png");
    image.save(&photo).unwrap();
    let sheet = dir.path().join("sheet.json");
    std::fs::write(&sheet, serde_json::to_string(&manifest).unwrap()).unwrap();
    let camera = dir.path().join("camera.yaml");
    std::fs::write(&camera, truth.to_ros_yaml("lens")).unwrap();

    let out = run_ok(&[
        "detect",
        "--bits",
        "10",
        "--distance",
        "2",
        // No --diameter: the board's markers give theirs.
        "--camera",
        camera.to_str().unwrap(),
        "--board",
        sheet.to_str().unwrap(),
        "--format",
        "json",
        photo.to_str().unwrap(),
    ]);
    let frame: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let board = &frame["boards"][0];
    assert_eq!(board["name"], "sheet", "{out}");
    let used: Vec<u64> = board["used"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert!(used.len() >= 16, "{board}");
    assert!(used.iter().all(|id| id % 2 == 1), "{board}");

    // The page's top-left corner, x right, y down, z into the page, in
    // the simulator's page frame (centre, y up, z out).
    let [w, h] = calibration::PAGE_MM;
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    let true_rotation = placement.rotation * flip;
    let true_position = placement.to_camera_mm(-w / 2.0, h / 2.0);
    let position = Vector3::from_iterator(
        board["position"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap()),
    );
    let rotation = Matrix3::from_iterator(
        board["rotation"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|row| row.as_array().unwrap().iter().map(|v| v.as_f64().unwrap())),
    )
    .transpose();
    let distance = true_position.norm();
    let rotation_error = angle_deg(&rotation, &true_rotation);
    let position_error = (position - true_position).norm() / distance;
    assert!(
        rotation_error < 0.05,
        "rotation off by {rotation_error}°: {board}"
    );
    assert!(
        position_error < 5e-4,
        "position off by {:.4} % of the distance: {board}",
        100.0 * position_error
    );
}

/// A marker's ID, its centre in the cube's frame and its orientation there.
type Face = (u32, Vector3<f64>, UnitQuaternion<f64>);

/// The cube's faces as 40 mm markers on cards, the cube's centre at
/// `position` turned by `rotation`, seen by `camera`.
fn cube_scene(
    camera: whycode::camera::Camera,
    family: &Family,
    faces: &[Face],
    rotation: &Matrix3<f64>,
    position: Vector3<f64>,
) -> Scene {
    let mut scene = Scene::new(camera);
    for (id, p, q) in faces {
        let marker = Marker::whycode(10, family.code(*id).unwrap(), 40.0);
        let placement = Placement::new(
            position + rotation * p,
            rotation * q.to_rotation_matrix().matrix(),
        );
        let mut loose = LooseMarker::new(marker, *id, placement);
        loose.card_half_mm = 29.0;
        scene.objects.push(SceneObject::Marker(loose));
    }
    scene
}

/// A session reading the cube's 40 mm markers of `family` through
/// `camera` and reporting the pose of `boards`.
fn cube_session(
    camera: whycode::camera::Camera,
    family: &Family,
    boards: Vec<Board>,
    tracking: bool,
) -> Session {
    Session::new(SessionConfig {
        boards,
        ..SessionConfig::detector(DetectorConfig {
            target: Target::WhyCode(family.clone()),
            camera: Some(camera),
            diameter_m: Some(0.04),
            tracking,
            ..Default::default()
        })
    })
}

/// A marker on each of the first `faces` of a 6 cm cube (+z, +x, +y faces;
/// each marker's +z out of its face) and the bundle describing them.
fn cube(faces: usize) -> (Vec<Face>, Vec<Board>) {
    let side = 0.06;
    let faces: Vec<_> = [
        (
            1,
            Vector3::new(0.0, 0.0, side / 2.0),
            UnitQuaternion::identity(),
        ),
        (
            2,
            Vector3::new(side / 2.0, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
        ),
        (
            3,
            Vector3::new(0.0, side / 2.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2),
        ),
    ]
    .into_iter()
    .take(faces)
    .collect();
    let bundle: String = std::iter::once("bundles:\n  - name: cube\n    layout:\n".to_string())
        .chain(faces.iter().map(|(id, p, q)| {
            format!(
                "      - {{id: {id}, diameter: 0.04, x: {}, y: {}, z: {}, qw: {}, qx: {}, qy: {}, qz: {}}}\n",
                p.x, p.y, p.z, q.w, q.i, q.j, q.k
            )
        }))
        .collect();
    (faces, Board::parse_bundles(&bundle).unwrap())
}

#[test]
fn a_bundle_on_a_cube_gives_the_cube_pose() {
    let truth = calibration::lens();
    let family = Family::generate(10, 2).unwrap();
    let (faces, boards) = cube(3);

    let cube_rotation = *Rotation3::rotation_between(
        &Vector3::new(1.0, 1.0, 1.0),
        &Vector3::new(0.15, -0.1, -1.0),
    )
    .unwrap()
    .matrix();
    let cube_position = Vector3::new(0.03, -0.02, 0.45);
    let mut scene = cube_scene(truth, &family, &faces, &cube_rotation, cube_position);
    scene.focus_blur_px = 0.6;
    scene.noise = 1.5;
    let image = simulate::render(&scene).0;

    let report = cube_session(truth, &family, boards, false)
        .process(Frame::new(&image, "cube"))
        .unwrap();
    let (found, poses) = (report.markers, report.boards);
    assert_eq!(poses.len(), 1, "{found:?}");
    let pose = &poses[0];
    assert_eq!(pose.used, vec![1, 2, 3], "{pose:?}");
    let rotation_error = angle_deg(&pose.rotation, &cube_rotation);
    let position_error = (pose.position - cube_position).norm();
    assert!(
        rotation_error < 0.2,
        "rotation off by {rotation_error}°: {pose:?}"
    );
    assert!(
        position_error < 0.5e-3,
        "position off by {position_error} m: {pose:?}"
    );
}

/// A cube moving steadily past a noisy camera: each frame's own fit
/// jitters, the tracked stream's board pose (smoothed over the frames)
/// stays closer to the truth once the filter has learnt the motion.
#[test]
fn a_tracked_board_is_smoothed_over_the_frames() {
    let truth = calibration::lens();
    let family = Family::generate(10, 2).unwrap();
    let (faces, boards) = cube(2);
    let cube_rotation = *Rotation3::rotation_between(
        &Vector3::new(1.0, 0.2, 1.0),
        &Vector3::new(0.15, -0.1, -1.0),
    )
    .unwrap()
    .matrix();
    let (mut tracked, mut single) = (
        cube_session(truth, &family, boards.clone(), true),
        cube_session(truth, &family, boards, false),
    );
    let (mut smoothed_sq, mut raw_sq, mut counted) = (0.0, 0.0, 0);
    for frame in 0u32..40 {
        let cube_position = Vector3::new(-0.02 + 0.0003 * f64::from(frame), -0.02, 0.7);
        let mut scene = cube_scene(truth, &family, &faces, &cube_rotation, cube_position);
        scene.focus_blur_px = 1.0;
        scene.noise = 6.0;
        scene.seed = u64::from(frame) + 7;
        let image = simulate::render(&scene).0;
        let smoothed = tracked.process(Frame::new(&image, "cube")).unwrap().boards;
        let raw = single.process(Frame::new(&image, "cube")).unwrap().boards;
        assert_eq!((smoothed.len(), raw.len()), (1, 1), "frame {frame}");
        if frame >= 20 {
            smoothed_sq += (smoothed[0].position - cube_position).norm_squared();
            raw_sq += (raw[0].position - cube_position).norm_squared();
            counted += 1;
        }
    }
    let rms = |sq: f64| (sq / f64::from(counted)).sqrt() * 1000.0;
    assert!(
        rms(smoothed_sq) < 0.8 * rms(raw_sq),
        "smoothed {:.3} mm RMS, each frame alone {:.3} mm",
        rms(smoothed_sq),
        rms(raw_sq)
    );
}

/// A bundle may give its markers' positions only (as apriltag_ros's may):
/// the pose then comes from the centres, started from where the markers'
/// own poses put them.
#[test]
fn a_bundle_of_positions_only_gives_the_cube_pose() {
    let truth = calibration::lens();
    let family = Family::generate(10, 2).unwrap();
    let (faces, _) = cube(3);
    let bundle: String = std::iter::once("bundles:\n  - name: cube\n    layout:\n".to_string())
        .chain(faces.iter().map(|(id, p, _)| {
            format!(
                "      - {{id: {id}, diameter: 0.04, x: {}, y: {}, z: {}}}\n",
                p.x, p.y, p.z
            )
        }))
        .collect();
    let boards = Board::parse_bundles(&bundle).unwrap();
    assert!(boards[0].markers.iter().all(|m| m.rotation.is_none()));
    let cube_rotation = *Rotation3::rotation_between(
        &Vector3::new(1.0, 1.0, 1.0),
        &Vector3::new(0.15, -0.1, -1.0),
    )
    .unwrap()
    .matrix();
    let cube_position = Vector3::new(0.03, -0.02, 0.45);
    let scene = cube_scene(truth, &family, &faces, &cube_rotation, cube_position);
    let image = simulate::render(&scene).0;
    let report = cube_session(truth, &family, boards, false)
        .process(Frame::new(&image, "cube"))
        .unwrap();
    let (found, poses) = (report.markers, report.boards);
    assert_eq!(poses.len(), 1, "no pose from positions only: {found:?}");
    let pose = &poses[0];
    assert_eq!(pose.used, vec![1, 2, 3], "{pose:?}");
    assert!(angle_deg(&pose.rotation, &cube_rotation) < 1.0, "{pose:?}");
    assert!((pose.position - cube_position).norm() < 2e-3, "{pose:?}");
}
