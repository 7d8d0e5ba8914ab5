//! The frames the detector's speed is measured on, for the detection
//! bench (`benches/detect.rs`) and the per-stage profile
//! (`examples/stage_profile.rs`): a 5000x5000 swarm of 550 markers, the
//! same swarm moving, and small frames with one or four markers. The
//! cluttered 1280x720 desk is [`crate::scenario::cluttered_desk`].

use std::sync::OnceLock;

use image::GrayImage;
use whycode::camera::Camera;
use whycode::detect::{DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::LooseMarker;

use crate::scenes::{camera, marker_at, render, scatter, Look};

/// The markers' family: 8 bits, Hamming distance 2.
pub fn family() -> Family {
    Family::generate(8, 2).expect("the 8-bit family")
}

/// The printed diameter of every marker, metres.
pub const DIAMETER_M: f64 = 0.1;

/// The camera of the 5000x5000 frames.
pub fn big_camera() -> Camera {
    camera(5000, 5000, 5000.0)
}

/// The k-th member of `codes` (8-bit, 100 mm), cycling.
fn member(codes: &[u32], k: usize) -> (Marker, u32) {
    let id = k % codes.len();
    (Marker::whycode(8, codes[id], 100.0), id as u32 + 1)
}

/// 5000x5000, 550 WhyCode markers of 60-120 px at random places and
/// rotations, in [`big_look`].
pub fn big_scene() -> &'static GrayImage {
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

/// The 5000x5000 frames' look: light falling 2:1 across the frame, mild
/// blur and noise.
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
/// played forwards then backwards ([`swarm_frame`]) make a stream without
/// jumps, but for the motion's turn at each end.
pub fn swarm_frames() -> &'static [GrayImage] {
    static FRAMES: OnceLock<Vec<GrayImage>> = OnceLock::new();
    FRAMES.get_or_init(|| render_swarm(true))
}

/// As [`swarm_frames`], the 550 markers all within the circle the frame's
/// sides touch, which none leaves: every track is followed every frame.
pub fn swarm_in_view_frames() -> &'static [GrayImage] {
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
pub fn swarm_frame(frames: &[GrayImage], k: usize) -> &GrayImage {
    let period = swarm_period(frames);
    let t = k % period;
    &frames[if t < frames.len() { t } else { period - t }]
}

/// Frames in one pass of a swarm's stream, forwards and back.
pub fn swarm_period(frames: &[GrayImage]) -> usize {
    2 * (frames.len() - 1)
}

/// A 640x480 camera of focal length 600 px.
pub fn small_camera() -> Camera {
    camera(640, 480, 600.0)
}

/// 640x480 with four markers of 40-90 px.
pub fn four_markers_640() -> &'static GrayImage {
    static SCENE: OnceLock<GrayImage> = OnceLock::new();
    SCENE.get_or_init(|| small_frame(640, 4))
}

/// 640x480 with one marker of 40-90 px.
pub fn one_marker_640() -> &'static GrayImage {
    static SCENE: OnceLock<GrayImage> = OnceLock::new();
    SCENE.get_or_init(|| small_frame(641, 1))
}

fn small_frame(seed: u64, count: usize) -> GrayImage {
    let codes = family().codes().to_vec();
    let camera = small_camera();
    let mut rng = Pcg32::new(seed, 0);
    let markers = scatter(&mut rng, &camera, count, (40.0, 90.0), &mut |k| {
        member(&codes, k)
    });
    let look = Look {
        blur: 1,
        noise: 2.0,
        ..Look::default()
    };
    render(&camera, &markers, look).0
}

/// A detector's configuration for these frames: the 8-bit family, and
/// with `camera` the pose of every marker.
pub fn config(tracking: bool, max_markers: usize, camera: Option<Camera>) -> DetectorConfig {
    DetectorConfig {
        target: Target::WhyCode(family()),
        tracking,
        max_markers,
        camera,
        diameter_m: camera.map(|_| DIAMETER_M),
        ..DetectorConfig::default()
    }
}
