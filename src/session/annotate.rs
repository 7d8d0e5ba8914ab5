//! Drawing detections over the image they came from: each marker's outer
//! ellipse, its +x axis and its ID, for checking a detector run by eye.

use crate::detect::Detection;
use crate::render::RenderError;
use image::{GrayImage, RgbImage};
use std::f64::consts::PI;
use tiny_skia::{Color, LineCap, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

/// Ellipse colour of a marker with a known ID (green), an unknown ID
/// (orange) and a legacy marker without ring (cyan); axis in red.
const KNOWN: [u8; 3] = [40, 200, 60];
const UNKNOWN: [u8; 3] = [255, 150, 0];
const LEGACY: [u8; 3] = [0, 190, 230];
const AXIS: [u8; 3] = [230, 30, 30];

/// The image in colour with the detections drawn, encoded as PNG.
pub fn annotated_png(image: &GrayImage, detections: &[Detection]) -> Result<Vec<u8>, RenderError> {
    crate::image_io::encode_rgb_png(&annotated_rgb(image, detections)?).map_err(|e| {
        RenderError::Encode {
            format: "PNG",
            detail: e.to_string(),
        }
    })
}

/// The image in colour with the detections drawn: what [`annotated_png`]
/// encodes, for callers that send pixels on (a video, a ROS image topic).
pub fn annotated_rgb(image: &GrayImage, detections: &[Detection]) -> Result<RgbImage, RenderError> {
    drawn(image.width(), image.height(), detections, |pixels| {
        for (dst, &g) in pixels.chunks_exact_mut(4).zip(image.as_raw()) {
            dst.copy_from_slice(&[g, g, g, 255]);
        }
    })
}

/// The detections drawn over a colour picture of the frame they came from
/// (the caller's own camera image rather than its grey).
pub fn drawn_over(picture: &RgbImage, detections: &[Detection]) -> Result<RgbImage, RenderError> {
    drawn(picture.width(), picture.height(), detections, |pixels| {
        for (dst, src) in pixels
            .chunks_exact_mut(4)
            .zip(picture.as_raw().chunks_exact(3))
        {
            dst.copy_from_slice(&[src[0], src[1], src[2], 255]);
        }
    })
}

/// The detections drawn over what `fill` puts in an opaque RGBA canvas of
/// `w` x `h`.
fn drawn(
    w: u32,
    h: u32,
    detections: &[Detection],
    fill: impl FnOnce(&mut [u8]),
) -> Result<RgbImage, RenderError> {
    let too_large = RenderError::ImageTooLarge {
        width: w,
        height: h,
    };
    let Some(mut pixmap) = Pixmap::new(w.max(1), h.max(1)) else {
        return Err(too_large);
    };
    fill(pixmap.data_mut());
    let line = (f64::from(w.max(h)) / 800.0).clamp(1.0, 4.0) as f32;
    for d in detections {
        draw_detection(&mut pixmap, d, line);
    }
    // Labels after every outline, each placed where it covers no marker
    // and no earlier label: in a crowd, a label beside its own marker
    // otherwise lands on its neighbour's outline.
    let outlines: Vec<Bounds> = detections.iter().map(outline_bounds).collect();
    let mut taken = outlines.clone();
    for (d, own) in detections.iter().zip(&outlines) {
        if let Some((text, cell, colour)) = label(d) {
            let place = label_place(own, &text, cell, &taken, (f64::from(w), f64::from(h)));
            draw_text(&mut pixmap, &text, place.x0, place.y0, cell, colour);
            taken.push(place);
        }
    }
    let rgb: Vec<u8> = pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    RgbImage::from_raw(pixmap.width(), pixmap.height(), rgb).ok_or(too_large)
}

fn paint(rgb: [u8; 3]) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color(Color::from_rgba8(rgb[0], rgb[1], rgb[2], 255));
    paint.anti_alias = true;
    paint
}

