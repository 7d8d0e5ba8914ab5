//! Detector speed (paper Table 5 setting). The benches without `_threads`
//! run in rayon's global pool (a thread a core, `RAYON_NUM_THREADS=1` for
//! one), which a 5000x5000 frame is split between.
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
//! small frames (the detector bar's cluttered 1280x720 without a marker,
//! one marker in 640x480) stay on one thread.
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

/// A moving swarm at 5000x5000, seen as a camera turning over a floor of
/// markers: 550 markers of 60-120 px in view (and more around it), all
/// turning about the frame's centre by a third of a degree a frame, so
/// that each moves 1-20 px a frame by its distance from the centre and
/// turns with the swarm (a third of them by up to 3° a frame more), and
/// those near the corners leave the view or come into it. Its frames
/// played forwards then backwards make a stream without jumps.
fn swarm_frames() -> &'static [GrayImage] {
    static FRAMES: OnceLock<Vec<GrayImage>> = OnceLock::new();
    FRAMES.get_or_init(|| render_swarm(true))
}

/// As [`swarm_frames`], the 550 markers all within the circle the frame's
/// sides touch, which none leaves: every track is followed every frame.
fn swarm_in_view_frames() -> &'static [GrayImage] {
    static FRAMES: OnceLock<Vec<GrayImage>> = OnceLock::new();
    FRAMES.get_or_init(|| render_swarm(false))
}

/// The frames of [`swarm_frames`] (`leaving`) or [`swarm_in_view_frames`].
fn render_swarm(leaving: bool) -> Vec<GrayImage> {
    let codes = family().codes().to_vec();
    let camera = big_camera();
    let centre = 2500.0;
    let corner = centre * std::f64::consts::SQRT_2;
    let reach_out = if leaving { corner } else { centre - 90.0 };
    // The swarm's turn a frame: 20 px at the corners.
    let turn = 20.0 / corner;
    let mut rng = Pcg32::new(5001, 0);
    // Per marker: centre, diameter, roll, and its own turn a frame;
    // placed as `scatter` places them, over the disc the corners turn
    // through (or the one the sides touch).
    let mut placed: Vec<(f64, f64, f64)> = Vec::new();
    let mut swarm = Vec::new();
    let in_view = |x: f64| (0.0..5000.0).contains(&x);
    let (mut seen, mut attempts) = (0, 0);
    while seen < 550 && attempts < 100_000 {
        attempts += 1;
        let d = rng.range(60.0, 120.0);
        let reach = d * 0.5 * 1.35 + 2.0;
        let (u, v) = (
            rng.range(centre - reach_out, centre + reach_out),
            rng.range(centre - reach_out, centre + reach_out),
        );
        if (u - centre).hypot(v - centre) > reach_out
            || placed
                .iter()
                .any(|&(pu, pv, pr)| (pu - u).hypot(pv - v) < pr + reach)
        {
            continue;
        }
        placed.push((u, v, reach));
        seen += usize::from(in_view(u) && in_view(v));
        let roll = rng.range(0.0, std::f64::consts::TAU);
        let own_turn = if swarm.len() % 3 == 0 {
            rng.range(-3.0, 3.0).to_radians()
        } else {
            0.0
        };
        swarm.push(((u, v), d, roll, own_turn));
    }
    (0..SWARM_FRAMES)
        .map(|t| {
            let angle = turn * t as f64;
            let (sin, cos) = angle.sin_cos();
            let markers: Vec<LooseMarker> = swarm
                .iter()
                .enumerate()
                .filter_map(|(k, &((u, v), d, roll, own_turn))| {
                    let (du, dv) = (u - centre, v - centre);
                    let at = (centre + du * cos - dv * sin, centre + du * sin + dv * cos);
                    // Only those whose card reaches into the view.
                    let near = |x: f64| (-d..5000.0 + d).contains(&x);
                    let roll = roll + angle + own_turn * t as f64;
                    (near(at.0) && near(at.1))
                        .then(|| marker_at(&camera, member(&codes, k), at, d, roll, (0.0, 0.0)))
                })
                .collect();
            render(&camera, &markers, big_look()).0
        })
        .collect()
}

/// The k-th frame of a swarm's stream: its frames forwards, then back.
fn swarm_frame(frames: &[GrayImage], k: usize) -> &GrayImage {
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
/// after a pass over the whole stream for the IDs to settle. A frame
/// after a marker left the view scans the whole frame for it.
#[divan::bench(sample_count = 28, sample_size = 1, args = [1, 2])]
fn moving_swarm_5000x5000_tracked_with_pose_threads(bencher: Bencher, threads: usize) {
    bench_swarm(bencher, threads, swarm_frames());
}

/// As `moving_swarm_...`, every marker in view in every frame.
#[divan::bench(sample_count = 28, sample_size = 1, args = [1, 2])]
fn moving_swarm_in_view_5000x5000_tracked_with_pose_threads(bencher: Bencher, threads: usize) {
    bench_swarm(bencher, threads, swarm_in_view_frames());
}

fn bench_swarm(bencher: Bencher, threads: usize, frames: &[GrayImage]) {
    let pool = pool(threads);
    let mut detector = Detector::new(with_pose(config(true, 1024)));
    let period = 2 * (SWARM_FRAMES - 1);
    for k in 0..period {
        let found = pool.install(|| detector.detect(swarm_frame(frames, k)));
        assert!(found.len() >= 520, "frame {k}: {} markers", found.len());
    }
    let mut k = period;
    bencher.bench_local(|| {
        let image = swarm_frame(frames, k);
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

/// The detector bar's row 8a: a cluttered 1280x720 frame without a
/// marker (the simulator's clutter, noise σ 2), the 8-bit family.
#[divan::bench(sample_count = 100)]
fn frame_1280x720_clutter_no_marker(bencher: Bencher) {
    use whycode_testkit::scenario::{self, Print};
    let family = family();
    let clutter = scenario::cluttered_desk(&family, 1);
    let image = clutter.frame(0, Print::WhyCode).image;
    let mut detector = scenario::detector(Some(&family), &clutter.camera(), false);
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
