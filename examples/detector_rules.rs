//! Figures for the detector's reporting rules (issue 9): phantoms on desk
//! clutter without markers, which marker sizes are still reported and named,
//! and what a family of the wrong bit count makes of a ring.
//!
//! `cargo run --release --example detector_rules [frames]` (default 100
//! cluttered frames). Every scene is seeded, so figures repeat exactly.

use std::f64::consts::PI;

use image::GrayImage;
use whycode::camera::Camera;
use whycode::detect::{legacy, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{
    self, nearest, Background, LooseMarker, Placement, Reach, Scene, SceneObject, Sighting,
};
use whycode_testkit::desk::desk_clutter;
use whycode_testkit::tally::Counts;

const DEG: f64 = PI / 180.0;
const DIAMETER_M: f64 = 0.05;

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100);
    let family = Family::generate(8, 2).expect("8-bit family");

    println!("1. desk clutter without markers, 1280x720, {frames} frames");
    let clutter_frames: Vec<GrayImage> = (0..frames).map(|k| desk_clutter(k as u64 + 1)).collect();
    if let Ok(path) = std::env::var("SAVE_CLUTTER") {
        clutter_frames[0].save(path).expect("save");
    }
    for (name, kind) in [
        ("WhyCode 8-bit d=2", Kind::Family(family.clone())),
        ("WhyCode auto bits", Kind::Auto),
        ("legacy WhyCon", Kind::WhyCon),
    ] {
        let Some(mut detector) = detector(kind) else {
            continue;
        };
        let mut reports = 0;
        let mut seconds = Vec::new();
        for image in &clutter_frames {
            let start = std::time::Instant::now();
            let found = detector.detect(image);
            if std::env::var("SHOW_PHANTOMS").is_ok() {
                for d in &found {
                    println!(
                        "      phantom at ({:.0}, {:.0}) axes {:.1} x {:.1} bits {:?} code {:?} conf {:.2}",
                        d.u, d.v, d.axes[0], d.axes[1], d.bits, d.code, d.confidence
                    );
                }
            }
            reports += found.len();
            seconds.push(start.elapsed().as_secs_f64());
        }
        seconds.sort_by(f64::total_cmp);
        println!(
            "   {name:<20} {:.3} reports/frame ({reports} in {frames}), median {:.2} ms/frame",
            reports as f64 / frames as f64,
            1e3 * seconds[seconds.len() / 2]
        );
    }

    println!("2. 8-bit d=2 markers by size (0-45 deg tilt, noise 2): detected / named / wrong");
    for size in [8.0, 10.0, 12.0, 14.0, 16.0, 20.0, 30.0] {
        let counts = sized_markers(&family, size, 8, 24);
        println!(
            "   {size:>4} px: detected {:5.1} %, ID {:5.1} %, wrong IDs {}",
            counts.percent(counts.detected),
            counts.percent(counts.correct_id),
            counts.wrong_id
        );
    }

    println!(
        "   legacy WhyCon by size (same scenes; the original's floor: a 100 px black ring, 12.4 px face-on)"
    );
    for size in [8.0, 10.0, 12.0, 13.0, 14.0, 16.0, 20.0, 30.0] {
        let counts = sized_legacy_markers(size, 8, 24, legacy::MIN_INK_PX);
        let unfloored = sized_legacy_markers(size, 8, 24, 0.0);
        println!(
            "   {size:>4} px: detected {:5.1} % ({:5.1} % without the floor)",
            counts.percent(counts.detected),
            unfloored.percent(unfloored.detected)
        );
    }

    println!("3. wrong family: rings of one bit count read with another");
    for (printed_bits, printed_distance, read_bits, read_distance) in
        [(12, 2, 8, 2), (12, 2, 12, 3), (8, 2, 12, 2), (16, 2, 8, 2)]
    {
        let printed = Family::generate(printed_bits, printed_distance).expect("family");
        let read = Family::generate(read_bits, read_distance).expect("family");
        let (known, total, wrong, corrected) = wrong_family(&printed, &read);
        println!(
            "   {printed_bits}-bit d={printed_distance} read as {read_bits}-bit d={read_distance}: \
             {known} of {total} known IDs ({wrong} not the printed one), {corrected} by correction"
        );
    }

    println!("4. small rings: markers 10-16 px across read with families one or two counts off");
    let (known, total, named, own) = small_neighbours();
    println!(
        "   4-16 bits d=2: {known} known IDs in {total} readings with a family of 1-2 bits \
         more or fewer; their own family named {named} of {own}"
    );
}

/// Known IDs in readings of small markers (4-16 bits, 10-16 px, 0-45°)
/// with the families of up to two counts more or fewer, out of how many
/// readings; and how many of the markers their own family names.
fn small_neighbours() -> (usize, usize, usize, usize) {
    let (mut known, mut total, mut named, mut own) = (0, 0, 0, 0);
    for bits in 4..=16u32 {
        let printed = Family::generate(bits, 2).expect("family");
        for (f, size) in [10.0, 12.0, 14.0, 16.0].into_iter().enumerate() {
            let seed = 500 + u64::from(bits) * 10 + f as u64;
            let mut rng = Pcg32::new(seed, 5);
            let scene = marker_scene(&printed, size, 12, &mut rng, seed);
            let (image, truth) = simulate::render(&scene);
            let mut own_detector = detector(Kind::Family(printed.clone())).expect("family");
            own += truth.markers.len();
            named += own_detector
                .detect(&image)
                .iter()
                .filter(|d| {
                    d.id != 0
                        && nearest(&truth.markers, (d.u, d.v), f64::INFINITY)
                            .is_some_and(|m| m.id == d.id && (m.u - d.u).hypot(m.v - d.v) < 3.0)
                })
                .count();
            for read_bits in [bits.saturating_sub(2), bits - 1, bits + 1, bits + 2] {
                let Ok(read) = Family::generate(read_bits, 2) else {
                    continue;
                };
                let mut other = detector(Kind::Family(read)).expect("family");
                total += truth.markers.len();
                known += other.detect(&image).iter().filter(|d| d.id != 0).count();
            }
        }
    }
    (known, total, named, own)
}

