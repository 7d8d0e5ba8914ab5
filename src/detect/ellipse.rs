//! The marker's outer ellipse: first from the segment's moments (eq. 2-3 of
//! the paper), then refined to sub-pixel accuracy from edge points.
//!
//! The moment ellipse depends on which boundary pixels the threshold let in,
//! so its axes are off by up to half a pixel and its centre is pulled by
//! uneven light. The refinement looks for the 50 % crossing between the
//! local black and the local white along rays through the outer edge (this
//! point does not move with symmetric blur) and fits a conic to those points.

use super::segment::{Gray, Stats};
use crate::math::sample::{floor_inside, Border};
use crate::math::Ellipse;

/// Bilinear grey level; None unless the 2×2 neighbourhood is in the image.
#[inline]
pub(crate) fn sample(image: Gray<'_>, x: f64, y: f64) -> Option<f64> {
    image.at(x, y, Border::Interior)
}

/// Pixels of the margin beyond the coarse outline that a ray must show to
/// place the edge on it: the edge's blur and a pixel of the paper.
const MIN_MARGIN_SEEN_PX: f64 = 3.0;

/// How far the rays' samples keep from the image's first and last pixel
/// centres. The sampler refuses a point even a rounding error outside;
/// a ray cut exactly at the edge would end there, and whether its last
/// sample falls inside would depend on the last bit of the platform's
/// square roots and sines, so the same photo would give other outlines
/// in the browser than on the command line.
const EDGE_SLACK_PX: f64 = 1.0 / 64.0;

/// How far from `origin` along the unit direction `dir` the bilinear
/// sampler can read before it leaves the image (less the slack).
fn room(origin: (f64, f64), dir: (f64, f64), image: Gray<'_>) -> f64 {
    let limit = |p: f64, d: f64, size: usize| {
        let (first, last) = (EDGE_SLACK_PX, size as f64 - 1.0 - EDGE_SLACK_PX);
        if d > 1e-12 {
            (last - p) / d
        } else if d < -1e-12 {
            (first - p) / d
        } else {
            f64::INFINITY
        }
    };
    limit(origin.0, dir.0, image.width)
        .min(limit(origin.1, dir.1, image.height))
        .max(0.0)
}

/// The coarse outline of a segment: the ellipse of its pixel moments.
pub fn from_moments(stats: &Stats) -> Option<Ellipse> {
    if stats.count < 3 {
        return None;
    }
    let (u, v) = stats.centroid();
    Ellipse::from_moments(u, v, stats.covariance())
}

/// Where [`edge_points`]' rays end: this share of the outline's radius
/// along each, and these pixels further.
const RAYS_END: f64 = 1.3;
const RAYS_END_PX: f64 = 1.5;

