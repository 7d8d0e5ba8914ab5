//! The page of a single marker: the marker, its white margin, and optional
//! centre cross, cut guide and label.

use super::font::{helvetica_width_mm, CAP_HEIGHT};
use super::page::{Anchor, Item, Page, MM_PER_PT};
use super::RenderError;
use crate::geometry::{Marker, MarkerKind};
use crate::units::trim_float;

/// Label font size when none is asked for, in points.
pub const DEFAULT_LABEL_PT: f64 = 7.0;
/// Smallest label font size we shrink a label to before giving up on fitting.
pub const MIN_LABEL_PT: f64 = 3.0;
/// White kept between a cut guide and the page edge, in mm.
const CUT_GUIDE_PAD_MM: f64 = 1.5;
/// How far outside the white margin a cut guide runs, in mm: scissors that
/// stray a little inside the line must still leave the detector its margin.
pub const CUT_CLEARANCE_MM: f64 = 1.0;
/// Space between the white margin and the label's cap line, in mm.
pub const LABEL_GAP_MM: f64 = 1.0;
/// Light grey for guides: visible on paper, brighter than any detector threshold.
pub const GUIDE_GREY: u8 = 150;
/// Line width of cut guides and crosses, in mm.
pub const GUIDE_WIDTH_MM: f64 = 0.15;

#[derive(Debug, Clone, PartialEq)]
/// How a single marker is put on its own page.
pub struct MarkerOptions {
    /// White margin around the black disc; None means the least allowed (0.3 R).
    pub margin_mm: Option<f64>,
    /// Thin grey cross in the white centre, for aligning the marker.
    pub cross: bool,
    /// Thin dashed circle just outside the white margin, to cut along.
    pub cut_guide: bool,
    /// A label line under the marker.
    pub label: Option<String>,
    /// Size of the label, points.
    pub label_size_pt: f64,
}

impl Default for MarkerOptions {
    fn default() -> Self {
        MarkerOptions {
            margin_mm: None,
            cross: false,
            cut_guide: false,
            label: None,
            label_size_pt: DEFAULT_LABEL_PT,
        }
    }
}

/// The text identifying a marker: "ID 5 · 8b d2 · 50 mm", or for a legacy
/// circle "WhyCon · 122 mm".
pub fn marker_label(marker: &Marker, id: Option<u32>, distance: Option<u32>) -> String {
    let size = format!("{} mm", trim_float(round_to(marker.diameter_mm, 0.1)));
    match marker.kind {
        MarkerKind::WhyCon => format!("WhyCon · {size}"),
        MarkerKind::WhyCode { bits, .. } => {
            let family = match distance {
                Some(d) => format!("{bits}b d{d}"),
                None => format!("{bits}b"),
            };
            match id {
                Some(id) => format!("ID {id} · {family} · {size}"),
                None => format!("{family} · {size}"),
            }
        }
    }
}

fn round_to(v: f64, step: f64) -> f64 {
    (v / step).round() * step
}

/// Checks a requested white margin against the least the detector needs.
pub fn checked_margin(marker: &Marker, margin_mm: Option<f64>) -> Result<f64, RenderError> {
    let least = marker.min_margin();
    match margin_mm {
        None => Ok(least),
        Some(m) if m + 1e-9 >= least && m.is_finite() => Ok(m),
        Some(m) => Err(RenderError::MarginTooSmall {
            margin_mm: m,
            diameter_mm: marker.diameter_mm,
            least_mm: least,
        }),
    }
}

/// A thin centre cross, kept inside the white centre disc so that it does
/// not touch the code ring, and drawn in light grey so that the detector's
/// white segment stays whole.
pub fn centre_cross(marker: &Marker, cx: f64, cy: f64) -> [Item; 2] {
    let arm = marker.outer_radius() * 0.22;
    let line = |from, to| Item::Line {
        from,
        to,
        width: GUIDE_WIDTH_MM,
        grey: GUIDE_GREY,
        dash: None,
    };
    [
        line((cx - arm, cy), (cx + arm, cy)),
        line((cx, cy - arm), (cx, cy + arm)),
    ]
}

/// A dashed cut circle of `radius` around a marker.
pub fn cut_circle(cx: f64, cy: f64, radius: f64) -> Item {
    Item::CircleOutline {
        cx,
        cy,
        radius,
        width: GUIDE_WIDTH_MM,
        grey: GUIDE_GREY,
        dash: Some([1.0, 1.0]),
    }
}

/// The label font size that fits `text` into `width` mm, from `wanted` down
/// to [`MIN_LABEL_PT`].
pub fn fitting_size(text: &str, wanted_pt: f64, width: f64) -> f64 {
    let natural = helvetica_width_mm(text, wanted_pt);
    if natural <= width {
        wanted_pt
    } else {
        (wanted_pt * width / natural).max(MIN_LABEL_PT)
    }
}

/// Lays out a single marker on a page exactly as large as it needs: the
/// black disc, its white margin, and room for the cut guide and label.
pub fn marker_page(marker: &Marker, options: &MarkerOptions) -> Result<Page, RenderError> {
    if !(marker.diameter_mm.is_finite() && marker.diameter_mm > 0.0) {
        return Err(RenderError::DiameterNotPositive {
            diameter_mm: marker.diameter_mm,
        });
    }
    let margin = checked_margin(marker, options.margin_mm)?;
    let pad = if options.cut_guide {
        CUT_CLEARANCE_MM + CUT_GUIDE_PAD_MM
    } else {
        0.0
    };
    let side = marker.diameter_mm + 2.0 * (margin + pad);
    let label = options.label.as_deref().filter(|t| !t.is_empty());
    let size_pt = label.map_or(0.0, |t| {
        fitting_size(t, options.label_size_pt, side - 2.0 * LABEL_GAP_MM)
    });
    let size_mm = size_pt * MM_PER_PT;
    let label_height = if label.is_some() {
        LABEL_GAP_MM + size_mm * (CAP_HEIGHT + 0.25) + LABEL_GAP_MM
    } else {
        0.0
    };
    let mut page = Page::new(side, side + label_height);
    let c = side / 2.0;
    page.push(Item::Marker {
        marker: *marker,
        cx: c,
        cy: c,
    });
    if options.cross {
        page.items.extend(centre_cross(marker, c, c));
    }
    if options.cut_guide {
        page.push(cut_circle(
            c,
            c,
            marker.outer_radius() + margin + CUT_CLEARANCE_MM,
        ));
    }
    if let Some(text) = label {
        page.push(Item::Text {
            x: c,
            y: side + LABEL_GAP_MM + size_mm * CAP_HEIGHT,
            size_pt,
            anchor: Anchor::Middle,
            grey: 0,
            text: text.to_string(),
        });
    }
    Ok(page)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_name_id_family_and_size() {
        let m = Marker::whycode(8, 11, 40.0);
        assert_eq!(marker_label(&m, Some(3), Some(2)), "ID 3 · 8b d2 · 40 mm");
        assert_eq!(
            marker_label(&Marker::whycon(122.0), None, None),
            "WhyCon · 122 mm"
        );
    }

    #[test]
    fn page_is_marker_plus_margin() {
        let m = Marker::whycode(8, 11, 50.0);
        let page = marker_page(&m, &MarkerOptions::default()).unwrap();
        assert!((page.width_mm - 65.0).abs() < 1e-9);
        assert!((page.height_mm - 65.0).abs() < 1e-9);
        assert!(marker_page(
            &m,
            &MarkerOptions {
                margin_mm: Some(5.0),
                ..MarkerOptions::default()
            }
        )
        .is_err());
    }
}
