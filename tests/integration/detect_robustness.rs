//! No panic on any input: degenerate and random images, every supported
//! file format, truncated and corrupt files, absurd dimensions.

use std::path::Path;

use crate::support::Pcg32;
use image::{GrayImage, Luma};
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::WHYCON_WHITE_RATIO;
use whycode::image_io::load_gray;

fn detectors() -> Vec<Detector> {
    let family = Family::generate(8, 2).unwrap();
    vec![
        Detector::new(DetectorConfig::default()),
        Detector::new(DetectorConfig {
            target: Target::WhyCode(family.clone()),
            ..DetectorConfig::default()
        }),
        Detector::new(DetectorConfig {
            target: Target::WhyCode(family),
            tracking: true,
            ..DetectorConfig::default()
        }),
    ]
}

#[test]
fn degenerate_sizes_give_no_detection() {
    for mut detector in detectors() {
        for (w, h) in [
            (0, 0),
            (1, 1),
            (0, 5),
            (5, 0),
            (1, 400),
            (400, 1),
            (2, 2),
            (3, 3),
            (4, 7),
        ] {
            for value in [0u8, 255] {
                let image = GrayImage::from_pixel(w, h, Luma([value]));
                assert!(detector.detect(&image).is_empty(), "{w}x{h}");
            }
        }
    }
}

/// Random content of many kinds and sizes, frames of changing size fed to
/// the same (tracking) detector: it must neither panic nor report IDs that
/// are no member.
#[test]
fn random_images_never_panic() {
    let mut rng = Pcg32::new(2024, 0);
    let family = Family::generate(8, 2).unwrap();
    let mut detectors = detectors();
    for round in 0..60 {
        let w = 1 + (rng.next_f64() * 260.0) as u32;
        let h = 1 + (rng.next_f64() * 200.0) as u32;
        let kind = round % 5;
        let mut image = GrayImage::new(w, h);
        let (cx, cy, r) = (
            rng.range(0.0, w as f64),
            rng.range(0.0, h as f64),
            rng.range(1.0, 80.0),
        );
        for (x, y, p) in image.enumerate_pixels_mut() {
            let (xf, yf) = (x as f64, y as f64);
            p.0[0] = match kind {
                0 => (rng.next_u32() & 255) as u8,
                1 => {
                    if (rng.next_u32() & 7) == 0 {
                        0
                    } else {
                        255
                    }
                }
                2 => (((xf - cx).hypot(yf - cy) / r * 3.0).sin() * 127.0 + 128.0) as u8,
                3 => ((x / 3 + y / 5) % 2 * 255) as u8,
                _ => {
                    let d = (xf - cx).hypot(yf - cy) / r;
                    if !(WHYCON_WHITE_RATIO..=1.0).contains(&d) {
                        (200.0 + 20.0 * rng.gaussian()).clamp(0.0, 255.0) as u8
                    } else {
                        (30.0 + 20.0 * rng.gaussian()).clamp(0.0, 255.0) as u8
                    }
                }
            };
        }
        for detector in &mut detectors {
            for d in detector.detect(&image) {
                assert!(d.u.is_finite() && d.v.is_finite() && d.axes.iter().all(|a| a.is_finite()));
                assert!((0.0..=1.0).contains(&d.confidence), "{d:?}");
                if d.id != 0 {
                    assert_eq!(
                        family.code(d.id),
                        d.code,
                        "an ID always comes with its member code"
                    );
                }
            }
        }
    }
}

fn sample_image() -> GrayImage {
    GrayImage::from_fn(37, 23, |x, y| Luma([(x * 7 + y * 3) as u8]))
}

#[test]
fn every_supported_format_loads_as_grey() {
    let dir = tempfile::tempdir().unwrap();
    let grey = sample_image();
    let rgb = image::DynamicImage::ImageLuma8(grey.clone()).into_rgb8();
    let grey16 = image::DynamicImage::ImageLuma8(grey.clone()).into_luma16();
    let rgba16 = image::DynamicImage::ImageLuma8(grey.clone()).into_rgba16();
    let cases: Vec<(&str, image::DynamicImage)> = vec![
        ("g8.png", image::DynamicImage::ImageLuma8(grey.clone())),
        ("g16.png", image::DynamicImage::ImageLuma16(grey16.clone())),
        ("rgb.png", image::DynamicImage::ImageRgb8(rgb.clone())),
        ("rgba16.png", image::DynamicImage::ImageRgba16(rgba16)),
        ("g8.pgm", image::DynamicImage::ImageLuma8(grey.clone())),
        ("g16.pgm", image::DynamicImage::ImageLuma16(grey16)),
        ("rgb.ppm", image::DynamicImage::ImageRgb8(rgb.clone())),
        ("rgb.bmp", image::DynamicImage::ImageRgb8(rgb.clone())),
        ("rgb.jpg", image::DynamicImage::ImageRgb8(rgb)),
    ];
    for (name, img) in cases {
        let path = dir.path().join(name);
        img.save(&path).unwrap();
        let loaded = load_gray(&path).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_eq!(loaded.dimensions(), grey.dimensions(), "{name}");
        let diffs: Vec<u8> = loaded
            .pixels()
            .zip(grey.pixels())
            .map(|(a, b)| a.0[0].abs_diff(b.0[0]))
            .collect();
        if name.ends_with(".jpg") {
            // Lossy, and the pattern wraps from 255 to 0: compare on average.
            let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
            assert!(mean < 8.0, "{name}: mean difference {mean}");
        } else {
            assert!(diffs.iter().all(|&d| d <= 1), "{name}: {diffs:?}");
        }
    }
}