/// How far from the coarse outline's centre [`edge_points`] reads pixels
/// (its rays' furthest samples, and their neighbours).
pub(crate) fn edge_points_reach(coarse: &Ellipse) -> f64 {
    RAYS_END * coarse.semi_major + RAYS_END_PX + 1.0
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
        // A disc near the image's border leaves some rays less of the
        // margin than the profile would take: what lies inside the frame is
        // read, as long as it shows a few pixels of the margin's light.
        let s0 = 0.75 * r - 1.0;
        let whole = RAYS_END * r + RAYS_END_PX;
        let s1 = whole.min(room((coarse.u, coarse.v), (ux, uy), image));
        if s1 < whole && s1 < r + MIN_MARGIN_SEEN_PX {
            continue;
        }
        let n = (((s1 - s0) as usize) + 1).clamp(8, profile.len());
        let step = (s1 - s0) / (n - 1) as f64;
        let (origin, dir) = ((coarse.u, coarse.v), (ux, uy));
        if !image.line(origin, dir, (s0, step), &mut profile[..n]) {
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
                if best.is_none_or(|b| (s - r).abs() < (b - r).abs()) {
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
    spokes: &mut Spokes,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    for &(dx, dy, r) in spokes.around(outer, 48) {
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
#[inline(always)]
fn smooth_sample(image: Gray<'_>, x: f64, y: f64) -> Option<f64> {
    // The nearest pixel, which must have a neighbour on either side.
    let (i, j) = floor_inside(x + 0.5, y + 0.5, image.width, image.height)?;
    if i == 0 || j == 0 {
        return None;
    }
    let weights = |d: f64| {
        [
            0.5 * (0.5 - d) * (0.5 - d),
            0.75 - d * d,
            0.5 * (0.5 + d) * (0.5 + d),
        ]
    };
    let as_f32 = |w: [f64; 3]| w.map(|w| w as f32);
    let (wx, wy) = (as_f32(weights(x - i as f64)), as_f32(weights(y - j as f64)));
    let (i, j, width) = (i as usize, j as usize, image.width);
    let start = (j - 1) * width + i - 1;
    Some(f64::from(blend_3x3(&image.pixels[start..], width, wx, wy)))
}

/// Σₖ wy[k] Σₗ wx[l] p[k·width + l] over a 3×3 neighbourhood whose top left
/// pixel is `p[0]`, in f32 and in one order on every target (each column
/// blended down its three rows, then the columns weighted and added as
/// (c₀ + c₂) + c₁), so that the vector path and the portable one agree to
/// the bit. f32 carries a grey level to 1e-5, far below what an edge
/// centroid can tell.
#[inline(always)]
fn blend_3x3(p: &[u8], width: usize, wx: [f32; 3], wy: [f32; 3]) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if let Some(rows) = p.get(..2 * width + 4) {
        // Four bytes a row, the fourth weighted zero (the slice's bounds
        // were checked for all twelve).
        let row = |k: usize| {
            let q = &rows[k * width..k * width + 4];
            i32::from_le_bytes([q[0], q[1], q[2], q[3]])
        };
        let (r0, r1, r2) = (row(0), row(1), row(2));
        // SAFETY: SSE2 is part of x86_64; the operations touch registers
        // only.
        unsafe {
            use std::arch::x86_64::*;
            let zero = _mm_setzero_si128();
            let lanes = |r: i32| {
                let bytes = _mm_cvtsi32_si128(r);
                _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero))
            };
            let column = _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(lanes(r0), _mm_set1_ps(wy[0])),
                    _mm_mul_ps(lanes(r1), _mm_set1_ps(wy[1])),
                ),
                _mm_mul_ps(lanes(r2), _mm_set1_ps(wy[2])),
            );
            let t = _mm_mul_ps(column, _mm_setr_ps(wx[0], wx[1], wx[2], 0.0));
            // (t₀ + t₂, t₁ + t₃) then their sum; t₃ is zero.
            let pairs = _mm_add_ps(t, _mm_movehl_ps(t, t));
            let total = _mm_add_ss(pairs, _mm_shuffle_ps::<1>(pairs, pairs));
            return _mm_cvtss_f32(total);
        }
    }
    let q = &p[..2 * width + 3];
    let column = |l: usize| {
        f32::from(q[l]) * wy[0]
            + f32::from(q[width + l]) * wy[1]
            + f32::from(q[2 * width + l]) * wy[2]
    };
    (column(0) * wx[0] + column(2) * wx[2]) + column(1) * wx[1]
}

/// Each ray as the offset to its outline point and its length.
type Rays = Vec<(f64, f64, f64)>;

/// The rays [`concentric_edge_points`] follows from an outline's centre to
/// `count` points spread evenly (by the ellipse's parameter) over it, each
/// as the offset to that point and its length: the same for every circle of
/// the marker, so worked out once per outline and count.
#[derive(Debug, Clone, Default)]
pub struct Spokes {
    /// The two latest outlines and counts with their rays: a marker's
    /// circles take one or two counts (a small marker's inner circle is
    /// given fewer rays), asked for in turn.
    sets: [(Option<(Ellipse, usize)>, Rays); 2],
    /// The set to replace next.
    older: usize,
}

