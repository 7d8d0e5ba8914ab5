//! The marker's outer ellipse: first from the segment's moments (eq. 2-3 of
//! the paper), then refined to sub-pixel accuracy from edge points.
//!
//! The moment ellipse depends on which boundary pixels the threshold let in,
//! so its axes are off by up to half a pixel and its centre is pulled by
//! uneven light. The refinement looks for the 50 % crossing between the
//! local black and the local white along rays through the outer edge (this
//! point does not move with symmetric blur) and fits a conic to those points.

use super::segment::{Gray, Stats};
use crate::math::sample::Border;
use crate::math::Ellipse;

/// Bilinear grey level; None unless the 2×2 neighbourhood is in the image.
#[inline]
pub(crate) fn sample(image: Gray<'_>, x: f64, y: f64) -> Option<f64> {
    image.at(x, y, Border::Interior)
}

/// The coarse outline of a segment: the ellipse of its pixel moments.
pub fn from_moments(stats: &Stats) -> Option<Ellipse> {
    if stats.count < 3 {
        return None;
    }
    let (u, v) = stats.centroid();
    Ellipse::from_moments(u, v, stats.covariance())
}

/// Sub-pixel points on the outer edge of the black disc, found along rays
/// from the centre through the coarse ellipse: the 50 % crossing between
/// the darkest value inside and the brightest outside, nearest to the
/// coarse edge.
/// Returns the number of rays cast.
pub fn edge_points(image: Gray<'_>, coarse: &Ellipse, out: &mut Vec<(f64, f64)>) -> usize {
    out.clear();
    let perimeter = std::f64::consts::PI * (coarse.semi_major + coarse.semi_minor);
    let rays = ((perimeter / 4.0) as usize).clamp(24, 64);
    // Profile from 0.75 to 1.3 of the edge radius, in steps of at most one
    // pixel; the black annulus is at least 0.4 R wide and the white margin
    // 0.3 R, so both levels are seen on every ray.
    let mut profile = [0.0f64; 48];
    for k in 0..rays {
        let t = std::f64::consts::TAU * (k as f64 + 0.5) / rays as f64;
        let (px, py) = coarse.point_at(t);
        let (dx, dy) = (px - coarse.u, py - coarse.v);
        let r = dx.hypot(dy);
        if r < 1.0 {
            continue;
        }
        let (ux, uy) = (dx / r, dy / r);
        let (s0, s1) = (0.75 * r - 1.0, 1.3 * r + 1.5);
        let n = (((s1 - s0) as usize) + 1).clamp(8, profile.len());
        let step = (s1 - s0) / (n - 1) as f64;
        let mut ok = true;
        for (j, slot) in profile[..n].iter_mut().enumerate() {
            let s = s0 + step * j as f64;
            match sample(image, coarse.u + ux * s, coarse.v + uy * s) {
                Some(value) => *slot = value,
                None => {
                    ok = false;
                    break;
                }
            }
        }
        if !ok {
            continue;
        }
        let edge_index = ((r - s0) / step).round() as usize;
        let edge_index = edge_index.min(n - 1);
        let black = profile[..=edge_index]
            .iter()
            .copied()
            .fold(f64::MAX, f64::min);
        let white = profile[edge_index..n]
            .iter()
            .copied()
            .fold(f64::MIN, f64::max);
        if white - black < 8.0 {
            continue;
        }
        let mid = (black + white) / 2.0;
        let mut best: Option<f64> = None;
        for j in 0..n - 1 {
            let (p, q) = (profile[j], profile[j + 1]);
            if p < mid && q >= mid {
                let s = s0 + step * (j as f64 + (mid - p) / (q - p));
                if best.map_or(true, |b| (s - r).abs() < (b - r).abs()) {
                    best = Some(s);
                }
            }
        }
        if let Some(s) = best {
            out.push((coarse.u + ux * s, coarse.v + uy * s));
        }
    }
    rays
}