/// Point of the outer ellipse at parameter `t` (pixel centres at integer
/// coordinates; tiny-skia's pixel centres sit at +0.5).
fn ellipse_point(d: &Detection, t: f64) -> (f32, f32) {
    let (s, c) = d.angle.sin_cos();
    let (st, ct) = t.sin_cos();
    let x = d.u + d.axes[0] * ct * c - d.axes[1] * st * s;
    let y = d.v + d.axes[0] * ct * s + d.axes[1] * st * c;
    ((x + 0.5) as f32, (y + 0.5) as f32)
}

fn draw_detection(pixmap: &mut Pixmap, d: &Detection, line: f32) {
    let colour = match (d.id, d.yaw, d.status) {
        (0, _, None) => LEGACY,
        (0, _, Some(_)) => UNKNOWN,
        _ => KNOWN,
    };
    let stroke = Stroke {
        width: line,
        line_cap: LineCap::Round,
        ..Stroke::default()
    };
    let mut pb = PathBuilder::new();
    const STEPS: usize = 72;
    for k in 0..=STEPS {
        let (x, y) = ellipse_point(d, 2.0 * PI * k as f64 / STEPS as f64);
        if k == 0 {
            pb.move_to(x, y);
        } else {
            pb.line_to(x, y);
        }
    }
    if let Some(path) = pb.finish() {
        pixmap.stroke_path(&path, &paint(colour), &stroke, Transform::identity(), None);
    }
    if let Some(yaw) = d.yaw {
        // Out to where the +x axis meets the outer ellipse.
        let rel = yaw - d.angle;
        let r = 1.0
            / ((rel.cos() / d.axes[0].max(1e-9)).powi(2)
                + (rel.sin() / d.axes[1].max(1e-9)).powi(2))
            .sqrt();
        let mut pb = PathBuilder::new();
        pb.move_to((d.u + 0.5) as f32, (d.v + 0.5) as f32);
        pb.line_to(
            (d.u + 0.5 + r * yaw.cos()) as f32,
            (d.v + 0.5 + r * yaw.sin()) as f32,
        );
        if let Some(path) = pb.finish() {
            pixmap.stroke_path(&path, &paint(AXIS), &stroke, Transform::identity(), None);
        }
    }
}

/// A marker's label (its ID, "?" when unknown; none for a legacy marker),
/// the glyph cell size (digits about a third of the marker tall) and colour.
fn label(d: &Detection) -> Option<(String, f64, [u8; 3])> {
    d.status?;
    let text = if d.id == 0 {
        "?".to_string()
    } else {
        d.id.to_string()
    };
    let colour = if d.id == 0 { UNKNOWN } else { KNOWN };
    Some((text, (d.axes[0] / 8.0).clamp(1.5, 12.0), colour))
}

/// An axis-aligned box, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bounds {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Bounds {
    fn overlap(&self, other: &Bounds) -> f64 {
        let w = (self.x1.min(other.x1) - self.x0.max(other.x0)).max(0.0);
        let h = (self.y1.min(other.y1) - self.y0.max(other.y0)).max(0.0);
        w * h
    }
}

/// The box round a marker's drawn outline (with the line's width).
fn outline_bounds(d: &Detection) -> Bounds {
    let (s, c) = d.angle.sin_cos();
    let [a, b] = d.axes;
    let half_w = ((a * c).powi(2) + (b * s).powi(2)).sqrt() + 2.0;
    let half_h = ((a * s).powi(2) + (b * c).powi(2)).sqrt() + 2.0;
    Bounds {
        x0: d.u - half_w,
        y0: d.v - half_h,
        x1: d.u + half_w,
        y1: d.v + half_h,
    }
}