impl Spokes {
    fn around(&mut self, outline: &Ellipse, count: usize) -> &[(f64, f64, f64)] {
        let key = Some((*outline, count));
        let slot = match self.sets.iter().position(|(k, _)| *k == key) {
            Some(slot) => slot,
            None => {
                let slot = self.older;
                self.older = 1 - slot;
                let (k, rays) = &mut self.sets[slot];
                *k = key;
                rays.clear();
                let (sin, cos) = outline.angle.sin_cos();
                // The parameter walks by a fixed rotation, from half a step.
                let step = std::f64::consts::TAU / count as f64;
                let (step_sin, step_cos) = step.sin_cos();
                let (mut sin_t, mut cos_t) = (0.5 * step).sin_cos();
                for _ in 0..count {
                    let (a, b) = (outline.semi_major * cos_t, outline.semi_minor * sin_t);
                    let (dx, dy) = (a * cos - b * sin, a * sin + b * cos);
                    rays.push((dx, dy, (dx * dx + dy * dy).sqrt()));
                    (sin_t, cos_t) = (
                        sin_t * step_cos + cos_t * step_sin,
                        cos_t * step_cos - sin_t * step_sin,
                    );
                }
                slot
            }
        };
        &self.sets[slot].1
    }
}

/// How many rays [`concentric_edge_points`] reads a circle along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeRays {
    /// Rays per pixel of the circle's perimeter.
    per_px: f64,
    /// At most this many a circle.
    most: usize,
}

impl EdgeRays {
    /// A ray every two pixels, at most 48 a circle: 144 points over the
    /// three circles give the normal the accuracy of the detector bar's
    /// rows 2/2a (docs/benchmarks.md); more rays cost time on every posed
    /// marker for no gain measured there.
    pub const POSE: EdgeRays = EdgeRays {
        per_px: 0.5,
        most: 48,
    };
    /// A ray every pixel, at most 400 a circle, for measuring (camera
    /// calibration). Each ray's edge point is off by a few hundredths of a
    /// pixel depending on where the ray crosses the pixel grid (the
    /// sampler's smoothing is not quite the same at every phase); 48 rays
    /// leave those errors to add up to a few thousandths of a pixel in the
    /// projected centre, rays at every pixel average them out (measured by
    /// `examples/calibration_centres`: docs/calibration.md, "What the
    /// centres were limited by"). Halving the spacing again gains nothing.
    pub const FINE: EdgeRays = EdgeRays {
        per_px: 1.0,
        most: 400,
    };

