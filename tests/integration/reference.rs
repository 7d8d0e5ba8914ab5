//! Outputs compared byte for byte with stored copies in `tests/data/`
//! (see `support::reference`): markers and a small sheet from the binary,
//! and simulated photos with what the detector reads in them.

use std::path::Path;

use image::GrayImage;
use serde_json::json;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::{self, layout, Background, MotionBlur, Scene, SceneObject};

use crate::support::reference::References;
use crate::support::run_ok_in;

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap()
}

#[test]
fn marker_files_match_the_stored_ones() {
    let dir = tempfile::tempdir().unwrap();
    let mut references = References::default();
    for (name, args) in [
        ("marker-8bit-id5.svg", &["--bits", "8", "--id", "5"][..]),
        ("marker-8bit-id5.png", &["--bits", "8", "--id", "5"]),
        ("marker-12bit-id3.svg", &["--bits", "12", "--id", "3"]),
        ("marker-whycon.svg", &["--legacy"]),
        ("marker-whycon.png", &["--legacy", "--dpi", "150"]),
    ] {
        let mut command = vec!["marker", "--diameter", "30mm", "-o", name];
        command.extend_from_slice(args);
        run_ok_in(dir.path(), &command);
        references.check(name, &read(dir.path(), name));
    }
    references.finish();
}

#[test]
fn a_small_sheet_and_its_manifest_match_the_stored_ones() {
    let dir = tempfile::tempdir().unwrap();
    run_ok_in(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--ids",
            "1-4",
            "--diameter",
            "30mm",
            "--template",
            "a5",
            "-o",
            "sheet-a5.pdf",
        ],
    );
    let mut references = References::default();
    references.check("sheet-a5.pdf", &read(dir.path(), "sheet-a5.pdf"));
    references.check("sheet-a5.json", &read(dir.path(), "sheet-a5.json"));
    references.finish();
}

/// A 400x300 photo of `count` markers of the `bits`-bit family, 50 mm
/// across, scattered at about `distance` metres.
fn photo_scene(bits: u32, count: u32, distance: f64, seed: u64) -> Scene {
    let family = Family::generate(bits, 2).unwrap();
    let camera = Camera::ideal(400, 300, 60.0);
    let markers: Vec<(Marker, u32)> = (1..=count)
        .map(|id| (Marker::whycode(bits, family.code(id).unwrap(), 50.0), id))
        .collect();
    let mut scene = Scene::new(camera);
    scene.objects = layout::marker_scatter(&camera, &markers, distance, 0.5, seed)
        .into_iter()
        .map(SceneObject::Marker)
        .collect();
    scene.seed = seed;
    scene
}

fn png_bytes(image: &GrayImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .unwrap();
    bytes
}

#[test]
fn simulated_photos_and_the_ids_read_in_them_match_the_stored_ones() {
    let mut table = photo_scene(8, 5, 0.5, 11);
    table.background = Background::Table;
    table.gradient = 2.0;
    table.noise = 2.0;
    let mut blurred = photo_scene(12, 4, 0.35, 12);
    blurred.motion_blur = Some(MotionBlur {
        length_px: 3.0,
        angle: 0.7,
    });
    blurred.focus_blur_px = 0.6;
    blurred.noise = 1.5;

    let mut references = References::default();
    for (name, bits, scene) in [
        ("photo-8bit-table", 8, table),
        ("photo-12bit-blur", 12, blurred),
    ] {
        let (image, truth) = simulate::render(&scene);
        let mut detector = Detector::new(DetectorConfig {
            target: Target::WhyCode(Family::generate(bits, 2).unwrap()),
            ..DetectorConfig::default()
        });
        let found = detector.detect(&image);

        // Whatever is stored, every marker must be read with its own ID.
        let mut want: Vec<u32> = truth
            .markers
            .iter()
            .filter(|m| m.visible)
            .map(|m| m.id)
            .collect();
        let mut got: Vec<u32> = found.iter().map(|d| d.id).collect();
        want.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, want, "{name}: IDs read vs placed");

        let expected = json!({
            "image": format!("{name}.png"),
            "family": { "bits": bits, "distance": 2 },
            "markers": found
                .iter()
                .map(|d| json!({
                    "id": d.id,
                    "u": round(d.u, 100.0),
                    "v": round(d.v, 100.0),
                    "yaw_deg": d.yaw.map(|y| round(y.to_degrees(), 10.0)),
                }))
                .collect::<Vec<_>>(),
        });
        let mut text = serde_json::to_string_pretty(&expected).unwrap();
        text.push('\n');
        references.check(&format!("{name}.png"), &png_bytes(&image));
        references.check(&format!("{name}.json"), text.as_bytes());
    }
    references.finish();
}

fn round(x: f64, per_unit: f64) -> f64 {
    (x * per_unit).round() / per_unit
}
