//! A large frame is worked on by all of a rayon pool's threads (bands of
//! rows for the threshold map and the seeds, outlines and descriptions per
//! candidate); what the detector reports must not depend on how many there
//! are: the same detections, IDs, poses and tracks, in the same order, as
//! on one thread.

use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::LooseMarker;
use whycode_testkit::scenes::{camera, cast_shadow, marker_at, render, Look};

/// Large enough that the detector splits its work between threads.
const WIDTH: u32 = 1800;
const HEIGHT: u32 = 1200;

fn family() -> Family {
    Family::generate(8, 2).unwrap()
}

fn frame_camera() -> Camera {
    camera(WIDTH, HEIGHT, 1500.0)
}

/// Seeded markers of 20-90 px on a grid with jitter, moved by `t` frames
/// of their own motion, under a light gradient and a cast shadow (the
/// shaded second look), some tilted.
fn frame(t: f64) -> image::GrayImage {
    let codes = family().codes().to_vec();
    let camera = frame_camera();
    let mut rng = Pcg32::new(36, 0);
    let mut markers: Vec<LooseMarker> = Vec::new();
    for row in 0..6 {
        for col in 0..10 {
            let k = row * 10 + col;
            let d = rng.range(20.0, 90.0);
            let u =
                90.0 + 180.0 * f64::from(col) + rng.range(-20.0, 20.0) + t * rng.range(-8.0, 8.0);
            let v =
                100.0 + 200.0 * f64::from(row) + rng.range(-20.0, 20.0) + t * rng.range(-8.0, 8.0);
            let roll = rng.range(0.0, std::f64::consts::TAU) + t * 0.05;
            let tilt = if k % 4 == 0 { rng.range(0.0, 1.0) } else { 0.0 };
            let id = k as usize % codes.len();
            let marker = (Marker::whycode(8, codes[id], 100.0), id as u32 + 1);
            markers.push(marker_at(
                &camera,
                marker,
                (u, v),
                d,
                roll,
                (tilt, rng.range(0.0, 3.0)),
            ));
        }
    }
    let look = Look {
        gradient_right: 0.6,
        blur: 1,
        noise: 2.0,
        ..Look::default()
    };
    let mut image = render(&camera, &markers, look).0;
    cast_shadow(&mut image, (1300.0, 0.0), 1.3, 0.5, 6.0);
    image
}

fn config(tracking: bool, max_markers: usize) -> DetectorConfig {
    DetectorConfig {
        target: Target::WhyCode(family()),
        camera: Some(frame_camera()),
        diameter_m: Some(0.1),
        tracking,
        max_markers,
        ..DetectorConfig::default()
    }
}

/// Every frame's detections by a detector of `config` in a pool of
/// `threads` threads, the frames one stream.
fn detect_in_pool(
    threads: usize,
    config: &DetectorConfig,
    frames: &[image::GrayImage],
) -> Vec<Vec<Detection>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut detector = Detector::new(config.clone());
    pool.install(|| frames.iter().map(|f| detector.detect(f)).collect())
}

#[test]
fn two_threads_report_what_one_does() {
    // The last frame jumps back to the first: the markers lie up to 30 px
    // from where their tracks predict them, and most are followed by the
    // flood fill.
    let frames: Vec<_> = [0, 1, 2, 0].map(|t| frame(f64::from(t))).to_vec();
    // The last stops at 9 candidates, fewer than the frame holds.
    for (config, least) in [
        (config(false, 1024), 50),
        (config(true, 1024), 50),
        (config(false, 9), 5),
    ] {
        let one = detect_in_pool(1, &config, &frames);
        assert!(one[0].len() >= least, "{} found", one[0].len());
        assert!(one[0].iter().all(|d| d.pose.is_some()));
        let two = detect_in_pool(2, &config, &frames);
        // Compared as printed, so that two NaNs in the same place agree.
        assert_eq!(format!("{one:?}"), format!("{two:?}"));
    }
}

/// Two markers of the same size side by side, the left one (track 1, a
/// little higher) gone in the last frame, where the right one moves
/// towards where it was by more than its edge search reaches: both tracks
/// fall back to the flood fill, and the left one's fill, along the row
/// from where its marker should be, runs into the right marker and labels
/// it. On one thread the right marker's own fill then starts on a
/// labelled pixel and takes nothing (the scan finds the marker instead);
/// the threads, which fill apart, must report the same.
fn fills_meeting(t: u32) -> image::GrayImage {
    let codes = family().codes().to_vec();
    let camera = frame_camera();
    let member = |k: usize| (Marker::whycode(8, codes[k], 100.0), k as u32 + 1);
    let right = if t < 3 { 1010.0 } else { 998.0 };
    let mut markers = vec![marker_at(
        &camera,
        member(1),
        (right, 600.0),
        80.0,
        0.3,
        (0.0, 0.0),
    )];
    if t < 3 {
        markers.push(marker_at(
            &camera,
            member(0),
            (900.0, 590.0),
            80.0,
            1.1,
            (0.0, 0.0),
        ));
    }
    let look = Look {
        blur: 1,
        noise: 2.0,
        ..Look::default()
    };
    render(&camera, &markers, look).0
}

#[test]
fn fills_that_meet_report_what_one_thread_does() {
    let frames: Vec<_> = (0..4).map(fills_meeting).collect();
    let config = config(true, 1024);
    let one = detect_in_pool(1, &config, &frames);
    let tracks = |k: usize| one[k].iter().map(|d| d.track).collect::<Vec<_>>();
    assert_eq!(tracks(2), [Some(1), Some(2)], "{one:?}");
    assert_eq!(one[3].len(), 1, "{one:?}");
    let two = detect_in_pool(2, &config, &frames);
    assert_eq!(format!("{one:?}"), format!("{two:?}"));
}
