//! Detector speed, single thread (paper Table 5 setting).
//!
//! Targets: a 5000x5000 grey image with 550 markers of 60-120 px, first
//! frame (no tracking) under 150 ms and a tracked frame under 15 ms, also
//! with the full 6-DoF pose of every marker (`..._with_pose`);
//! 640x480 with a few markers under 1 ms. Memory: divan's "max alloc"
//! column shows what a frame allocates on top of the image (target: the
//! whole process under 3x the image size, i.e. under 2x on top of it).
//! Run with `cargo bench --bench detect`.

use std::sync::OnceLock;

use divan::{black_box, AllocProfiler, Bencher};
use image::GrayImage;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode_testkit::scenes::{camera, render, scatter, Look};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

fn family() -> Family {
    Family::generate(8, 2).unwrap()
}

/// The camera `big_scene` is rendered with.
fn big_camera() -> Camera {
    camera(5000, 5000, 5000.0)
}

/// The k-th member of `codes` (8-bit, 100 mm), cycling.
fn member(codes: &[u32], k: usize) -> (Marker, u32) {
    let id = k % codes.len();
    (Marker::whycode(8, codes[id], 100.0), id as u32 + 1)
}

/// 5000x5000, 550 WhyCode markers of 60-120 px at random places and
/// rotations, light falling 2:1 across the frame, mild blur and noise.
fn big_scene() -> &'static GrayImage {
    static SCENE: OnceLock<GrayImage> = OnceLock::new();
    SCENE.get_or_init(|| {
        let codes = family().codes().to_vec();
        let camera = big_camera();
        let mut rng = Pcg32::new(5000, 0);
        let markers = scatter(&mut rng, &camera, 550, (60.0, 120.0), &mut |k| {
            member(&codes, k)
        });
        assert_eq!(markers.len(), 550);
        let look = Look {
            gradient_right: 0.5,
            blur: 1,
            noise: 2.0,
            ..Look::default()
        };
        render(&camera, &markers, look).0
    })
}

fn small_scene() -> &'static GrayImage {
    static SCENE: OnceLock<GrayImage> = OnceLock::new();
    SCENE.get_or_init(|| {
        let codes = family().codes().to_vec();
        let camera = camera(640, 480, 600.0);
        let mut rng = Pcg32::new(640, 0);
        let markers = scatter(&mut rng, &camera, 4, (40.0, 90.0), &mut |k| {
            member(&codes, k)
        });
        let look = Look {
            blur: 1,
            noise: 2.0,
            ..Look::default()
        };
        render(&camera, &markers, look).0
    })
}

fn config(tracking: bool, max_markers: usize) -> DetectorConfig {
    DetectorConfig {
        target: Target::WhyCode(family()),
        tracking,
        max_markers,
        ..DetectorConfig::default()
    }
}

/// With `big_scene`'s camera and its markers' diameter.
fn with_pose(config: DetectorConfig) -> DetectorConfig {
    DetectorConfig {
        camera: Some(big_camera()),
        diameter_m: Some(0.1),
        ..config
    }
}

/// A frame seen without tracking, buffers already allocated (a folder of
/// unrelated frames, or the first frame of a sequence after the first).
#[divan::bench(sample_count = 10)]
fn first_frame_5000x5000_550_markers(bencher: Bencher) {
    let image = big_scene();
    let mut detector = Detector::new(config(false, 1024));
    assert_eq!(detector.detect(image).len(), 550);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}

/// The very first frame of a fresh detector (allocates its buffers).
#[divan::bench(sample_count = 5)]
fn fresh_detector_5000x5000_550_markers(bencher: Bencher) {
    let image = big_scene();
    bencher.bench_local(|| {
        Detector::new(config(false, 1024))
            .detect(black_box(image))
            .len()
    });
}

/// A tracked frame: every marker found again where it was, so only the
/// markers' own pixels are touched.
#[divan::bench(sample_count = 20)]
fn tracked_frame_5000x5000_550_markers(bencher: Bencher) {
    let image = big_scene();
    let mut detector = Detector::new(config(true, 550));
    assert_eq!(detector.detect(image).len(), 550);
    bencher.bench_local(|| {
        let found = detector.detect(black_box(image)).len();
        assert_eq!(found, 550);
        found
    });
}

/// As `first_frame_...`, with every marker's pose.
#[divan::bench(sample_count = 10)]
fn first_frame_5000x5000_550_markers_with_pose(bencher: Bencher) {
    let image = big_scene();
    let mut detector = Detector::new(with_pose(config(false, 1024)));
    assert_eq!(detector.detect(image).len(), 550);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}

/// As `tracked_frame_...`, with every marker's pose.
#[divan::bench(sample_count = 20)]
fn tracked_frame_5000x5000_550_markers_with_pose(bencher: Bencher) {
    let image = big_scene();
    let mut detector = Detector::new(with_pose(config(true, 550)));
    let first = detector.detect(image);
    assert_eq!(first.len(), 550);
    assert!(first.iter().all(|d| d.pose.is_some()));
    bencher.bench_local(|| {
        let found = detector.detect(black_box(image)).len();
        assert_eq!(found, 550);
        found
    });
}

#[divan::bench(sample_count = 100)]
fn frame_640x480_4_markers(bencher: Bencher) {
    let image = small_scene();
    let mut detector = Detector::new(config(false, 1024));
    assert_eq!(detector.detect(image).len(), 4);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}
