//! Figures for the detector's reporting rules (issue 9): phantoms on desk
//! clutter without markers, which marker sizes are still reported and named,
//! and what a family of the wrong bit count makes of a ring.
//!
//! `cargo run --release --example detector_rules [frames]` (default 100
//! cluttered frames). Every scene is seeded, so figures repeat exactly.

use std::f64::consts::PI;

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::render::font::stroke_text;
use whycode::render::page::{Anchor, Segment};
use whycode::simulate::{self, Background, LooseMarker, Placement, Scene, SceneObject};

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
            counts.percent(counts.named),
            counts.wrong
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

#[derive(Default)]
struct Counts {
    total: usize,
    detected: usize,
    named: usize,
    wrong: usize,
}

impl Counts {
    fn percent(&self, n: usize) -> f64 {
        100.0 * n as f64 / self.total.max(1) as f64
    }
}

fn camera() -> Camera {
    Camera::ideal(1280, 720, 60.0)
}

/// A marker whose centre projects to (u, v), `diameter_px` across face-on.
fn placement_at(camera: &Camera, (u, v): (f64, f64), diameter_px: f64, tilt: f64) -> Placement {
    let z = camera.fx * DIAMETER_M / diameter_px;
    let (x, y) = camera.undistort(u, v);
    Placement::viewed(Vector3::new(x * z, y * z, z), tilt, 0.0, 0.0)
}

fn marker_scene(family: &Family, size: f64, count: usize, rng: &mut Pcg32, seed: u64) -> Scene {
    let cam = camera();
    let mut scene = Scene::new(cam);
    let cols = 6;
    let rows = count.div_ceil(cols);
    for k in 0..count {
        let (col, row) = (k % cols, k / cols);
        let u = (col as f64 + 0.5) * 1280.0 / cols as f64 + rng.range(-20.0, 20.0);
        let v = (row as f64 + 0.5) * 720.0 / rows as f64 + rng.range(-20.0, 20.0);
        let id = 1 + rng.next_u32() % family.len() as u32;
        let code = family.code(id).expect("member");
        let tilt = rng.range(0.0, 45.0) * DEG;
        let roll = rng.range(0.0, 2.0 * PI);
        let mut placement = placement_at(&cam, (u, v), size, tilt);
        placement.rotation *=
            *nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), roll).matrix();
        let marker = Marker::whycode(family.bits(), code, DIAMETER_M * 1000.0);
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
        let mut rng = Pcg32::new(1000 + f as u64, 3);
        let scene = marker_scene(family, size, per_frame, &mut rng, 1000 + f as u64);
        let (image, truth) = simulate::render(&scene);
        let found = detector.detect(&image);
        for m in truth.markers.iter().filter(|m| m.visible) {
            counts.total += 1;
            let near = nearest(&found, m.u, m.v, 0.3 * m.diameter_px + 1.0);
            if let Some(d) = near {
                counts.detected += 1;
                if d.id == m.id {
                    counts.named += 1;
                } else if d.id != 0 {
                    counts.wrong += 1;
                }
            }
        }
    }
    counts
}

fn nearest(found: &[Detection], u: f64, v: f64, reach: f64) -> Option<&Detection> {
    found
        .iter()
        .filter(|d| (d.u - u).hypot(d.v - v) < reach)
        .min_by(|a, b| {
            (a.u - u)
                .hypot(a.v - v)
                .total_cmp(&(b.u - u).hypot(b.v - v))
        })
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
            if let Some(m) = nearest_truth(&truth.markers, d) {
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

fn nearest_truth<'a>(
    markers: &'a [whycode::simulate::TrueMarker],
    d: &Detection,
) -> Option<&'a whycode::simulate::TrueMarker> {
    markers.iter().min_by(|a, b| {
        (a.u - d.u)
            .hypot(a.v - d.v)
            .total_cmp(&(b.u - d.u).hypot(b.v - d.v))
    })
}

