//! The original project's own test files: a real photo of legacy markers
//! and a printed sheet of 8-bit WhyCode markers.

use crate::support::{compat_fixture, have_tool};
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::image_io::load_gray;

/// Writes the image with the detections drawn to /tmp when
/// WHYCODE_ANNOTATE is set, to look at.
fn annotate(image: &image::GrayImage, detections: &[Detection], name: &str) {
    if std::env::var_os("WHYCODE_ANNOTATE").is_none() {
        return;
    }
    let mut rgb = image::DynamicImage::ImageLuma8(image.clone()).into_rgb8();
    for d in detections {
        let (s, c) = d.angle.sin_cos();
        for k in 0..720 {
            let t = k as f64 * std::f64::consts::TAU / 720.0;
            let (x, y) = (d.axes[0] * t.cos(), d.axes[1] * t.sin());
            let (px, py) = (d.u + x * c - y * s, d.v + x * s + y * c);
            if px >= 0.0 && py >= 0.0 && (px as u32) < rgb.width() && (py as u32) < rgb.height() {
                rgb.put_pixel(px as u32, py as u32, image::Rgb([255, 0, 0]));
            }
        }
        if let Some(yaw) = d.yaw {
            for k in 0..(d.axes[0] as i32) {
                let (px, py) = (d.u + k as f64 * yaw.cos(), d.v + k as f64 * yaw.sin());
                if px >= 0.0 && py >= 0.0 && (px as u32) < rgb.width() && (py as u32) < rgb.height()
                {
                    rgb.put_pixel(px as u32, py as u32, image::Rgb([0, 200, 0]));
                }
            }
        }
    }
    let out = std::env::temp_dir().join(format!("whycode_{name}.png"));
    rgb.save(&out).unwrap();
    eprintln!("annotated: {}", out.display());
}

#[test]
fn many_png_finds_every_legacy_marker_and_nothing_else() {
    let Some(path) = compat_fixture("many.png") else {
        return;
    };
    let image = load_gray(&path).unwrap();
    let mut detector = Detector::new(DetectorConfig::default());
    let found = detector.detect(&image);
    annotate(&image, &found, "many");
    for d in &found {
        eprintln!(
            "{:7.1} {:7.1}  axes {:5.1} {:5.1}  conf {:.2}",
            d.u, d.v, d.axes[0], d.axes[1], d.confidence
        );
    }
    // The photo holds 48 markers (47 pasted, 1 printed and held up), which
    // the original finds too; checked by eye on the annotated image. Any
    // further detection would be a false one on the background.
    assert_eq!(found.len(), 48, "found {} markers", found.len());
    for d in &found {
        assert!(
            d.axes[0] / d.axes[1] < 1.3,
            "a marker seen nearly face-on: {d:?}"
        );
        assert!(d.axes[1] > 8.0, "{d:?}");
    }
}

#[test]
fn tags_35_reads_every_id_the_original_reads() {
    let Some(pdf) = compat_fixture("tags_35.pdf") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let prefix = dir.path().join("page");
    if !have_tool("pdftoppm", "poppler-utils") {
        return;
    }
    let status = std::process::Command::new("pdftoppm")
        .args(["-r", "150", "-png", "-singlefile"])
        .arg(&pdf)
        .arg(&prefix)
        .status();
    assert!(status.expect("pdftoppm runs").success());
    let image = load_gray(&prefix.with_extension("png")).unwrap();
    let family = whycode::family::Family::generate(8, 1).unwrap();
    let mut detector = Detector::new(DetectorConfig {
        target: Target::WhyCode(family),
        ..DetectorConfig::default()
    });
    let found = detector.detect(&image);
    annotate(&image, &found, "tags_35");
    assert_eq!(found.len(), 35, "{found:?}");
    // Column-major: columns left to right, top to bottom in each column.
    let mut sorted = found.clone();
    sorted.sort_by(|a, b| a.u.total_cmp(&b.u));
    let mut ids = Vec::new();
    for column in sorted.chunks(8) {
        let mut column = column.to_vec();
        column.sort_by(|a, b| a.v.total_cmp(&b.v));
        ids.extend(column.iter().map(|d| d.id));
    }
    let expected = [
        0, 1, 2, 3, 4, 5, 6, 7, 8, 0, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 0, 21, 22, 23,
        24, 25, 0, 26, 27, 28, 29, 0, 30,
    ];
    assert_eq!(ids, expected);
    for d in &found {
        if d.id != 0 {
            assert!(d.yaw.is_some(), "a read ID comes with a yaw: {d:?}");
        }
    }
}
