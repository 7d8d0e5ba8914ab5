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
//! one marker in 640x480) stay on one thread. The frames are
//! `whycode_testkit::speed`'s; `examples/stage_profile` shows where their
//! time goes, stage by stage.
//! Run with `cargo bench --bench detect`.

use divan::{black_box, AllocProfiler, Bencher};
use image::GrayImage;
use whycode::detect::{Detector, DetectorConfig};
use whycode_testkit::speed::{
    big_camera, big_scene, four_markers_640, one_marker_640, small_camera, swarm_frame,
    swarm_frames, swarm_in_view_frames, swarm_period,
};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// A pool of `threads` threads, for the thread-scaling benches.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn config(tracking: bool, max_markers: usize) -> DetectorConfig {
    whycode_testkit::speed::config(tracking, max_markers, None)
}

/// With `big_scene`'s camera and its markers' diameter.
fn with_pose(tracking: bool, max_markers: usize) -> DetectorConfig {
    whycode_testkit::speed::config(tracking, max_markers, Some(big_camera()))
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
    let mut detector = Detector::new(with_pose(false, 1024));
    assert_eq!(detector.detect(image).len(), 550);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}

/// As `tracked_frame_...`, with every marker's pose.
#[divan::bench(sample_count = 20)]
fn tracked_frame_5000x5000_550_markers_with_pose(bencher: Bencher) {
    let image = big_scene();
    let mut detector = Detector::new(with_pose(true, 550));
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
    let mut detector = Detector::new(with_pose(false, 1024));
    assert_eq!(pool.install(|| detector.detect(image)).len(), 550);
    bencher.bench_local(|| pool.install(|| detector.detect(black_box(image)).len()));
}

/// A tracked stream of the moving swarm with every marker's pose, in a
/// pool of 1 and of 2 threads: each sample is the stream's next frame,
/// after a pass over the whole stream for the IDs to settle. A marker
/// lost at the frame's edge is looked for where it was; markers lost
/// inside the frame (at the motion's turn, where their predicted places
/// overshoot) have the whole frame scanned for them.
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
    let mut detector = Detector::new(with_pose(true, 1024));
    let period = swarm_period(frames);
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
    let image = four_markers_640();
    let mut detector = Detector::new(config(false, 1024));
    assert_eq!(detector.detect(image).len(), 4);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}

/// The detector bar's row 8a: a cluttered 1280x720 frame without a
/// marker (the simulator's clutter, noise σ 2), the 8-bit family.
#[divan::bench(sample_count = 100)]
fn frame_1280x720_clutter_no_marker(bencher: Bencher) {
    use whycode_testkit::scenario::{self, Print};
    let family = whycode_testkit::speed::family();
    let clutter = scenario::cluttered_desk(&family, 1);
    let image = clutter.frame(0, Print::WhyCode).image;
    let mut detector = scenario::detector(Some(&family), &clutter.camera(), false);
    assert_eq!(detector.detect(&image).len(), 0);
    bencher.bench_local(|| detector.detect(black_box(&image)).len());
}

/// One marker of 40-90 px in a 640x480 frame, with its pose.
#[divan::bench(sample_count = 100)]
fn frame_640x480_1_marker_with_pose(bencher: Bencher) {
    let image = one_marker_640();
    let mut detector = Detector::new(whycode_testkit::speed::config(
        false,
        1024,
        Some(small_camera()),
    ));
    assert_eq!(detector.detect(image).len(), 1);
    bencher.bench_local(|| detector.detect(black_box(image)).len());
}
