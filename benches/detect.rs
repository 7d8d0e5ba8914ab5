//! Detector speed, single thread (paper Table 5 setting).
//!
//! Targets: a 5000x5000 grey image with 550 markers of 60-120 px, first
//! frame (no tracking) under 150 ms and a tracked frame under 15 ms, also
//! with the full 6-DoF pose of every marker (`..._with_pose`);
//! 640x480 with a few markers under 1 ms. Memory: divan's "max alloc"
//! column shows what a frame allocates on top of the image (target: the
//! whole process under 3x the image size, i.e. under 2x on top of it).
//! The `..._threads` benches run the same frames in a rayon pool of 1 and
//! of 2 threads (a large frame is split between the pool's threads; the
//! results are the same for any number). `moving_swarm_...` is a tracked
//! stream whose markers move 1-20 px a frame, some turning, some entering
//! and leaving the view, every marker's pose computed each frame. The
//! small frames (a cluttered 1280x720 desk without a marker, one marker in
//! 640x480) stay on one thread.
//! Run with `cargo bench --bench detect`.

use std::sync::OnceLock;

use divan::{black_box, AllocProfiler, Bencher};
use image::GrayImage;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::LooseMarker;
use whycode_testkit::scenes::{camera, marker_at, render, scatter, Look};

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
/// rotations, in `big_look`.
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
        render(&camera, &markers, big_look()).0
    })
}

/// `big_scene`'s look: light falling 2:1 across the frame, mild blur
/// and noise.
fn big_look() -> Look {
    Look {
        gradient_right: 0.5,
        blur: 1,
        noise: 2.0,
        ..Look::default()
    }
}

/// Frames rendered of the moving swarm, played forwards and back.
const SWARM_FRAMES: usize = 8;

/// A moving swarm at 5000x5000: `big_scene`'s 550 markers, each moving
/// 1-20 px a frame in its own direction, a third of them turning by up
/// to 4° a frame, and 16 more crossing the frame's edges (half coming
/// in, half going out). Its frames played forwards then backwards make a
/// stream without jumps.
fn swarm_frames() -> &'static [GrayImage] {
    static FRAMES: OnceLock<Vec<GrayImage>> = OnceLock::new();
    FRAMES.get_or_init(|| {
        let codes = family().codes().to_vec();
        let camera = big_camera();
        let mut rng = Pcg32::new(5001, 0);
        // Per marker: member, centre, diameter, roll, and per frame a
        // step and a turn; placed as `scatter` places them.
        let mut placed: Vec<(f64, f64, f64)> = Vec::new();
        let mut swarm = Vec::new();
        while swarm.len() < 550 {
            let d = rng.range(60.0, 120.0);
            let reach = d * 0.5 * 1.35 + 2.0;
            let (u, v) = (
                rng.range(reach, 5000.0 - reach),
                rng.range(reach, 5000.0 - reach),
            );
            if placed
                .iter()
                .any(|&(pu, pv, pr)| (pu - u).hypot(pv - v) < pr + reach)
            {
                continue;
            }
            placed.push((u, v, reach));
            let speed = rng.range(1.0, 20.0);
            let heading = rng.range(0.0, std::f64::consts::TAU);
            let turn = if swarm.len() % 3 == 0 {
                rng.range(-4.0, 4.0).to_radians()
            } else {
                0.0
            };
            let roll = rng.range(0.0, std::f64::consts::TAU);
            let step = (speed * heading.cos(), speed * heading.sin());
            swarm.push((member(&codes, swarm.len()), (u, v), d, roll, step, turn));
        }
        // Crossing the edges at 15 px a frame: from 50 px outside the
        // left and top edges inwards, from 50 px inside the right and
        // bottom edges outwards.
        for k in 0..16 {
            let along = 400.0 + 520.0 * (k / 4) as f64;
            let (centre, step) = match k % 4 {
                0 => ((-50.0, along), (15.0, 0.0)),
                1 => ((along, -50.0), (0.0, 15.0)),
                2 => ((4950.0, along + 200.0), (15.0, 0.0)),
                _ => ((along + 200.0, 4950.0), (0.0, 15.0)),
            };
            let id = member(&codes, 550 + k);
            swarm.push((id, centre, 90.0, 0.0, step, 0.0));
        }
        (0..SWARM_FRAMES)
            .map(|t| {
                let t = t as f64;
                let markers: Vec<LooseMarker> = swarm
                    .iter()
                    .map(|(id, (u, v), d, roll, (du, dv), turn)| {
                        let centre = (u + t * du, v + t * dv);
                        marker_at(&camera, *id, centre, *d, roll + t * turn, (0.0, 0.0))
                    })
                    .collect();
                render(&camera, &markers, big_look()).0
            })
            .collect()
    })
}