enum Kind {
    Family(Family),
    Auto,
    WhyCon,
}

/// A default detector for one kind of marker (None: not supported here).
fn detector(kind: Kind) -> Option<Detector> {
    let target = match kind {
        Kind::Family(f) => Target::WhyCode(f),
        Kind::Auto => Target::AnyBits { distance: None },
        Kind::WhyCon => Target::WhyCon,
    };
    Some(Detector::new(DetectorConfig {
        target,
        ..Default::default()
    }))
}

fn camera() -> Camera {
    Camera::ideal(1280, 720, 60.0)
}

/// Reports this near a marker (0.3 of its size plus a pixel) are about it.
const NEAR: Reach = Reach {
    of_size: 0.3,
    px: 1.0,
};

/// Adds one frame's visible markers and what `detector` found to `counts`.
fn count(counts: &mut Counts, seed: u64, detector: &mut Detector, scene: &Scene) {
    let (image, truth) = simulate::render(scene);
    let found: Vec<Sighting> = detector.detect(&image).iter().map(Sighting::from).collect();
    counts.add_within(seed, &truth.targets(), &found, NEAR);
}

/// The scene of [`marker_scene`] with `family`'s markers, or legacy ones
/// (None) in their places.
fn marker_scene(family: &Family, size: f64, count: usize, rng: &mut Pcg32, seed: u64) -> Scene {
    marker_scene_of(Some(family), size, count, rng, seed)
}

fn marker_scene_of(
    family: Option<&Family>,
    size: f64,
    count: usize,
    rng: &mut Pcg32,
    seed: u64,
) -> Scene {
    let cam = camera();
    let mut scene = Scene::new(cam);
    let cols = 6;
    let rows = count.div_ceil(cols);
    for k in 0..count {
        let (col, row) = (k % cols, k / cols);
        let u = (col as f64 + 0.5) * 1280.0 / cols as f64 + rng.range(-20.0, 20.0);
        let v = (row as f64 + 0.5) * 720.0 / rows as f64 + rng.range(-20.0, 20.0);
        let draw = rng.next_u32();
        let tilt = rng.range(0.0, 45.0) * DEG;
        let roll = rng.range(0.0, 2.0 * PI);
        let (marker, id) = match family {
            Some(family) => {
                let id = 1 + draw % family.len() as u32;
                let code = family.code(id).expect("member");
                (
                    Marker::whycode(family.bits(), code, DIAMETER_M * 1000.0),
                    id,
                )
            }
            None => (Marker::whycon(DIAMETER_M * 1000.0), 0),
        };
        let placement = Placement::at_pixel(&cam, &marker, (u, v), size, tilt, 0.0, roll);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    }
    scene.background = Background::Uniform(0.45);
    scene.noise = 2.0;
    scene.seed = seed;
    scene
}

fn sized_markers(family: &Family, size: f64, frames: usize, per_frame: usize) -> Counts {
    let mut counts = Counts::default();
    let mut detector = detector(Kind::Family(family.clone())).expect("family detector");
    for f in 0..frames {
        let seed = 1000 + f as u64;
        let mut rng = Pcg32::new(seed, 3);
        let scene = marker_scene(family, size, per_frame, &mut rng, seed);
        count(&mut counts, seed, &mut detector, &scene);
    }
    counts
}

/// Legacy markers found among those of [`sized_markers`]'s scenes, with
/// a black ring of at least `min_ink_px` pixels.
fn sized_legacy_markers(size: f64, frames: usize, per_frame: usize, min_ink_px: f64) -> Counts {
    let mut counts = Counts::default();
    let mut detector = Detector::new(DetectorConfig {
        legacy_min_ink_px: min_ink_px,
        ..Default::default()
    });
    for f in 0..frames {
        let seed = 1000 + f as u64;
        let mut rng = Pcg32::new(seed, 3);
        let scene = marker_scene_of(None, size, per_frame, &mut rng, seed);
        count(&mut counts, seed, &mut detector, &scene);
    }
    counts
}

/// Known IDs (and wrong ones, and ones needing correction) when markers of
/// `printed` are read with `read`.
fn wrong_family(printed: &Family, read: &Family) -> (usize, usize, usize, usize) {
    let mut detector = detector(Kind::Family(read.clone())).expect("family detector");
    let (mut known, mut total, mut wrong, mut corrected) = (0, 0, 0, 0);
    for f in 0..2u64 {
        let mut rng = Pcg32::new(77 + f, 5);
        let size = 60.0 + 10.0 * f as f64;
        let scene = marker_scene(printed, size, 12, &mut rng, 77 + f);
        let (image, truth) = simulate::render(&scene);
        let found = detector.detect(&image);
        total += truth.markers.len();
        for d in found.iter().filter(|d| d.id != 0) {
            known += 1;
            if let Some(m) = nearest(&truth.markers, (d.u, d.v), f64::INFINITY) {
                if m.code != d.code.unwrap_or(0) || m.bits != read.bits() {
                    wrong += 1;
                }
            }
            if d.status == Some(whycode::family::MatchStatus::Corrected) {
                corrected += 1;
            }
        }
    }
    (known, total, wrong, corrected)
}