/// Points where the grey level falls through `mid` going outwards within
/// ±0.07 of `ratio` times the outer ellipse's radius: the edge of a white
/// disc of that relative radius inside the black one. Under perspective the
/// inner circle's image is not concentric with the outer ellipse, which is
/// what tells the two candidate poses apart.
pub fn inner_edge_points(
    image: Gray<'_>,
    outer: &Ellipse,
    ratio: f64,
    mid: f64,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let rays = 48;
    for k in 0..rays {
        let t = std::f64::consts::TAU * (k as f64 + 0.5) / f64::from(rays);
        let (px, py) = outer.point_at(t);
        let (dx, dy) = (px - outer.u, py - outer.v);
        let r = dx.hypot(dy);
        let (s0, s1) = ((ratio - 0.07) * r, (ratio + 0.07) * r);
        let steps = (((s1 - s0) * 2.0) as usize).max(4);
        let at = |s: f64| sample(image, outer.u + dx / r * s, outer.v + dy / r * s);
        let mut previous = at(s0);
        for j in 1..=steps {
            let s = s0 + (s1 - s0) * j as f64 / steps as f64;
            let current = at(s);
            if let (Some(p), Some(q)) = (previous, current) {
                if p >= mid && q < mid {
                    let step = (s1 - s0) / steps as f64;
                    let hit = s - step + step * (p - mid) / (p - q);
                    out.push((outer.u + dx / r * hit, outer.v + dy / r * hit));
                    break;
                }
            }
            previous = current;
        }
    }
}

/// The image at (x, y) interpolated with the quadratic B-spline, which
/// smooths as it interpolates: a sharp edge's steps between pixels, which
/// bilinear samples keep, would move the gradient's centroid with the
/// edge's phase against the grid. `None` unless the 3×3 neighbourhood is
/// in the image.
#[inline]
fn smooth_sample(image: Gray<'_>, x: f64, y: f64) -> Option<f64> {
    if !(x >= 0.5 && y >= 0.5) {
        return None;
    }
    // Rounding by truncation: the coordinates are positive.
    let (i, j) = ((x + 0.5) as usize as f64, (y + 0.5) as usize as f64);
    if !(i + 1.0 < image.width as f64 && j + 1.0 < image.height as f64) {
        return None;
    }
    let weights = |d: f64| {
        [
            0.5 * (0.5 - d) * (0.5 - d),
            0.75 - d * d,
            0.5 * (0.5 + d) * (0.5 + d),
        ]
    };
    let (wx, wy) = (weights(x - i), weights(y - j));
    let (i, j) = (i as usize, j as usize);
    let mut value = 0.0;
    for (row, w) in image.pixels[(j - 1) * image.width..]
        .chunks_exact(image.width)
        .zip(wy)
    {
        let p = &row[i - 1..i + 2];
        value += w * (wx[0] * f64::from(p[0]) + wx[1] * f64::from(p[1]) + wx[2] * f64::from(p[2]));
    }
    Some(value)
}

/// Edge points of a circle of the marker concentric with its outer edge,
/// at `ratio` times the outer radius (1 for the outer edge itself), for the
/// pose: each point is the centroid of the grey-level change across the
/// edge along a ray from the outer ellipse's centre. Unlike a 50 %
/// crossing between interpolated samples, which shifts by up to a tenth of
/// a pixel with the edge's phase against the pixel grid, the centroid of a
/// smoothly interpolated step hardly does, and it does not depend on the
/// levels on either side. Rays where the grey level does not change by at
/// least `min_rise` the expected way (dark inside the outer edge, light
/// inside an inner one) give no point, nor rays whose nominal edge point
/// `wanted` refuses (on a WhyCode ring an inner circle shows only where a
/// sector borders it, and breaks at the sectors' sides).
pub fn concentric_edge_points(
    image: Gray<'_>,
    outer: &Ellipse,
    ratio: f64,
    min_rise: f64,
    wanted: impl Fn((f64, f64)) -> bool,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let perimeter = std::f64::consts::PI * ratio * (outer.semi_major + outer.semi_minor);
    let rays = ((perimeter / 4.0) as usize).clamp(16, 64);
    // Darker outside than inside for the inner circles.
    let sign = if ratio >= 1.0 { 1.0 } else { -1.0 };
    const STEP: f64 = 1.0;
    let mut profile = [0.0f64; 16];
    for k in 0..rays {
        let t = std::f64::consts::TAU * (k as f64 + 0.5) / rays as f64;
        let (px, py) = outer.point_at(t);
        let (dx, dy) = (px - outer.u, py - outer.v);
        let r = dx.hypot(dy);
        // The window stays clear of the neighbouring circles: the ring's
        // borders lie 0.257 R apart.
        let half = (0.2 * r).min(3.0);
        if half < 1.5 || !wanted((outer.u + ratio * dx, outer.v + ratio * dy)) {
            continue;
        }
        let n = ((2.0 * half / STEP) as usize + 1).min(profile.len());
        let s0 = ratio * r - STEP * (n - 1) as f64 / 2.0;
        let (ux, uy) = (dx / r, dy / r);
        let mut inside = true;
        for (j, slot) in profile[..n].iter_mut().enumerate() {
            let s = s0 + STEP * j as f64;
            match smooth_sample(image, outer.u + ux * s, outer.v + uy * s) {
                Some(value) => *slot = sign * value,
                None => {
                    inside = false;
                    break;
                }
            }
        }
        if !inside {
            continue;
        }
        let ends = 2.min(n / 4).max(1);
        let low = profile[..ends].iter().sum::<f64>() / ends as f64;
        let high = profile[n - ends..n].iter().sum::<f64>() / ends as f64;
        if high - low < min_rise {
            continue;
        }
        let (mut weight, mut moment) = (0.0, 0.0);
        for j in 0..n - 1 {
            let rise = profile[j + 1] - profile[j];
            weight += rise;
            moment += rise * (j as f64 + 0.5);
        }
        if weight <= 0.0 {
            continue;
        }
        let s = s0 + STEP * moment / weight;
        out.push((outer.u + ux * s, outer.v + uy * s));
    }
}

