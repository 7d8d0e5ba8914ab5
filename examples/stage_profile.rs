//! Where the detector's time goes on the detection bench's frames, stage
//! by stage (`DetectorConfig::timings`): the median milliseconds of each
//! stage over many runs of each frame set, in a rayon pool of one thread
//! (or `--threads N`), and the median, mean and longest frame. The
//! medians of the stages need not add up to the median frame.
//!
//!     cargo run --release --example stage_profile [-- --threads 2] [--runs N] [set ...]
//!
//! Sets: `clutter` (the detector bar's cluttered 1280x720 desk without a
//! marker), `one` (one marker in 640x480, with pose), `four` (four markers
//! in 640x480), `first` (5000x5000, 550 markers, first frame with pose),
//! `tracked` (the same frame again and again, tracked, with pose),
//! `moving` (the moving swarm, tracked with pose), `in-view` (the moving
//! swarm without markers leaving). All of them without a set named.

use std::time::Duration;

use image::GrayImage;
use whycode::detect::{Detector, DetectorConfig, Stage};
use whycode_testkit::scenario::{self, Print};
use whycode_testkit::speed;

const SETS: [&str; 7] = [
    "clutter", "one", "four", "first", "tracked", "moving", "in-view",
];

fn main() {
    let mut threads = 1;
    let mut runs: Option<usize> = None;
    let mut wanted = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |name: &str| -> usize {
            args.next()
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| fail(&format!("{name} takes a whole number")))
        };
        match arg.as_str() {
            "--threads" => threads = value("--threads").max(1),
            "--runs" => runs = Some(value("--runs").max(1)),
            set if SETS.contains(&set) => wanted.push(set.to_string()),
            other => fail(&format!(
                "unknown argument {other:?}: the sets are {}",
                SETS.join(", ")
            )),
        }
    }
    if wanted.is_empty() {
        wanted = SETS.iter().map(|s| s.to_string()).collect();
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    println!("{threads} thread(s); median milliseconds per frame\n");
    print!("| frames | markers |");
    for stage in Stage::ALL {
        print!(" {} |", stage.name());
    }
    println!(" total | mean | max |");
    println!("|---|---|{}---|---|---|", "---|".repeat(Stage::ALL.len()));
    for set in &wanted {
        let (detector, frames, default_runs) = frame_set(set);
        let row = pool.install(|| profile(detector, &frames, runs.unwrap_or(default_runs)));
        println!("| {set} | {row}");
    }
}

/// A detector with its configuration for `set`, the set's frames in the
/// order they are shown, and how many runs give a steady median.
fn frame_set(set: &str) -> (Detector, Vec<&'static GrayImage>, usize) {
    let timed = |config: DetectorConfig| {
        Detector::new(DetectorConfig {
            timings: true,
            ..config
        })
    };
    let big = Some(speed::big_camera());
    match set {
        "clutter" => {
            let family = speed::family();
            let desk = scenario::cluttered_desk(&family, 1);
            let image: &'static GrayImage =
                Box::leak(Box::new(desk.frame(0, Print::WhyCode).image));
            let config = scenario::detector_config(Some(&family), &desk.camera(), false);
            (timed(config), vec![image], 400)
        }
        "one" => (
            timed(speed::config(false, 1024, Some(speed::small_camera()))),
            vec![speed::one_marker_640()],
            1000,
        ),
        "four" => (
            timed(speed::config(false, 1024, None)),
            vec![speed::four_markers_640()],
            1000,
        ),
        "first" => (
            timed(speed::config(false, 1024, big)),
            vec![speed::big_scene()],
            15,
        ),
        "tracked" => (
            timed(speed::config(true, 550, big)),
            vec![speed::big_scene()],
            40,
        ),
        "moving" | "in-view" => {
            let frames = if set == "moving" {
                speed::swarm_frames()
            } else {
                speed::swarm_in_view_frames()
            };
            let stream = (0..speed::swarm_period(frames))
                .map(|k| speed::swarm_frame(frames, k))
                .collect();
            (timed(speed::config(true, 1024, big)), stream, 56)
        }
        _ => unreachable!("a set of SETS"),
    }
}

/// The table row of `runs` frames of `frames` (in turn, after one pass
/// for the detector's state to settle): the markers of the last frame,
/// each stage's median, and the whole frame's median, mean and maximum.
fn profile(mut detector: Detector, frames: &[&GrayImage], runs: usize) -> String {
    for frame in frames {
        detector.detect(*frame);
    }
    let mut stages: Vec<Vec<Duration>> = vec![Vec::with_capacity(runs); Stage::ALL.len()];
    let mut totals = Vec::with_capacity(runs);
    let mut markers = 0;
    for k in 0..runs {
        markers = detector.detect(frames[k % frames.len()]).len();
        let timings = detector
            .last_timings()
            .expect("the timings are on and the target has a clock");
        for (times, stage) in stages.iter_mut().zip(Stage::ALL) {
            times.push(timings.get(stage));
        }
        totals.push(timings.total());
    }
    let mut row = format!("{markers} |");
    for mut times in stages {
        row += &format!(" {} |", ms(median(&mut times)));
    }
    let mean = totals.iter().sum::<Duration>() / totals.len() as u32;
    let max = totals.iter().copied().max().unwrap_or_default();
    row + &format!(
        " {} | {} | {} |",
        ms(median(&mut totals)),
        ms(mean),
        ms(max)
    )
}

fn median(times: &mut [Duration]) -> Duration {
    times.sort_unstable();
    times[times.len() / 2]
}

fn ms(t: Duration) -> String {
    if t.is_zero() {
        "-".to_string()
    } else {
        format!("{:.3}", t.as_secs_f64() * 1e3)
    }
}

fn fail(message: &str) -> ! {
    eprintln!("stage_profile: {message}");
    std::process::exit(2)
}
