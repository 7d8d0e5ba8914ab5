//! Simulator and detector together: scattered markers on a cluttered
//! background are found where the ground truth says, with their IDs and
//! yaw, and the clutter (rings and discs that are not markers) raises no
//! detections. Also the `simulate` CLI's loose-marker mode.

use crate::support::run_ok;
use whycode::math::angle::angle_between;

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
            angle_between(yaw, t.yaw) < 0.1,
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
        assert!(angle_between(m.yaw, -30f64.to_radians()) < 1e-9);
    }
    let image = image::open(&out).unwrap();
    assert_eq!((image.width(), image.height()), (640, 480));
}

/// "This marker at this pixel, this many pixels across", through a lens
/// with strong barrel distortion: each marker's true centre lands on its
/// pixel and its face-on size on its diameter, also in the frame's
/// corners; then detected, matched with the truth and scored: every one
/// found on its pixel with its own ID and yaw, and its pose's normal; the
/// one printed square no detector here reads is missed, not misread.
#[test]
fn markers_placed_at_pixels_land_there_and_are_found_and_matched() {
    use whycode::simulate::{
        match_reports, IdRead, LooseMarker, Placement, PrintedSquare, Reach, Sighting,
    };
    let family = Family::generate(8, 2).unwrap();
    let camera = Camera {
        distortion: [-0.28, 0.09, 0.0008, -0.0005, 0.0],
        ..Camera::ideal(1280, 720, 70.0)
    };
    let cases = [
        ((640.0, 360.0), 90.0, (0.0, 0.0)),
        ((110.3, 95.7), 70.0, (0.0, 0.0)),
        ((1190.0, 640.0), 60.0, (0.0, 0.0)),
        ((400.0, 560.0), 80.0, (0.6, 0.3)),
        ((980.0, 150.0), 75.0, (-0.4, 0.5)),
    ];
    let mut scene = Scene::new(camera);
    for (k, &((u, v), diameter_px, (tilt, pan))) in cases.iter().enumerate() {
        let id = 3 * k as u32 + 1;
        let marker = Marker::whycode(8, family.code(id).unwrap(), 60.0);
        let roll = 0.7 * k as f64;
        let placement = Placement::at_pixel(&camera, &marker, (u, v), diameter_px, tilt, pan, roll);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    }
    // A square card no WhyCode detector reads, at the centre of the left edge.
    let square = image::GrayImage::from_fn(6, 6, |x, y| {
        image::Luma([if (x + y) % 2 == 0 { 0 } else { 255 }])
    });
    let marker = Marker::whycon(60.0);
    let placement = Placement::at_pixel(&camera, &marker, (200.0, 360.0), 60.0, 0.0, 0.0, 0.0);
    scene.objects.push(SceneObject::Square(PrintedSquare::new(
        square, 60.0, 99, placement,
    )));
    scene.noise = 1.5;
    let (image, truth) = render(&scene);
    for (m, &((u, v), diameter_px, (tilt, pan))) in truth.markers.iter().zip(&cases) {
        assert!(
            (m.u - u).hypot(m.v - v) < 1e-6,
            "marker {} at ({}, {}), asked for ({u}, {v})",
            m.id,
            m.u,
            m.v
        );
        if (tilt, pan) == (0.0, 0.0) {
            // Distortion's stretch varies across the disc: first order.
            let size = m.diameter_px / diameter_px;
            assert!((size - 1.0).abs() < 0.01, "marker {}: {size}", m.id);
        }
    }
    let mut detector = Detector::new(DetectorConfig {
        target: Target::WhyCode(family),
        camera: Some(camera),
        diameter_m: Some(0.06),
        ..Default::default()
    });
    let found: Vec<Sighting> = detector.detect(&image).iter().map(Sighting::from).collect();
    let targets = truth.targets();
    assert_eq!(targets.len(), cases.len() + 1);
    let matched = match_reports(&targets, &found, Reach::default());
    assert!(matched.false_reports.is_empty(), "{found:?}");
    assert_eq!(matched.missed(), vec![cases.len()], "{found:?}");
    for &(t, d) in &matched.pairs[..cases.len()] {
        let (m, d) = (&targets[t], &found[d.expect("found")]);
        assert_eq!(m.id_read(d.id), IdRead::Right, "{d:?}");
        assert!(m.centre_error((d.u, d.v)) < 0.2, "{d:?} vs {m:?}");
        let yaw = m.yaw_error(d.yaw.expect("a yaw"));
        assert!(
            yaw.abs() < 0.5f64.to_radians(),
            "marker {}: yaw {yaw}",
            m.id
        );
        let normal = m.normal_error(&d.normal.expect("a pose"));
        assert!(
            normal < 2f64.to_radians(),
            "marker {}: normal {normal}",
            m.id
        );
    }
}
