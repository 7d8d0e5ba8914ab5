//! The one structure a legacy WhyCon marker has to show: a white disc of
//! 0.41 R, concentric with the black one (spec section 1). The moment tests
//! accept a disc with an off-centre hole or a washer whose hole is some
//! other size (their pixel counts fit within the tolerances blur and
//! perspective need); the inner edge, found along rays from the centre,
//! does not: it must lie at the same relative radius all round, and at
//! WhyCon's.

use super::ellipse;
use super::segment::Gray;
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO, WHYCON_WHITE_RATIO};
use crate::math::Ellipse;

/// Rays cast from the centre.
const RAYS: usize = 32;

/// Largest deviation of the median inner edge radius from 0.41 R, in R,
/// plus this many pixels (blur moves a small disc's edge inwards).
const RATIO_TOLERANCE: f64 = 0.06;
const RATIO_TOLERANCE_PX: f64 = 0.5;

/// Largest spread of the inner edge radius between rays (in R, plus a
/// pixel's worth): an off-centre hole varies by twice its offset.
const SPREAD_TOLERANCE: f64 = 0.04;

/// True when the disc stands on white: WhyCon markers are printed with at
/// least 0.3 R of white margin (spec section 1), while a letter 'o' or a
/// ring drawn on a busy surface touches other ink. Rays that leave the
/// image say nothing.
pub fn white_margin(gray: Gray<'_>, outer: &Ellipse, black: f64, white: f64) -> bool {
    let mid = 0.5 * (black + white);
    // Just outside the edge's blur, and inside the 0.3 R margin.
    let rho = 1.0 + (0.15f64).max(1.5 / outer.semi_minor.max(1.0)).min(0.28);
    let (mut seen, mut light) = (0, 0);
    for k in 0..RAYS {
        let t = std::f64::consts::TAU * k as f64 / RAYS as f64;
        let (x, y) = outer.scaled(rho).point_at(t);
        if let Some(value) = ellipse::sample(gray, x, y) {
            seen += 1;
            light += usize::from(value >= mid);
        }
    }
    seen == 0 || light * 8 >= seen * 7
}

/// True when the white inside the candidate is a disc of WhyCon's size
/// centred on the black one.
pub fn concentric_white_disc(gray: Gray<'_>, outer: &Ellipse, black: f64, white: f64) -> bool {
    let mid = 0.5 * (black + white);
    let radius_px = outer.semi_minor.max(1.0);
    let step = (0.25 / radius_px).min(0.02);
    let mut radii = Vec::with_capacity(RAYS);
    for k in 0..RAYS {
        let t = std::f64::consts::TAU * k as f64 / RAYS as f64;
        let at = |rho: f64| {
            let (x, y) = outer.scaled(rho).point_at(t);
            ellipse::sample(gray, x, y)
        };
        // From inside the white disc outwards to the first dark sample.
        let mut rho = 0.15;
        let Some(mut previous) = at(rho) else {
            return false;
        };
        let mut crossing = None;
        while rho < 0.85 {
            let next_rho = rho + step;
            let Some(next) = at(next_rho) else {
                return false;
            };
            if previous >= mid && next < mid {
                crossing = Some(rho + step * (previous - mid) / (previous - next));
                break;
            }
            previous = next;
            rho = next_rho;
        }
        if let Some(r) = crossing {
            radii.push(r);
        }
    }
    if radii.len() * 8 < RAYS * 7 {
        return false;
    }
    let pixel = 1.0 / radius_px;
    let ratio_ok = |median: f64, expected: f64| {
        (median - expected).abs() <= RATIO_TOLERANCE + RATIO_TOLERANCE_PX * pixel
    };
    // A WhyCode marker is a WhyCon one too (paper section 5): its first
    // edge is the centre disc's (0.343 R) on rays through black sectors and
    // the ring's outside (0.6 R) on the others.
    let split = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
    let (inner, outer_edges): (Vec<f64>, Vec<f64>) =
        radii.iter().copied().partition(|&r| r < split);
    let whycode = inner.len() * 4 >= RAYS
        && outer_edges.len() * 4 >= RAYS
        && tight(inner, pixel).is_some_and(|m| ratio_ok(m, RING_INNER_RATIO))
        && tight(outer_edges, pixel).is_some_and(|m| ratio_ok(m, WHYCODE_WHITE_RATIO));
    whycode || tight(radii, pixel).is_some_and(|m| ratio_ok(m, WHYCON_WHITE_RATIO))
}

/// The median of edge radii that agree (trimmed spread within tolerance).
fn tight(mut radii: Vec<f64>, pixel: f64) -> Option<f64> {
    radii.sort_by(f64::total_cmp);
    // Middle 80 %: one glint or scratch may move a few rays.
    let trim = radii.len() / 10;
    let spread = radii[radii.len() - 1 - trim] - radii[trim];
    (spread <= 2.0 * SPREAD_TOLERANCE + 2.0 * pixel).then(|| radii[radii.len() / 2])
}