    fn along(self, perimeter: f64) -> usize {
        ((perimeter * self.per_px) as usize).clamp(16, self.most)
    }
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
#[allow(clippy::too_many_arguments)]
pub fn concentric_edge_points(
    image: Gray<'_>,
    outer: &Ellipse,
    ratio: f64,
    min_rise: f64,
    density: EdgeRays,
    wanted: impl Fn((f64, f64)) -> bool,
    spokes: &mut Spokes,
    out: &mut Vec<(f64, f64)>,
) {
    out.clear();
    let perimeter = std::f64::consts::PI * ratio * (outer.semi_major + outer.semi_minor);
    let rays = density.along(perimeter);
    // Darker outside than inside for the inner circles.
    let sign = if ratio >= 1.0 { 1.0 } else { -1.0 };
    const STEP: f64 = 1.0;
    let mut profile = [0.0f64; 16];
    for &(dx, dy, r) in spokes.around(outer, rays) {
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
                        let better = crossing.is_none_or(|b| {
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
    /// The motion blur the outline showed, when the fit had to leave out
    /// the stretches of edge smeared along it.
    pub blur: Option<LinearBlur>,
}

/// Least motion blur (pixels, as [`linear_blur`] measures it) that may
/// explain an outline whose edge points scatter along one direction.
pub const MIN_MOTION_BLUR_PX: f64 = 4.0;

/// The outer ellipse refined from edge points, with points farther than
/// max(0.5 px, 3 × median) from a first fit dropped before a second fit.
/// Where a motion blur smears the edge across more than the black annulus
/// the 50 % crossing moves (the ramp no longer reaches black): when too
/// many points are off and the outline shows a linear blur, only the
/// stretches the blur leaves sharp enough are fitted.
/// None when the edge does not support a consistent ellipse near `coarse`.
pub fn refine(image: Gray<'_>, coarse: &Ellipse, scratch: &mut Vec<(f64, f64)>) -> Option<Refined> {
    let rays = edge_points(image, coarse, scratch);
    let scale = coarse.semi_major.max(1.0);
    let first = Ellipse::fit_near(scratch, (coarse.u, coarse.v), scale)?;
    let residuals: Vec<f64> = first.radial_distances(scratch).collect();
    let mut sorted = residuals.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let limit = (3.0 * median).max(0.5);
    let total = scratch.len();
    let kept = residuals.iter().filter(|&&r| r <= limit).count();
    let mut blur = None;
    if kept * 4 < total * 3 {
        let b = linear_blur(image, &first).filter(|b| b.length >= MIN_MOTION_BLUR_PX)?;
        // Keep the points where the ramp (L·|cos φ|, as measured: about
        // 0.85 of the true one) about fits inside the black annulus (0.4 R).
        let (sb, cb) = b.angle.sin_cos();
        let (s, c) = first.angle.sin_cos();
        let (a2, b2) = (first.semi_major.powi(2), first.semi_minor.powi(2));
        let reach = 0.45 * first.semi_minor;
        scratch.retain(|&(x, y)| {
            let (dx, dy) = (x - first.u, y - first.v);
            let (p, q) = (dx * c + dy * s, -dx * s + dy * c);
            let (nl, nm) = (p / a2, q / b2);
            let (nx, ny) = (nl * c - nm * s, nl * s + nm * c);
            let spread = b.length * (nx * cb + ny * sb).abs() / nx.hypot(ny);
            spread <= reach
        });
        if scratch.len() * 20 < total * 9 || scratch.len() < 12 {
            return None;
        }
        blur = Some(b);
    } else {
        let mut keep = residuals.iter().map(|&r| r <= limit);
        scratch.retain(|_| keep.next().unwrap_or(false));
    }
    let fitted = Ellipse::fit_near(scratch, (coarse.u, coarse.v), scale)?;
    let consistent = (fitted.u - coarse.u).hypot(fitted.v - coarse.v)
        < 0.25 * coarse.semi_minor + 1.0
        && (fitted.semi_major / coarse.semi_major - 1.0).abs() < 0.25
        && (fitted.semi_minor / coarse.semi_minor - 1.0).abs() < 0.25;
    if !consistent {
        return None;
    }
    let sum_sq: f64 = fitted.radial_distances(scratch).map(|d| d.powi(2)).sum();
    Some(Refined {
        ellipse: fitted,
        rms: (sum_sq / scratch.len() as f64).sqrt(),
        support: scratch.len() as f64 / rays as f64,
        blur,
    })
}

/// A straight-line motion blur: the image averaged along a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearBlur {
    /// Length of the segment, pixels.
    pub length: f64,
    /// Its direction, radians in [0, π).
    pub angle: f64,
    /// Width (pixels) of the outline's edge ramp across the blur: focus
    /// blur and the pixels' own size.
    pub base_width: f64,
}

/// Rays cast across the outline to measure its edge spread.
const BLUR_RAYS: usize = 48;

/// The motion blur the outline's edge profile shows, if any. A blur of
/// length L in direction θ spreads an edge whose normal makes the angle φ
/// with θ over a ramp of L·|cos φ| (plus the focus blur), whatever lies
/// beside the edge, and the ramp's steepest slope is the black-white
/// contrast over that width: so the inverse slope across the outline,
/// fitted as a + b·|cos(φ - θ)|, gives θ, and b times the contrast (read
/// where the edge is sharpest) gives L. `None` when the outline shows no
/// anisotropic spread (a sharp or evenly blurred edge) or cannot be read.
pub fn linear_blur(image: Gray<'_>, outer: &Ellipse) -> Option<LinearBlur> {
    let rays = edge_spread(image, outer)?;
    // Least squares of inverse slope = a + b·|cos(φ - θ)| on a grid of θ.
    let mut best: Option<(f64, f64, f64, f64)> = None;
    for step in 0..90 {
        let theta = std::f64::consts::PI * f64::from(step) / 90.0;
        let (mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &(phi, inv, _) in &rays {
            let x = (phi - theta).cos().abs();
            sx += x;
            sy += inv;
            sxx += x * x;
            sxy += x * inv;
            syy += inv * inv;
        }
        let n = rays.len() as f64;
        let det = n * sxx - sx * sx;
        if det <= 1e-12 {
            continue;
        }
        let slope = (n * sxy - sx * sy) / det;
        let offset = (sy - slope * sx) / n;
        let residual = syy - offset * sy - slope * sxy;
        if best.is_none_or(|b| residual < b.0) {
            best = Some((residual, theta, offset, slope));
        }
    }
    let (_, theta, offset, slope) = best?;
    // The contrast where the edge is sharpest (across the blur), where
    // the ramp reaches both the black annulus and the white margin.
    let mut across: Vec<f64> = rays
        .iter()
        .filter(|r| (r.0 - theta).cos().abs() < 0.5)
        .map(|r| r.2)
        .collect();
    if across.len() < 4 || slope <= 0.0 {
        return None;
    }
    across.sort_by(f64::total_cmp);
    let contrast = across[across.len() / 2];
    Some(LinearBlur {
        length: slope * contrast,
        angle: theta,
        base_width: (offset * contrast).max(0.0),
    })
}

/// The outline's edge spread along [`BLUR_RAYS`] rays across it: per ray
/// that reads both levels, the outward normal's angle, the inverse of the
/// steepest slope (over two pixels) and the black-white contrast. `None`
/// when too few rays read (a ring under 8 px across the minor axis, cut
/// by the border, or without contrast).
fn edge_spread(image: Gray<'_>, outer: &Ellipse) -> Option<Vec<(f64, f64, f64)>> {
    let (s, c) = outer.angle.sin_cos();
    let (a, b) = (outer.semi_major, outer.semi_minor);
    if !(a.is_finite() && b > 4.0) {
        return None;
    }
    // Along the normal, from inside the black annulus (0.4 R wide) to the
    // white margin (0.3 R wide).
    let (inside, outside) = (0.35 * b, 0.3 * b);
    let step = 0.5;
    let samples = ((inside + outside) / step) as usize + 1;
    let mut profile = vec![0.0f64; samples];
    // (normal angle, inverse steepest slope, contrast) per ray.
    let mut rays: Vec<(f64, f64, f64)> = Vec::with_capacity(BLUR_RAYS);
    for k in 0..BLUR_RAYS {
        let t = std::f64::consts::TAU * (k as f64 + 0.5) / BLUR_RAYS as f64;
        let (px, py) = outer.point_at(t);
        // Outward normal: gradient of the implicit form, rotated to the image.
        let (nl, nm) = (t.cos() / a, t.sin() / b);
        let (nx, ny) = (nl * c - nm * s, nl * s + nm * c);
        let norm = nx.hypot(ny);
        let (nx, ny) = (nx / norm, ny / norm);
        if !image.line((px, py), (nx, ny), (-inside, step), &mut profile) {
            continue;
        }
        // Slope over two pixels (four steps), against noise.
        let slope = (4..samples)
            .map(|j| (profile[j] - profile[j - 4]) / (4.0 * step))
            .fold(f64::MIN, f64::max);
        let low = profile.iter().copied().fold(f64::MAX, f64::min);
        let high = profile.iter().copied().fold(f64::MIN, f64::max);
        if slope <= 0.0 || high - low < 8.0 {
            continue;
        }
        rays.push((ny.atan2(nx), 1.0 / slope, high - low));
    }
    (rays.len() >= BLUR_RAYS * 3 / 4).then_some(rays)
}

/// Variance (px²) the outline's edge profile shows on top of the focus
/// blur: the pixel's own area (1/12) and the bilinear sampler's (1/6).
const SAMPLED_EDGE_VARIANCE: f64 = 0.25;

/// The isotropic (defocus) blur the outline's edge profile shows: the
/// sigma, pixels, of a Gaussian focus blur on top of the pixels' own area.
/// A Gaussian of sigma s spreads an edge of contrast C so that its slope
/// over two pixels peaks at C·erf(1/(s√2))/2; the median over the rays of
/// the contrast over that slope gives s. `None` when the edge cannot be
/// read (see `edge_spread`).
pub fn defocus(image: Gray<'_>, outer: &Ellipse) -> Option<f64> {
    let rays = edge_spread(image, outer)?;
    let mut widths: Vec<f64> = rays
        .iter()
        .map(|&(_, inverse, contrast)| inverse * contrast)
        .collect();
    widths.sort_by(f64::total_cmp);
    let width = widths[widths.len() / 2];
    // width = 2 / erf(1/(s√2)) grows with s from 2 (a sharp step): bisect.
    let width_of = |s: f64| 2.0 / erf(1.0 / (s * std::f64::consts::SQRT_2));
    if width <= width_of(0.05) {
        return Some(0.0);
    }
    let (mut low, mut high) = (0.05f64, 8.0f64);
    for _ in 0..40 {
        let mid = 0.5 * (low + high);
        if width_of(mid) < width {
            low = mid;
        } else {
            high = mid;
        }
    }
    let total = 0.5 * (low + high);
    Some((total * total - SAMPLED_EDGE_VARIANCE).max(0.0).sqrt())
}

/// The error function (Abramowitz and Stegun 7.1.26, error under 1.5e-7).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let y = 1.0 - poly * (-x * x).exp();
    if x < 0.0 {
        -y
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disc cut by the frame's top edge: the rays that meet the edge end
    /// where the frame does, and which of them place an edge point must
    /// not hang on the last bit of the centre (a rounding error of another
    /// platform's square root or sine moves it that much).
    #[test]
    fn rays_cut_by_the_edge_do_not_hang_on_rounding() {
        let (width, height, radius) = (200usize, 120usize, 40.0);
        let (cx, cy) = (100.0, 44.0);
        let pixels: Vec<u8> = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f64, (i / width) as f64);
                let r = (x - cx).hypot(y - cy);
                (40.0 + 160.0 * (r - radius + 0.5).clamp(0.0, 1.0)) as u8
            })
            .collect();
        let image = Gray::new(&pixels, width, height);
        let mut counts = std::collections::BTreeSet::new();
        let mut points = Vec::new();
        for k in 0..400 {
            let nudge = f64::from(k) * 1e-12;
            let coarse = Ellipse {
                u: cx + nudge,
                v: cy - nudge,
                semi_major: radius,
                semi_minor: radius,
                angle: 0.0,
            };
            edge_points(image, &coarse, &mut points);
            for &(x, y) in &points {
                let off = (x - cx).hypot(y - cy) - radius;
                assert!(off.abs() < 0.35, "({x}, {y}) is {off} px off the edge");
            }
            counts.insert(points.len());
        }
        assert_eq!(counts.len(), 1, "edge points per nudge: {counts:?}");
        // The disc's top reaches within 4 px of the edge: the rays up to it
        // still read, those that show too little margin do not.
        let count = *counts.first().unwrap();
        assert!((40..64).contains(&count), "{count} edge points");
    }

    /// The vector blend of a 3×3 neighbourhood and the portable one (taken
    /// where the slice ends before a fourth byte of the last row) agree to
    /// the bit, so detections do not depend on the target; both are the
    /// weighted sum.
    #[test]
    fn both_paths_of_the_smooth_blend_agree_to_the_bit() {
        let mut rng = crate::math::Pcg32::new(7, 3);
        let width = 5;
        for _ in 0..2000 {
            let pixels: Vec<u8> = (0..3 * width)
                .map(|_| (rng.next_u32() % 256) as u8)
                .collect();
            let spline = |d: f64| {
                [
                    0.5 * (0.5 - d) * (0.5 - d),
                    0.75 - d * d,
                    0.5 * (0.5 + d) * (0.5 + d),
                ]
                .map(|w| w as f32)
            };
            let offset = |r: u32| f64::from(r % 1000) / 1000.0 - 0.5;
            let (wx, wy) = (
                spline(offset(rng.next_u32())),
                spline(offset(rng.next_u32())),
            );
            let long = blend_3x3(&pixels, width, wx, wy);
            let short = blend_3x3(&pixels[..2 * width + 3], width, wx, wy);
            assert_eq!(long.to_bits(), short.to_bits());
            let exact: f64 = (0..3)
                .flat_map(|k| (0..3).map(move |l| (k, l)))
                .map(|(k, l)| {
                    f64::from(wy[k]) * f64::from(wx[l]) * f64::from(pixels[k * width + l])
                })
                .sum();
            assert!((f64::from(long) - exact).abs() < 1e-3, "{long} {exact}");
        }
    }

    /// A marker rendered under motion blur: the outline's edge spread
    /// gives the blur's direction, and its length to within the fifth the
    /// ring model's search covers; a sharp marker shows none.
    #[test]
    fn the_outline_of_a_motion_blurred_marker_gives_the_blur() {
        use crate::camera::Camera;
        use crate::geometry::Marker;
        use crate::simulate::{self, LooseMarker, MotionBlur, Placement, Scene, SceneObject};
        use nalgebra::Vector3;
        let camera = Camera::ideal(320, 240, 60.0);
        let z = camera.fx * 0.05 / 80.0;
        for (length, angle) in [(0.0, 0.0), (12.0, 0.3), (20.0, 2.0), (25.0, 1.2)] {
            let mut scene = Scene::new(camera);
            scene.noise = 2.0;
            let marker = Marker::whycode(8, 0b0001_0011, 50.0);
            let placement = Placement::viewed(Vector3::new(0.0, 0.0, z), 0.0, 0.0, 0.5);
            scene
                .objects
                .push(SceneObject::Marker(LooseMarker::new(marker, 1, placement)));
            scene.motion_blur = Some(MotionBlur {
                length_px: length,
                angle,
            });
            let (image, truth) = simulate::render(&scene);
            let m = &truth.markers[0];
            let outer = Ellipse {
                u: m.u,
                v: m.v,
                semi_major: m.diameter_px / 2.0,
                semi_minor: m.diameter_px / 2.0,
                angle: 0.0,
            };
            let gray = Gray::new(image.as_raw(), 320, 240);
            let blur = linear_blur(gray, &outer).expect("edge readable");
            if length == 0.0 {
                assert!(blur.length < MIN_MOTION_BLUR_PX, "{blur:?}");
                continue;
            }
            let off = (blur.angle - angle).rem_euclid(std::f64::consts::PI);
            let off = off.min(std::f64::consts::PI - off);
            assert!(off < 0.1, "{length} px at {angle}: {blur:?}");
            let ratio = blur.length / length;
            assert!((0.7..1.05).contains(&ratio), "{length} px: {blur:?}");
        }
    }

    /// A marker rendered out of focus: the outline's edge spread gives the
    /// Gaussian's sigma to within the span the ring model tries around it.
    #[test]
    fn the_outline_of_a_defocused_marker_gives_the_blur() {
        use crate::camera::Camera;
        use crate::geometry::Marker;
        use crate::simulate::{self, LooseMarker, Placement, Scene, SceneObject};
        use nalgebra::Vector3;
        let camera = Camera::ideal(320, 240, 60.0);
        for (diameter, sigma) in [
            (30.0, 0.0),
            (30.0, 1.0),
            (30.0, 2.0),
            (60.0, 1.5),
            (60.0, 3.0),
        ] {
            let z = camera.fx * 0.05 / diameter;
            let mut scene = Scene::new(camera);
            scene.noise = 2.0;
            scene.focus_blur_px = sigma;
            let marker = Marker::whycode(8, 0b0001_0011, 50.0);
            let placement = Placement::viewed(Vector3::new(0.0, 0.0, z), 0.0, 0.0, 0.5);
            scene
                .objects
                .push(SceneObject::Marker(LooseMarker::new(marker, 1, placement)));
            let (image, truth) = simulate::render(&scene);
            let m = &truth.markers[0];
            let outer = Ellipse {
                u: m.u,
                v: m.v,
                semi_major: m.diameter_px / 2.0,
                semi_minor: m.diameter_px / 2.0,
                angle: 0.0,
            };
            let gray = Gray::new(image.as_raw(), 320, 240);
            let measured = defocus(gray, &outer).expect("edge readable");
            assert!(
                (measured - sigma).abs() < 0.25 * sigma + 0.4,
                "sigma {sigma} on {diameter} px read as {measured}"
            );
        }
    }

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