fn assert_error_names_file(path: &Path) {
    let err = load_gray(path).expect_err("must not load");
    let message = format!("{err:#}");
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(
        message.contains(&name),
        "error does not name the file: {message}"
    );
}

#[test]
fn truncated_and_corrupt_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let img =
        image::DynamicImage::ImageLuma8(GrayImage::from_fn(64, 48, |x, y| Luma([(x ^ y) as u8])));
    for ext in ["png", "jpg", "pgm", "bmp"] {
        let full = dir.path().join(format!("full.{ext}"));
        img.save(&full).unwrap();
        let bytes = std::fs::read(&full).unwrap();
        for cut in [
            0,
            1,
            8,
            20,
            bytes.len() / 3,
            bytes.len() / 2,
            bytes.len() - 10,
        ] {
            let path = dir.path().join(format!("cut{cut}.{ext}"));
            std::fs::write(&path, &bytes[..cut]).unwrap();
            // Some decoders fill a cut-off tail; what matters is no panic,
            // and an error that names the file when it fails.
            if let Err(err) = load_gray(&path) {
                assert!(
                    format!("{err:#}").contains(&format!("cut{cut}.{ext}")),
                    "{err:#}"
                );
            }
        }
    }
    let mut rng = Pcg32::new(5, 0);
    for k in 0..40 {
        let len = (rng.next_f64() * 300.0) as usize;
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.next_u32() as u8).collect();
        // Keep a real signature on some, so the decoder gets past it.
        let signatures: [&[u8]; 4] = [b"\x89PNG\r\n\x1a\n", b"P5\n", b"BM", b"\xff\xd8\xff"];
        let sig = signatures[k % 4];
        if bytes.len() > sig.len() && k % 2 == 0 {
            bytes[..sig.len()].copy_from_slice(sig);
        }
        let path = dir.path().join(format!("random{k}.img"));
        std::fs::write(&path, &bytes).unwrap();
        let _ = load_gray(&path);
    }
    assert_error_names_file(&dir.path().join("missing.png"));
    let text = dir.path().join("notes.png");
    std::fs::write(&text, "not an image").unwrap();
    assert_error_names_file(&text);
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn absurd_dimensions_are_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let pgm = dir.path().join("huge.pgm");
    std::fs::write(&pgm, b"P5\n100000 100000\n255\n\x00\x00\x00").unwrap();
    assert_error_names_file(&pgm);
    let message = format!("{:#}", load_gray(&pgm).unwrap_err());
    assert!(message.contains("100000x100000"), "{message}");

    // A PNG header claiming 25000 x 25000 (625 megapixels).
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(25_000u32.to_be_bytes());
    ihdr.extend(25_000u32.to_be_bytes());
    ihdr.extend([8, 0, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(13u32.to_be_bytes());
    png.extend(&ihdr);
    png.extend(crc32(&ihdr).to_be_bytes());
    // An empty IDAT chunk: the header is all a decoder reads to learn the size.
    png.extend(0u32.to_be_bytes());
    png.extend(b"IDAT");
    png.extend(crc32(b"IDAT").to_be_bytes());
    let path = dir.path().join("huge.png");
    std::fs::write(&path, &png).unwrap();
    let message = format!("{:#}", load_gray(&path).unwrap_err());
    assert!(
        message.contains("huge.png") && message.contains("25000x25000"),
        "{message}"
    );
}

/// A camera's 10-bit data in a 16-bit file: divided by 257 it would keep
/// four grey levels; the marker must still be found and read.
#[test]
fn ten_bit_data_in_a_sixteen_bit_file_keeps_its_contrast() {
    let dir = tempfile::tempdir().unwrap();
    let family = Family::generate(8, 2).unwrap();
    let marker = whycode::geometry::Marker::whycode(8, family.code(5).unwrap(), 30.0);
    let page = whycode::render::marker::marker_page(&marker, &Default::default()).unwrap();
    let page = page.on_white(15.0);
    let rendered = whycode::render::raster::render_page(&page, 254.0).unwrap();
    let ten_bit = image::ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(
        rendered.width(),
        rendered.height(),
        |x, y| Luma([u16::from(rendered.get_pixel(x, y).0[0]) * 4]),
    );
    let path = dir.path().join("ten-bit.png");
    image::DynamicImage::ImageLuma16(ten_bit)
        .save(&path)
        .unwrap();
    let loaded = load_gray(&path).unwrap();
    let brightest = loaded.pixels().map(|p| p.0[0]).max().unwrap();
    assert_eq!(brightest, 255);
    let mut detector = Detector::new(DetectorConfig {
        target: Target::WhyCode(family),
        ..DetectorConfig::default()
    });
    let found = detector.detect(&loaded);
    assert_eq!(found.iter().map(|d| d.id).collect::<Vec<_>>(), [5]);
}

/// The JPEG decoder fills a cut-off file with grey and reports nothing; a
/// photo cut short in transfer must be an error, not "no markers here".
#[test]
fn truncated_jpegs_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let img = image::DynamicImage::ImageLuma8(GrayImage::from_fn(64, 48, |x, y| {
        Luma([(x * 3 + y * 5) as u8])
    }));
    let full = dir.path().join("full.jpg");
    img.save(&full).unwrap();
    assert!(load_gray(&full).is_ok());
    let bytes = std::fs::read(&full).unwrap();
    for cut in [bytes.len() / 2, bytes.len() - 2] {
        let path = dir.path().join(format!("cut{cut}.jpg"));
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let err = format!(
            "{:#}",
            load_gray(&path).expect_err("a cut JPEG must not load")
        );
        assert!(err.contains(&format!("cut{cut}.jpg")), "{err}");
        assert!(err.contains("truncated"), "{err}");
    }
}
