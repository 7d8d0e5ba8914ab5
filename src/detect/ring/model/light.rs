//! The letter-vs-marker light test: a small ring that the model vouches
//! for without naming a member must show a marker's round light, not the
//! stretched hole of a letter drawn with a pen.

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::footprint::MarkerFrame;
use super::COMPARED_RADIUS;
use crate::geometry::WHYCODE_WHITE_RATIO;
use crate::math::Ellipse as ImageEllipse;

/// Most elongation of a small ring's light along its outline's major axis
/// ([`light_elongation`]) for a ring the model vouches for without naming
/// it. The light of real small rings spreads either way, the code's second
/// harmonic turned any way, and stays under it; the hole of a bold
/// stroke-font letter is stretched along the major axis, most letters' to
/// near it or past it, and the 'O' once reported as a marker well past it
/// (the spreads, measured by `examples/small_ring_light`:
/// docs/detection.md, "The 11 px 'O', reproduced"). Rings the model names
/// are left alone: a member explaining them with a clear margin over every
/// other is what no letter earned.
pub const MAX_LIGHT_ELONGATION: f64 = 0.23;

/// How much more the light inside the ring's outer edge (radius 0.6 of
/// the outline) spreads along the outline's major axis than along its
/// minor one, in the outline's own frame: (Σ l·p² − Σ l·q²) / (Σ l·p² +
/// Σ l·q²), l a pixel's lightness between the disc's darkest tenth and
/// the white margin around it. A marker's light, its centre disc and the
/// white half of every bit, is as round as its outline up to the code's
/// second harmonic. A letter's hole is not: a pen of constant width
/// leaves a hole the narrower beside the outline the narrower the outline
/// is, so the hole is stretched along the major axis (an 'O' 10.7 × 8.4 px
/// outside, 2 × 5 px inside). `None` when the ring leaves the image.
pub fn light_elongation<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
) -> Option<f64> {
    let frame = MarkerFrame::of(outer);
    let (a, b) = (outer.semi_major, outer.semi_minor);
    let (width, height) = image.dimensions();
    let reach = a * MARGIN_RADII.1 + 1.0;
    let (x0, x1) = ((outer.u - reach).floor(), (outer.u + reach).ceil());
    let (y0, y1) = ((outer.v - reach).floor(), (outer.v + reach).ceil());
    if !(b > 0.0 && x0 >= 0.0 && y0 >= 0.0 && x1 < f64::from(width) && y1 < f64::from(height)) {
        return None;
    }
    let mut disc: Vec<(f64, f64, f64)> = Vec::new();
    let mut margin: Vec<f64> = Vec::new();
    for y in y0 as u32..=y1 as u32 {
        for x in x0 as u32..=x1 as u32 {
            let (p, q) = frame.marker_point(f64::from(x), f64::from(y));
            let rho = p.hypot(q);
            let grey = f64::from(image.get_pixel(x, y).0[0]);
            if rho <= COMPARED_RADIUS {
                disc.push((p, q, grey));
            } else if (MARGIN_RADII.0..MARGIN_RADII.1).contains(&rho) {
                margin.push(grey);
            }
        }
    }
    if disc.len() < 12 || margin.is_empty() {
        return None;
    }
    let mut greys: Vec<f64> = disc.iter().map(|d| d.2).collect();
    let (_, &mut black, _) = greys.select_nth_unstable_by(disc.len() / 10, f64::total_cmp);
    let middle = margin.len() / 2;
    let (_, &mut white, _) = margin.select_nth_unstable_by(middle, f64::total_cmp);
    let span = (white - black).max(1.0);
    let (mut along, mut across) = (0.0, 0.0);
    for &(p, q, grey) in &disc {
        if p.hypot(q) < WHYCODE_WHITE_RATIO {
            let light = ((grey - black) / span).clamp(0.0, 1.0);
            along += light * p * p;
            across += light * q * q;
        }
    }
    (along + across > 0.0).then(|| (along - across) / (along + across))
}

/// The white margin around a marker's disc, in radii of its outline: its
/// grey is the light that [`light_elongation`] measures against.
const MARGIN_RADII: (f64, f64) = (1.1, 1.3);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::ring::test_images::draw;
    use crate::family::Family;
    use crate::geometry::Marker;

    #[test]
    fn a_markers_light_is_round_and_a_pen_drawn_hole_is_not() {
        let family = Family::generate(8, 2).unwrap();
        for id in 1..=family.len() as u32 {
            for turn in [0.0, 0.7, 1.9] {
                let marker = Marker::whycode(8, family.code(id).unwrap(), 50.0);
                let (image, outline) = draw(&marker, 10.0, 24, (12.3, 11.6), turn);
                let e = light_elongation(&image, &outline).unwrap();
                assert!(e.abs() <= MAX_LIGHT_ELONGATION, "ID {id}, turn {turn}: {e}");
            }
        }
        // An 'O' drawn with a pen 3 px wide, 10.7 x 8.4 px outside (the
        // stroke-font 'O' of docs/detection.md: a hole 2 x 5 px).
        let outline = ImageEllipse {
            u: 12.2,
            v: 11.7,
            semi_major: 5.35,
            semi_minor: 4.2,
            angle: 0.0,
        };
        let inside = |x: f64, y: f64, a: f64, b: f64| {
            let (dx, dy) = (x - outline.u, y - outline.v);
            (dx / a).powi(2) + (dy / b).powi(2) <= 1.0
        };
        let letter = image::GrayImage::from_fn(24, 24, |x, y| {
            let ink = (0..16)
                .filter(|k| {
                    let (sx, sy) = (
                        f64::from(x) + (f64::from(k % 4) - 1.5) / 4.0,
                        f64::from(y) + (f64::from(k / 4) - 1.5) / 4.0,
                    );
                    inside(sx, sy, 5.35, 4.2) && !inside(sx, sy, 2.35, 1.2)
                })
                .count();
            Luma([(200 - 10 * ink) as u8])
        });
        let e = light_elongation(&letter, &outline).unwrap();
        assert!(e > MAX_LIGHT_ELONGATION, "{e}");
    }
}