/// Where a label goes: the first of right, left, above, below and the
/// four corners of its marker's box that lies in the image and covers no
/// marker or earlier label; else the one covering least.
fn label_place(own: &Bounds, text: &str, cell: f64, taken: &[Bounds], image: (f64, f64)) -> Bounds {
    let (w, h) = (text.chars().count() as f64 * 4.0 * cell - cell, 5.0 * cell);
    let gap = cell;
    let (mid_x, mid_y) = ((own.x0 + own.x1) / 2.0, (own.y0 + own.y1) / 2.0);
    let corners = [
        (own.x1 + gap, mid_y - h / 2.0),
        (own.x0 - gap - w, mid_y - h / 2.0),
        (mid_x - w / 2.0, own.y0 - gap - h),
        (mid_x - w / 2.0, own.y1 + gap),
        (own.x1 + gap, own.y0 - gap - h),
        (own.x0 - gap - w, own.y0 - gap - h),
        (own.x1 + gap, own.y1 + gap),
        (own.x0 - gap - w, own.y1 + gap),
    ];
    let boxes = corners.map(|(x0, y0)| Bounds {
        x0,
        y0,
        x1: x0 + w,
        y1: y0 + h,
    });
    let cost = |b: &Bounds| {
        let outside = (b.x1 - b.x0) * (b.y1 - b.y0)
            - b.overlap(&Bounds {
                x0: 0.0,
                y0: 0.0,
                x1: image.0,
                y1: image.1,
            });
        outside + taken.iter().map(|t| t.overlap(b)).sum::<f64>()
    };
    let mut best = boxes[0];
    let mut best_cost = f64::INFINITY;
    for b in boxes {
        let c = cost(&b);
        if c <= 0.0 {
            return b;
        }
        if c < best_cost {
            (best, best_cost) = (b, c);
        }
    }
    best
}

/// 3x5 bitmap glyphs: rows top to bottom, bit 2 is the left column.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 2, 2],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        _ => [7, 1, 3, 0, 2],
    }
}

fn draw_text(pixmap: &mut Pixmap, text: &str, x: f64, y: f64, cell: f64, rgb: [u8; 3]) {
    let ink = paint(rgb);
    let mut shadow = paint([0, 0, 0]);
    shadow.anti_alias = false;
    for (k, c) in text.chars().enumerate() {
        let rows = glyph(c);
        let gx = x + k as f64 * 4.0 * cell;
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 0 {
                    continue;
                }
                let px = gx + col as f64 * cell;
                let py = y + row as f64 * cell;
                // A dark outline keeps the glyph readable on white paper.
                if let Some(r) = Rect::from_xywh(
                    (px - 0.5) as f32,
                    (py - 0.5) as f32,
                    (cell + 1.0) as f32,
                    (cell + 1.0) as f32,
                ) {
                    pixmap.fill_rect(r, &shadow, Transform::identity(), None);
                }
            }
        }
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 0 {
                    continue;
                }
                if let Some(r) = Rect::from_xywh(
                    (gx + col as f64 * cell) as f32,
                    (y + row as f64 * cell) as f32,
                    cell as f32,
                    cell as f32,
                ) {
                    pixmap.fill_rect(r, &ink, Transform::identity(), None);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn marker(id: u32, u: f64, v: f64) -> Detection {
        Detection {
            id,
            code: None,
            u,
            v,
            yaw: Some(0.0),
            axes: [20.0, 20.0],
            angle: 0.0,
            confidence: 1.0,
            status: Some(crate::family::MatchStatus::Exact),
            pose: None,
            bits: Some(8),
            unreadable: false,
            unnamed: None,
            track: None,
        }
    }

    #[test]
    fn labels_keep_clear_of_the_next_marker_and_of_each_other() {
        // A row of markers with less room between them than a label needs,
        // and one at the image's right edge.
        let row: Vec<Detection> = (0..4)
            .map(|k| marker(100 + k, 30.0 + 48.0 * f64::from(k), 100.0))
            .collect();
        let outlines: Vec<Bounds> = row.iter().map(outline_bounds).collect();
        let mut taken = outlines.clone();
        for (d, own) in row.iter().zip(&outlines) {
            let (text, cell, _) = label(d).unwrap();
            let place = label_place(own, &text, cell, &taken, (200.0, 200.0));
            assert!(
                taken.iter().all(|t| t.overlap(&place) == 0.0),
                "label of {} at {place:?} covers a marker or a label",
                d.id
            );
            assert!(place.x0 >= 0.0 && place.x1 <= 200.0 && place.y0 >= 0.0);
            taken.push(place);
        }
    }
}