/// A 1280x720 desk without markers: the simulator's clutter (filled and
/// hollow circles, ellipses, rectangles, lines) plus what a desk adds:
/// printed text in several weights, hollow circles of every hole ratio
/// (but WhyCon's own 0.41, which is a legacy marker), dark blobs with an
/// off-centre hole, and washers whose light middle has marker proportions.
fn desk_clutter(seed: u64) -> GrayImage {
    let mut scene = Scene::new(camera());
    scene.background = Background::Clutter { density: 1.5 };
    scene.noise = 2.0;
    scene.seed = seed;
    let (mut image, _) = simulate::render(&scene);
    let mut rng = Pcg32::new(seed, 99);
    let paper = 215.0;
    // Text blocks on light paper patches.
    for _ in 0..6 {
        let (x0, y0) = (rng.range(0.0, 1100.0), rng.range(0.0, 650.0));
        let size_pt = rng.range(4.0, 22.0);
        let weight = rng.range(1.0, 2.6);
        let lines = 1 + rng.next_u32() % 5;
        let scale = 3.0; // pixels per millimetre of the stroke font
        let line_height = size_pt * 0.5 * scale;
        let width = 60.0 * size_pt / 10.0 * scale;
        fill(
            &mut image,
            x0,
            y0,
            x0 + width,
            y0 + line_height * (lines as f64 + 0.5),
            |_, _| Some(paper),
        );
        let words = [
            "good morning",
            "boot loop 808",
            "pod bag doge",
            "queue 0600 do",
            "dope code",
            "a bad egg",
            "90 68 00 98",
            "@ odd bob",
            "o o o O O 0",
        ];
        for l in 0..lines {
            let text = words[rng.next_u32() as usize % words.len()];
            let baseline = y0 + line_height * (l as f64 + 1.0);
            let segments = stroke_text(text, x0 / scale, baseline / scale, size_pt, Anchor::Start);
            let pen = whycode::render::font::stroke_pen_mm(size_pt) * scale * weight;
            draw_polylines(&mut image, &segments, scale, pen, rng.range(10.0, 60.0));
        }
    }
    // Round things.
    for _ in 0..25 {
        let (cx, cy) = (rng.range(0.0, 1280.0), rng.range(0.0, 720.0));
        let r = (rng.range(3f64.ln(), 60f64.ln())).exp();
        let ink = rng.range(10.0, 70.0);
        let light = rng.range(150.0, 230.0);
        let squash = rng.range(0.6, 1.0);
        let angle = rng.range(0.0, PI);
        match rng.next_u32() % 3 {
            0 => {
                // Hollow circle, any hole but WhyCon's.
                let mut hole = rng.range(0.25, 0.9);
                if (hole - 0.41).abs() < 0.05 {
                    hole += 0.1;
                }
                ring(
                    &mut image,
                    (cx, cy),
                    r,
                    squash,
                    angle,
                    (hole, 0.0, 0.0),
                    ink,
                    light,
                );
            }
            1 => {
                // Blob with an off-centre hole.
                let hole = rng.range(0.3, 0.7);
                let offset = rng.range(0.08, 0.3);
                let dir = rng.range(0.0, 2.0 * PI);
                let hole_centre = (offset * dir.cos(), offset * dir.sin());
                ring(
                    &mut image,
                    (cx, cy),
                    r,
                    squash,
                    angle,
                    (hole, hole_centre.0, hole_centre.1),
                    ink,
                    light,
                );
            }
            _ => {
                // Washer: light middle at a marker-like ratio.
                let hole = rng.range(0.45, 0.65);
                ring(
                    &mut image,
                    (cx, cy),
                    r,
                    squash,
                    angle,
                    (hole, 0.0, 0.0),
                    ink,
                    light,
                );
            }
        }
    }
    image
}

/// Supersampled fill of pixels inside a box: `shade(x, y)` gives the grey
/// at a sub-pixel point, or None to keep the pixel's own.
fn fill(
    image: &mut GrayImage,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    shade: impl Fn(f64, f64) -> Option<f64>,
) {
    let (w, h) = (image.width() as i64, image.height() as i64);
    let (px0, py0) = ((x0.floor() as i64).max(0), (y0.floor() as i64).max(0));
    let (px1, py1) = ((x1.ceil() as i64).min(w - 1), (y1.ceil() as i64).min(h - 1));
    for y in py0..=py1 {
        for x in px0..=px1 {
            let own = f64::from(image.get_pixel(x as u32, y as u32).0[0]);
            let mut sum = 0.0;
            for sy in 0..4 {
                for sx in 0..4 {
                    let (fx, fy) = (
                        x as f64 + (sx as f64 + 0.5) / 4.0 - 0.5,
                        y as f64 + (sy as f64 + 0.5) / 4.0 - 0.5,
                    );
                    sum += shade(fx, fy).unwrap_or(own);
                }
            }
            image.put_pixel(
                x as u32,
                y as u32,
                image::Luma([(sum / 16.0).round().clamp(0.0, 255.0) as u8]),
            );
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn ring(
    image: &mut GrayImage,
    (cx, cy): (f64, f64),
    r: f64,
    squash: f64,
    angle: f64,
    (hole, hx, hy): (f64, f64, f64),
    ink: f64,
    light: f64,
) {
    let (s, c) = angle.sin_cos();
    let reach = r + 1.0;
    fill(
        image,
        cx - reach,
        cy - reach,
        cx + reach,
        cy + reach,
        |x, y| {
            let (dx, dy) = (x - cx, y - cy);
            let (p, q) = ((dx * c + dy * s) / r, (-dx * s + dy * c) / (r * squash));
            if p * p + q * q > 1.0 {
                None
            } else if (p - hx).powi(2) + (q - hy).powi(2) < hole * hole {
                Some(light)
            } else {
                Some(ink)
            }
        },
    );
}

fn draw_polylines(image: &mut GrayImage, segments: &[Segment], scale: f64, pen: f64, ink: f64) {
    let mut previous: Option<(f64, f64)> = None;
    for segment in segments {
        let point = match *segment {
            Segment::MoveTo(x, y) => {
                previous = Some((x * scale, y * scale));
                continue;
            }
            Segment::LineTo(x, y) => (x * scale, y * scale),
            Segment::CubicTo(_, _, _, _, x, y) => (x * scale, y * scale),
            Segment::Close => continue,
        };
        if let Some(from) = previous {
            let half = pen / 2.0;
            let (x0, x1) = (from.0.min(point.0) - half, from.0.max(point.0) + half);
            let (y0, y1) = (from.1.min(point.1) - half, from.1.max(point.1) + half);
            fill(image, x0, y0, x1, y1, |x, y| {
                let (dx, dy) = (point.0 - from.0, point.1 - from.1);
                let len2 = (dx * dx + dy * dy).max(1e-12);
                let t = (((x - from.0) * dx + (y - from.1) * dy) / len2).clamp(0.0, 1.0);
                let (ex, ey) = (x - from.0 - t * dx, y - from.1 - t * dy);
                (ex * ex + ey * ey <= half * half).then_some(ink)
            });
        }
        previous = Some(point);
    }
}
