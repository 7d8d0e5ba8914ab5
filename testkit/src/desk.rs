//! A cluttered desk without markers, for the phantom rules (issue 9): the
//! simulator's clutter (filled and hollow circles, ellipses, rectangles,
//! lines) plus what a desk adds: printed text in several weights, hollow
//! circles of every hole ratio but WhyCon's, dark blobs with an off-centre
//! hole, and washers whose light middle has marker proportions. The
//! integration tests and `examples/detector_rules` see the same scenes.

use std::f64::consts::PI;

use image::GrayImage;
use whycode::camera::Camera;
use whycode::math::Pcg32;
use whycode::render::font::stroke_text;
use whycode::render::page::{Anchor, Segment};
use whycode::simulate::{self, Background, Scene};

/// A 1280x720 desk frame without markers (seeded): the simulator's clutter (filled and
/// hollow circles, ellipses, rectangles, lines) plus what a desk adds:
/// printed text in several weights, hollow circles of every hole ratio
/// (but WhyCon's own 0.41, which is a legacy marker), dark blobs with an
/// off-centre hole, and washers whose light middle has marker proportions.
pub fn desk_clutter(seed: u64) -> GrayImage {
    let mut scene = Scene::new(Camera::ideal(1280, 720, 60.0));
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
            let ink = rng.range(10.0, 60.0);
            stroke_letters(&mut image, text, (x0, baseline), size_pt, weight, ink);
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
        let hole = match rng.next_u32() % 3 {
            0 => {
                // Hollow circle, any hole but WhyCon's.
                let mut hole = rng.range(0.25, 0.9);
                if (hole - 0.41).abs() < 0.05 {
                    hole += 0.1;
                }
                (hole, 0.0, 0.0)
            }
            1 => {
                // Blob with an off-centre hole.
                let hole = rng.range(0.3, 0.7);
                let offset = rng.range(0.08, 0.3);
                let dir = rng.range(0.0, 2.0 * PI);
                (hole, offset * dir.cos(), offset * dir.sin())
            }
            // Washer: light middle at a marker-like ratio.
            _ => (rng.range(0.45, 0.65), 0.0, 0.0),
        };
        ring(&mut image, (cx, cy), r, squash, angle, hole, ink, light);
    }
    image
}

/// Draws `text` in the stroke font on `image`: baseline starting at
/// (x, y) pixels, at 3 pixels per millimetre, the pen `weight` times the
/// font's own, in grey `ink`.
pub fn stroke_letters(
    image: &mut GrayImage,
    text: &str,
    (x, y): (f64, f64),
    size_pt: f64,
    weight: f64,
    ink: f64,
) {
    let scale = 3.0;
    let segments = stroke_text(text, x / scale, y / scale, size_pt, Anchor::Start);
    let pen = whycode::render::font::stroke_pen_mm(size_pt) * scale * weight;
    draw_polylines(image, &segments, scale, pen, ink);
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