/// Edge points of a tracked marker along image rows (and, for the top
/// and bottom caps, columns) through its predicted outline: rows are
/// contiguous in memory, so each point costs one or two cache lines where a
/// slanted ray would touch a new line at every step; and no interpolation
/// is needed. Each edge is the centroid of the grey-level steps across it
/// (levels from the ends of the ±`window` segment, checked against `mid`
/// and `contrast`, the marker's known mid-grey and white-minus-black).
/// Returns the number of segments tried.
pub fn scanline_edge_points(
    image: Gray<'_>,
    guess: &Ellipse,
    mid: f64,
    contrast: f64,
    window: f64,
    out: &mut Vec<(f64, f64)>,
) -> usize {
    out.clear();
    let (s, c) = guess.angle.sin_cos();
    let (ia, ib) = (
        1.0 / (guess.semi_major * guess.semi_major),
        1.0 / (guess.semi_minor * guess.semi_minor),
    );
    // Q(dx, dy) = A dx² + 2 H dx dy + D dy² = 1 on the outline.
    let (qa, qh, qd) = (
        c * c * ia + s * s * ib,
        c * s * (ia - ib),
        s * s * ia + c * c * ib,
    );
    let half_height = (guess.semi_major * guess.semi_major * s * s
        + guess.semi_minor * guess.semi_minor * c * c)
        .sqrt();
    let half_width = (guess.semi_major * guess.semi_major * c * c
        + guess.semi_minor * guess.semi_minor * s * s)
        .sqrt();
    let perimeter = std::f64::consts::PI * (guess.semi_major + guess.semi_minor);
    let lines = ((perimeter / 12.0) as usize).clamp(6, 16);
    let half = window.ceil() as isize;
    let mut tried = 0;
    let mut profile = [0.0f64; 64];
    for vertical in [false, true] {
        let (extent, count) = if vertical {
            (0.55 * half_width, lines / 2 + 1)
        } else {
            (0.75 * half_height, lines)
        };
        for k in 0..count {
            let offset = extent * (2.0 * (k as f64 + 0.5) / count as f64 - 1.0);
            // The scan line: a row (fixed y) or a column (fixed x).
            let (line, centre, a2, h, d) = if vertical {
                let x = (guess.u + offset).round();
                (
                    x,
                    guess.v,
                    qd,
                    qh * (x - guess.u),
                    qa * (x - guess.u).powi(2),
                )
            } else {
                let y = (guess.v + offset).round();
                (
                    y,
                    guess.u,
                    qa,
                    qh * (y - guess.v),
                    qd * (y - guess.v).powi(2),
                )
            };
            // a2 t² + 2 h t + d = 1 → t = (-h ± √(h² - a2 (d - 1))) / a2.
            let disc = h * h - a2 * (d - 1.0);
            if disc <= 0.0 || line < 0.0 {
                continue;
            }
            let root = disc.sqrt();
            for (sign, rising) in [(-1.0, false), (1.0, true)] {
                tried += 1;
                let hit = centre + (-h + sign * root) / a2;
                let first = hit.round() as isize - half;
                let n = (2 * half + 1) as usize;
                if first < 0 || n > profile.len() {
                    continue;
                }
                let (first, line_index) = (first as usize, line as usize);
                let ok = if vertical {
                    if line_index >= image.width || first + n > image.height {
                        false
                    } else {
                        for (j, slot) in profile[..n].iter_mut().enumerate() {
                            *slot = f64::from(image.pixels[(first + j) * image.width + line_index]);
                        }
                        true
                    }
                } else if line_index >= image.height || first + n > image.width {
                    false
                } else {
                    let row = &image.pixels[line_index * image.width + first..][..n];
                    for (slot, &p) in profile[..n].iter_mut().zip(row) {
                        *slot = f64::from(p);
                    }
                    true
                };
                if !ok {
                    continue;
                }
                // Leaving the disc the grey rises; entering it, it falls.
                if !rising {
                    profile[..n].reverse();
                }
                let third = (n / 3).max(1);
                let lo = profile[..third].iter().sum::<f64>() / third as f64;
                let hi = profile[n - third..n].iter().sum::<f64>() / third as f64;
                if lo >= mid || hi < mid || hi - lo < (0.6 * contrast).max(8.0) {
                    continue;
                }
                let level = (lo + hi) / 2.0;
                let expected = half as f64;
                let mut crossing: Option<usize> = None;
                for j in 0..n - 1 {
                    if profile[j] < level && profile[j + 1] >= level {
                        let better = crossing.map_or(true, |b| {
                            (j as f64 - expected).abs() < (b as f64 - expected).abs()
                        });
                        if better {
                            crossing = Some(j);
                        }
                    }
                }
                let Some(cross) = crossing else { continue };
                let (mut weight, mut moment) = (0.0, 0.0);
                for j in cross.saturating_sub(2)..(cross + 3).min(n - 1) {
                    let rise = (profile[j + 1] - profile[j]).max(0.0);
                    weight += rise;
                    moment += rise * (j as f64 + 0.5);
                }
                if weight <= 0.0 {
                    continue;
                }
                let mut position = moment / weight;
                if (position - expected).abs() > window - 1.5 {
                    continue;
                }
                if !rising {
                    position = (n - 1) as f64 - position;
                }
                let along = first as f64 + position;
                out.push(if vertical {
                    (line, along)
                } else {
                    (along, line)
                });
            }
        }
    }
    tried
}

