//! Annotated copies of validated photos: each marker outlined in the colour
//! of its status, missing ones drawn dashed where they should be.

use super::{MarkerStatus, PhotoReport};
use image::{GrayImage, Rgb, RgbImage};

pub(crate) const GREEN: Rgb<u8> = Rgb([0, 200, 0]);
pub(crate) const RED: Rgb<u8> = Rgb([230, 0, 0]);
pub(crate) const ORANGE: Rgb<u8> = Rgb([255, 150, 0]);
pub(crate) const MAGENTA: Rgb<u8> = Rgb([230, 0, 230]);
pub(crate) const CYAN: Rgb<u8> = Rgb([0, 190, 230]);

pub(crate) fn status_colour(status: MarkerStatus) -> Rgb<u8> {
    match status {
        MarkerStatus::Found => GREEN,
        MarkerStatus::Misread => RED,
        MarkerStatus::Unidentified => ORANGE,
        MarkerStatus::Missing | MarkerStatus::NotInView => MAGENTA,
    }
}

/// The photo in colour with the report drawn over it. Line width grows
/// with the image so that it stays visible when the photo is scaled down.
pub fn annotate(image: &GrayImage, report: &PhotoReport) -> RgbImage {
    let mut out = RgbImage::from_fn(image.width(), image.height(), |x, y| {
        let g = image.get_pixel(x, y)[0];
        Rgb([g, g, g])
    });
    let thickness = (f64::from(image.width().max(image.height())) / 800.0).clamp(1.0, 6.0);
    for page in &report.pages {
        if let Some(c) = page.scale.corners() {
            for k in 0..4 {
                line(&mut out, c[k], c[(k + 1) % 4], thickness, CYAN);
            }
        }
    }
    for m in &report.markers {
        let Some(mut e) = m.outline else {
            continue;
        };
        // Just outside the black disc, so the outline does not hide its edge.
        e.semi_major += 1.5 * thickness;
        e.semi_minor += 1.5 * thickness;
        let colour = status_colour(m.status);
        let dashed = matches!(m.status, MarkerStatus::Missing | MarkerStatus::NotInView);
        let steps = ((e.semi_major * 0.8) as usize).clamp(24, 720);
        for k in 0..steps {
            if dashed && (k / 3) % 2 == 1 {
                continue;
            }
            let t0 = k as f64 / steps as f64 * std::f64::consts::TAU;
            let t1 = (k + 1) as f64 / steps as f64 * std::f64::consts::TAU;
            line(&mut out, e.point_at(t0), e.point_at(t1), thickness, colour);
        }
        // Misread markers get a cross so they stand out in a crowd.
        if m.status == MarkerStatus::Misread {
            let r = e.semi_minor * 0.7;
            line(
                &mut out,
                (e.u - r, e.v - r),
                (e.u + r, e.v + r),
                thickness,
                colour,
            );
            line(
                &mut out,
                (e.u - r, e.v + r),
                (e.u + r, e.v - r),
                thickness,
                colour,
            );
        }
    }
    out
}

/// A thick line segment (round caps), clipped to the image.
fn line(image: &mut RgbImage, a: (f64, f64), b: (f64, f64), thickness: f64, colour: Rgb<u8>) {
    let half = thickness / 2.0;
    let (w, h) = (image.width() as i64, image.height() as i64);
    let x0 = (a.0.min(b.0) - half).floor().max(0.0) as i64;
    let x1 = (a.0.max(b.0) + half).ceil().min((w - 1) as f64) as i64;
    let y0 = (a.1.min(b.1) - half).floor().max(0.0) as i64;
    let y1 = (a.1.max(b.1) + half).ceil().min((h - 1) as f64) as i64;
    if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
        return;
    }
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (px, py) = (x as f64 - a.0, y as f64 - a.1);
            let t = if len2 > 0.0 {
                ((px * dx + py * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            if (px - t * dx).hypot(py - t * dy) <= half {
                image.put_pixel(x as u32, y as u32, colour);
            }
        }
    }
}