/// The k-th frame of the swarm's stream: its frames forwards, then back.
fn swarm_frame(k: usize) -> &'static GrayImage {
    let frames = swarm_frames();
    let period = 2 * (frames.len() - 1);
    let t = k % period;
    &frames[if t < frames.len() { t } else { period - t }]
}

/// A pool of `threads` threads, for the thread-scaling benches.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
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

/// As `first_frame_..._with_pose`, in a pool of 1 and of 2 threads.
#[divan::bench(sample_count = 10, args = [1, 2])]
fn first_frame_5000x5000_550_markers_with_pose_threads(bencher: Bencher, threads: usize) {
    let image = big_scene();
    let pool = pool(threads);
    let mut detector = Detector::new(with_pose(config(false, 1024)));
    assert_eq!(pool.install(|| detector.detect(image)).len(), 550);
    bencher.bench_local(|| pool.install(|| detector.detect(black_box(image)).len()));
}

/// A tracked stream of the moving swarm with every marker's pose, in a
/// pool of 1 and of 2 threads: each sample is the stream's next frame,
/// after a pass over the whole stream for the IDs to settle.
#[divan::bench(sample_count = 28, sample_size = 1, args = [1, 2])]
fn moving_swarm_5000x5000_tracked_with_pose_threads(bencher: Bencher, threads: usize) {
    let pool = pool(threads);
    let mut detector = Detector::new(with_pose(config(true, 1024)));
    let period = 2 * (SWARM_FRAMES - 1);
    for k in 0..period {
        let found = pool.install(|| detector.detect(swarm_frame(k)));
        assert!(found.len() >= 500, "frame {k}: {} markers", found.len());
    }
    let mut k = period;
    bencher.bench_local(|| {
        let image = swarm_frame(k);
        k += 1;
        pool.install(|| detector.detect(black_box(image)).len())
    });
}

#[divan::bench(sample_count = 100)]
fn frame_640x480_4_markers(bencher: Bencher) {
    let image = small_scene();
    let mut detector = Detector::new(config(false, 1024));
    assert_eq!(detector.detect(image).len(), 4);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}

/// A cluttered 1280x720 desk without a marker (testkit's `desk_clutter`):
/// everything the scan fills is turned down.
#[divan::bench(sample_count = 100)]
fn frame_1280x720_desk_clutter_no_marker(bencher: Bencher) {
    let image = whycode_testkit::desk::desk_clutter(1);
    let mut detector = Detector::new(config(false, 1024));
    assert_eq!(detector.detect(&image).len(), 0);
    bencher.bench_local(|| detector.detect(black_box(&image)).len());
}

/// One marker of 40-90 px in a 640x480 frame, with its pose.
#[divan::bench(sample_count = 100)]
fn frame_640x480_1_marker_with_pose(bencher: Bencher) {
    let codes = family().codes().to_vec();
    let camera = camera(640, 480, 600.0);
    let mut rng = Pcg32::new(641, 0);
    let markers = scatter(&mut rng, &camera, 1, (40.0, 90.0), &mut |k| {
        member(&codes, k)
    });
    let look = Look {
        blur: 1,
        noise: 2.0,
        ..Look::default()
    };
    let image = render(&camera, &markers, look).0;
    let mut detector = Detector::new(DetectorConfig {
        camera: Some(camera),
        diameter_m: Some(0.1),
        ..config(false, 1024)
    });
    assert_eq!(detector.detect(&image).len(), 1);
    bencher.bench_local(|| detector.detect(black_box(&image)).len());
}
