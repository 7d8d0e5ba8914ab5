//! A page to print, as a list of items in millimetres from the page's
//! top-left corner (y down). Every output format (SVG, PDF, PNG, rasters for
//! checking) draws from this one description, and markers in it are drawn from
//! [`Marker::shapes`], so all formats agree.

use crate::geometry::{Marker, Shape};
use std::f64::consts::FRAC_PI_2;

/// Grey level: 0 black, 255 white.
pub type Grey = u8;

/// How a text item is placed horizontally relative to its x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    /// The text starts at x.
    Start,
    /// The text is centred on x.
    Middle,
    /// The text ends at x.
    End,
}

/// One thing on a page.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    /// A marker centred at (cx, cy), unrotated (its +x along the page's +x).
    Marker {
        /// The marker to draw.
        marker: Marker,
        /// Centre, mm from the left edge.
        cx: f64,
        /// Centre, mm from the top edge.
        cy: f64,
    },
    /// A filled axis-aligned rectangle (top-left corner, size).
    Rect {
        /// Left edge, mm.
        x: f64,
        /// Top edge, mm.
        y: f64,
        /// Width, mm.
        width: f64,
        /// Height, mm.
        height: f64,
        /// Fill grey.
        grey: Grey,
    },
    /// A straight stroked line, optionally dashed (dash, gap lengths).
    Line {
        /// Start point, mm.
        from: (f64, f64),
        /// End point, mm.
        to: (f64, f64),
        /// Stroke width, mm.
        width: f64,
        /// Stroke grey.
        grey: Grey,
        /// Dash and gap lengths, mm; solid when `None`.
        dash: Option<[f64; 2]>,
    },
    /// A stroked circle, optionally dashed.
    CircleOutline {
        /// Centre, mm from the left edge.
        cx: f64,
        /// Centre, mm from the top edge.
        cy: f64,
        /// Radius to the middle of the stroke, mm.
        radius: f64,
        /// Stroke width, mm.
        width: f64,
        /// Stroke grey.
        grey: Grey,
        /// Dash and gap lengths, mm; solid when `None`.
        dash: Option<[f64; 2]>,
    },
    /// One line of text; y is the baseline, size the font size in points.
    Text {
        /// Anchor point, mm from the left edge.
        x: f64,
        /// Baseline, mm from the top edge.
        y: f64,
        /// Font size, points.
        size_pt: f64,
        /// Which end of the text sits at x.
        anchor: Anchor,
        /// Text grey.
        grey: Grey,
        /// The text, one line.
        text: String,
    },
}

/// A page of a given size with its items, painted in order on white.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    /// Page width, mm.
    pub width_mm: f64,
    /// Page height, mm.
    pub height_mm: f64,
    /// What is on the page, painted in this order.
    pub items: Vec<Item>,
}

impl Page {
    /// An empty page of the given size.
    pub fn new(width_mm: f64, height_mm: f64) -> Page {
        Page {
            width_mm,
            height_mm,
            items: Vec::new(),
        }
    }

    /// Adds an item on top of the ones already there.
    pub fn push(&mut self, item: Item) {
        self.items.push(item);
    }

    /// This page on a larger white sheet, `pad` mm of white added on every
    /// side: how a marker file cut to its margin looks once it lies on paper.
    pub fn on_white(&self, pad: f64) -> Page {
        let mut items = self.items.clone();
        for item in &mut items {
            match item {
                Item::Marker { cx, cy, .. } | Item::CircleOutline { cx, cy, .. } => {
                    *cx += pad;
                    *cy += pad;
                }
                Item::Rect { x, y, .. } | Item::Text { x, y, .. } => {
                    *x += pad;
                    *y += pad;
                }
                Item::Line { from, to, .. } => {
                    for point in [from, to] {
                        point.0 += pad;
                        point.1 += pad;
                    }
                }
            }
        }
        Page {
            width_mm: self.width_mm + 2.0 * pad,
            height_mm: self.height_mm + 2.0 * pad,
            items,
        }
    }

    /// The markers on the page with their centres.
    pub fn markers(&self) -> impl Iterator<Item = (&Marker, f64, f64)> {
        self.items.iter().filter_map(|item| match item {
            Item::Marker { marker, cx, cy } => Some((marker, *cx, *cy)),
            _ => None,
        })
    }
}

/// Millimetres per typographic point.
pub const MM_PER_PT: f64 = 25.4 / 72.0;

/// A path segment in page millimetres (y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Segment {
    /// Starts a new subpath at (x, y).
    MoveTo(f64, f64),
    /// A straight line to (x, y).
    LineTo(f64, f64),
    /// A cubic Bézier: two control points, then the end point.
    CubicTo(f64, f64, f64, f64, f64, f64),
    /// Closes the subpath.
    Close,
}