/// A refined outline and how well the edge fits it.
#[derive(Debug, Clone, Copy)]
pub struct Refined {
    /// The fitted outline of the black disc.
    pub ellipse: Ellipse,
    /// RMS distance of the kept edge points from the ellipse, pixels.
    pub rms: f64,
    /// Share of rays that gave an edge point kept in the fit.
    pub support: f64,
}

/// The outer ellipse refined from edge points, with points farther than
/// max(0.5 px, 3 × median) from a first fit dropped before a second fit.
/// None when the edge does not support a consistent ellipse near `coarse`.
pub fn refine(image: Gray<'_>, coarse: &Ellipse, scratch: &mut Vec<(f64, f64)>) -> Option<Refined> {
    let rays = edge_points(image, coarse, scratch);
    let scale = coarse.semi_major.max(1.0);
    let first = Ellipse::fit_near(scratch, (coarse.u, coarse.v), scale)?;
    let mut residuals: Vec<f64> = scratch
        .iter()
        .map(|&(x, y)| first.radial_distance(x, y))
        .collect();
    let mut sorted = residuals.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let limit = (3.0 * median).max(0.5);
    let total = scratch.len();
    let mut keep = residuals.iter_mut().map(|r| *r <= limit);
    scratch.retain(|_| keep.next().unwrap_or(false));
    if scratch.len() * 4 < total * 3 {
        return None;
    }
    let fitted = Ellipse::fit_near(scratch, (coarse.u, coarse.v), scale)?;
    let consistent = (fitted.u - coarse.u).hypot(fitted.v - coarse.v)
        < 0.25 * coarse.semi_minor + 1.0
        && (fitted.semi_major / coarse.semi_major - 1.0).abs() < 0.25
        && (fitted.semi_minor / coarse.semi_minor - 1.0).abs() < 0.25;
    if !consistent {
        return None;
    }
    let sum_sq: f64 = scratch
        .iter()
        .map(|&(x, y)| fitted.radial_distance(x, y).powi(2))
        .sum();
    Some(Refined {
        ellipse: fitted,
        rms: (sum_sq / scratch.len() as f64).sqrt(),
        support: scratch.len() as f64 / rays as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_a_filled_disc_give_its_radius() {
        let mut s = Stats::default();
        let r = 30i64;
        for y in -r..=r {
            let half = ((r * r - y * y) as f64).sqrt().floor() as i64;
            s.add_run(
                (y + 100) as u32,
                (100 - half) as u32,
                (100 + half) as u32,
                0,
            );
        }
        let e = from_moments(&s).unwrap();
        assert!((e.u - 100.0).abs() < 1e-9 && (e.v - 100.0).abs() < 1e-9);
        assert!(
            (e.semi_major - 30.0).abs() < 0.6 && (e.semi_minor - 30.0).abs() < 0.6,
            "{e:?}"
        );
    }
}
