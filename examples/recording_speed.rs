//! Is detection what users wait for on a recorded run? A simulated 640x480
//! video (H.264, markers moving across it) is read three ways, in turns,
//! in this one run: ffmpeg alone decoding it to raw grey frames (the
//! baseline), whycode reading its frames through ffmpeg's pipe without
//! detecting, and the whole run (decode + detect + track). Prints medians
//! and the ratio to the baseline (the target: at most 2x).
//!
//!     cargo run --release --example recording_speed [-- FRAMES]

use std::process::Command;
use std::time::Instant;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::geometry::Marker;
use whycode::recording::{ReadOptions, Recording};
use whycode::Family;
use whycode_testkit::scenes::{self, Look};

const REPEATS: usize = 5;

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .map(|n| n.parse().expect("a frame count"))
        .unwrap_or(300);
    let dir = tempfile::tempdir().expect("a temporary folder");
    let family = Family::generate(8, 2).expect("the default family");
    let camera = scenes::camera(640, 480, 600.0);
    eprintln!("rendering {frames} frames of 640x480 ...");
    for k in 0..frames {
        let t = k as f64 / frames as f64;
        let markers: Vec<_> = (0..6u32)
            .map(|i| {
                let id = i + 1;
                let marker = Marker::whycode(8, family.code(id).unwrap(), 40.0);
                let u = 70.0 + 100.0 * f64::from(i) + 40.0 * (t * 6.0 + f64::from(i)).sin();
                let v = 120.0 + 240.0 * t + 30.0 * f64::from(i % 2);
                scenes::marker_at(&camera, (marker, id), (u, v), 60.0, t * 3.0, (0.3, 0.5))
            })
            .collect();
        let look = Look {
            noise: 2.0,
            ..Look::default()
        };
        let (image, _) = scenes::render(&camera, &markers, look);
        image
            .save(dir.path().join(format!("f{k:05}.png")))
            .expect("a frame saved");
    }
    let video = dir.path().join("run.mp4");
    let encoded = Command::new("ffmpeg")
        .args([
            "-hide_banner",
            "-loglevel",
            "error",
            "-y",
            "-framerate",
            "30",
            "-i",
        ])
        .arg(dir.path().join("f%05d.png"))
        .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
        .arg(&video)
        .status()
        .expect("ffmpeg runs");
    assert!(encoded.success(), "ffmpeg encodes the frames");

    let baseline = || {
        let status = Command::new("ffmpeg")
            .args(["-hide_banner", "-loglevel", "error", "-nostdin", "-i"])
            .arg(&video)
            .args(["-f", "rawvideo", "-pix_fmt", "gray", "-y", "/dev/null"])
            .status()
            .expect("ffmpeg runs");
        assert!(status.success());
    };
    let recording = Recording::open(&video).expect("the video opens");
    let read_only = || {
        let mut n = 0;
        for frame in recording.frames(&ReadOptions::default()).expect("frames") {
            frame.expect("a frame");
            n += 1;
        }
        assert_eq!(n, frames);
    };
    let mut found = 0;
    let mut whole = || {
        let mut detector = Detector::new(DetectorConfig {
            target: Target::WhyCode(family.clone()),
            tracking: true,
            ..DetectorConfig::default()
        });
        found = 0;
        for frame in recording.frames(&ReadOptions::default()).expect("frames") {
            found += detector.detect(&frame.expect("a frame").image).len();
        }
    };
    let (mut base, mut read, mut run) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..REPEATS {
        base.push(time(baseline));
        read.push(time(read_only));
        run.push(time(&mut whole));
    }
    let (b, r, w) = (median(&mut base), median(&mut read), median(&mut run));
    println!("{frames} frames of 640x480 H.264, medians of {REPEATS} runs each, in turns:");
    println!(
        "  ffmpeg alone to raw grey frames  {:8.1} ms  ({:.2} ms/frame)  1.00x",
        b,
        b / frames as f64
    );
    println!(
        "  whycode reading frames (no detect){:7.1} ms  ({:.2} ms/frame)  {:.2}x",
        r,
        r / frames as f64,
        r / b
    );
    println!(
        "  whole run: decode + detect + track{:7.1} ms  ({:.2} ms/frame)  {:.2}x",
        w,
        w / frames as f64,
        w / b
    );
    println!(
        "  markers found per frame: {:.2} (6 in view)",
        found as f64 / frames as f64
    );
}

fn time(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64() * 1000.0
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}