/// Page point of the marker-frame point at radius `r` and angle `theta`.
fn polar(cx: f64, cy: f64, r: f64, theta: f64) -> (f64, f64) {
    (cx + r * theta.cos(), cy - r * theta.sin())
}

/// Cubic Bezier pieces (each at most 90°) of the arc of radius `r` from
/// marker angle `from` to `to` (either direction), the start point excluded.
pub fn arc_segments(cx: f64, cy: f64, r: f64, from: f64, to: f64, out: &mut Vec<Segment>) {
    let sweep = to - from;
    let pieces = (sweep.abs() / FRAC_PI_2 - 1e-9).ceil().max(1.0) as usize;
    let step = sweep / pieces as f64;
    // Control-arm length of the standard cubic approximation of a circular arc.
    let k = 4.0 / 3.0 * (step / 4.0).tan();
    for i in 0..pieces {
        let a = from + step * i as f64;
        let b = a + step;
        let (ca, sa) = (a.cos(), a.sin());
        let (cb, sb) = (b.cos(), b.sin());
        let p1 = (ca - k * sa, sa + k * ca);
        let p2 = (cb + k * sb, sb - k * cb);
        out.push(Segment::CubicTo(
            cx + r * p1.0,
            cy - r * p1.1,
            cx + r * p2.0,
            cy - r * p2.1,
            cx + r * cb,
            cy - r * sb,
        ));
    }
}

/// A full circle as four Bezier quarter arcs; `positive` traverses it with
/// growing marker angle, the other way otherwise.
pub fn circle_segments(cx: f64, cy: f64, r: f64, positive: bool, out: &mut Vec<Segment>) {
    let (x, y) = polar(cx, cy, r, 0.0);
    out.push(Segment::MoveTo(x, y));
    let end = if positive {
        2.0 * std::f64::consts::PI
    } else {
        -2.0 * std::f64::consts::PI
    };
    arc_segments(cx, cy, r, 0.0, end, out);
    out.push(Segment::Close);
}

/// The closed outline of an annular sector, traversed with growing angle on
/// its outer arc (the same turning sense as a positive circle).
pub fn sector_segments(
    cx: f64,
    cy: f64,
    inner: f64,
    outer: f64,
    start: f64,
    end: f64,
    out: &mut Vec<Segment>,
) {
    let (x, y) = polar(cx, cy, outer, start);
    out.push(Segment::MoveTo(x, y));
    arc_segments(cx, cy, outer, start, end, out);
    let (x, y) = polar(cx, cy, inner, end);
    out.push(Segment::LineTo(x, y));
    arc_segments(cx, cy, inner, end, start, out);
    out.push(Segment::Close);
}

/// The black of a marker as one path to fill with the nonzero winding rule.
///
/// [`Marker::shapes`] lists nested layers painted in order (black disc, white
/// disc, black sectors, ...). Giving black layers winding +1 and white ones -1
/// makes the winding number of every point the sum of the layers above it,
/// which is 1 exactly where the painted result is black. Filling one path
/// instead of painting layers leaves no anti-aliasing seams where a black
/// sector meets the black disc across the white disc's edge.
pub fn marker_black_path(marker: &Marker, cx: f64, cy: f64) -> Vec<Segment> {
    let mut out = Vec::new();
    for shape in marker.shapes() {
        match shape {
            Shape::Disc { radius, black } => circle_segments(cx, cy, radius, black, &mut out),
            Shape::Sector {
                inner,
                outer,
                start,
                end,
                black,
            } => {
                if black {
                    sector_segments(cx, cy, inner, outer, start, end, &mut out);
                } else {
                    sector_segments(cx, cy, inner, outer, end, start, &mut out);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bezier_quarter_arcs_stay_on_the_circle() {
        let mut segs = Vec::new();
        circle_segments(10.0, 20.0, 5.0, true, &mut segs);
        assert_eq!(segs.len(), 6);
        let mut last = (15.0, 20.0);
        for seg in &segs {
            if let Segment::CubicTo(x1, y1, x2, y2, x, y) = *seg {
                for t in [0.25, 0.5, 0.75] {
                    let u = 1.0 - t;
                    let px = u * u * u * last.0
                        + 3.0 * u * u * t * x1
                        + 3.0 * u * t * t * x2
                        + t * t * t * x;
                    let py = u * u * u * last.1
                        + 3.0 * u * u * t * y1
                        + 3.0 * u * t * t * y2
                        + t * t * t * y;
                    let r = ((px - 10.0).powi(2) + (py - 20.0).powi(2)).sqrt();
                    assert!((r - 5.0).abs() < 5.0 * 3e-4, "r = {r}");
                }
                last = (x, y);
            }
        }
        // Growing marker angle goes up the page first (y down).
        if let Segment::CubicTo(_, _, _, _, x, y) = segs[1] {
            assert!((x - 10.0).abs() < 1e-9 && (y - 15.0).abs() < 1e-9);
        }
    }
}
