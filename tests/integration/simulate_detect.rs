//! Simulator and detector together: scattered markers on a cluttered
//! background are found where the ground truth says, with their IDs and
//! yaw, and the clutter (rings and discs that are not markers) raises no
//! detections. Also the `simulate` CLI's loose-marker mode.

use crate::support::{angle_diff, run_ok};

use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::{layout, render, Background, GroundTruth, Scene, SceneObject};

#[test]
fn scattered_markers_on_clutter_are_found_with_ids_and_yaw() {
    let family = Family::generate(8, 2).unwrap();
    let camera = Camera::ideal(1280, 960, 60.0);
    let markers: Vec<(Marker, u32)> = (1..=12)
        .map(|id| (Marker::whycode(8, family.code(id).unwrap(), 60.0), id))
        .collect();
    let mut scene = Scene::new(camera);
    scene.objects.extend(
        layout::marker_scatter(&camera, &markers, 0.9, 20f64.to_radians(), 3)
            .into_iter()
            .map(SceneObject::Marker),
    );
    assert!(
        scene.objects.len() >= 10,
        "only {} placed",
        scene.objects.len()
    );
    scene.background = Background::Clutter { density: 1.0 };
    scene.noise = 2.0;
    scene.focus_blur_px = 0.7;
    scene.seed = 3;
    let (image, truth) = render(&scene);
    let mut detector = Detector::new(DetectorConfig {
        target: Target::WhyCode(family),
        ..Default::default()
    });
    let detections = detector.detect(&image);
    for t in truth.markers.iter().filter(|t| t.visible) {
        let e = t.ellipse.unwrap();
        let d = detections
            .iter()
            .find(|d| (d.u - e.u).hypot(d.v - e.v) < 1.0)
            .unwrap_or_else(|| panic!("marker {} at ({:.1}, {:.1}) not found", t.id, e.u, e.v));
        assert_eq!(d.id, t.id, "marker at ({:.1}, {:.1})", e.u, e.v);
        let yaw = d.yaw.expect("yaw of an identified marker");
        assert!(
            angle_diff(yaw, t.yaw) < 0.1,
            "marker {}: yaw {yaw:.3} vs truth {:.3}",
            t.id,
            t.yaw
        );
    }
    let false_positives: Vec<_> = detections
        .iter()
        .filter(|d| {
            truth
                .markers
                .iter()
                .all(|t| (d.u - t.u).hypot(d.v - t.v) > t.diameter_px / 2.0)
        })
        .collect();
    assert!(false_positives.is_empty(), "{false_positives:?}");
}

#[test]
fn cli_loose_markers_write_image_and_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene.png");
    run_ok(&[
        "simulate",
        "--bits",
        "12",
        "--ids",
        "1-4,9",
        "--diameter",
        "40mm",
        "--size",
        "640x480",
        "--camera-distance",
        "0.6m",
        "--roll",
        "30deg",
        "-o",
        out.to_str().unwrap(),
    ]);
    let truth: GroundTruth =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene.json")).unwrap())
            .unwrap();
    let ids: Vec<u32> = truth.markers.iter().map(|m| m.id).collect();
    assert_eq!(ids, [1, 2, 3, 4, 9]);
    let family = Family::generate(12, 2).unwrap();
    for m in &truth.markers {
        assert_eq!(m.code, family.code(m.id).unwrap());
        assert!(m.visible);
        // Rolled 30° counter-clockwise as seen: +x points up-right, v down.
        assert!(angle_diff(m.yaw, -30f64.to_radians()) < 1e-9);
    }
    let image = image::open(&out).unwrap();
    assert_eq!((image.width(), image.height()), (640, 480));
}
