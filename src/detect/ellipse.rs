//! The marker's outer ellipse: first from the segment's moments (eq. 2-3 of
//! the paper), then refined to sub-pixel accuracy from edge points.
//!
//! The moment ellipse depends on which boundary pixels the threshold let in,
//! so its axes are off by up to half a pixel and its centre is pulled by
//! uneven light. The refinement looks for the 50 % crossing between the
//! local black and the local white along rays through the outer edge (this
//! point does not move with symmetric blur) and fits a conic to those points.

use super::segment::{Gray, Stats};

/// An ellipse in pixel coordinates (origin at the top-left pixel's centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    pub u: f64,
    pub v: f64,
    /// Semi-major axis, pixels.
    pub a: f64,
    /// Semi-minor axis, pixels.
    pub b: f64,
    /// Direction of the major axis, atan2(dv, du), in (-π/2, π/2].
    pub angle: f64,
}

impl Ellipse {
    /// The ellipse of a uniformly filled region with these moments: its
    /// covariance has eigenvalues a²/4 and b²/4.
    pub fn from_moments(stats: &Stats) -> Option<Ellipse> {
        if stats.count < 3 {
            return None;
        }
        let (u, v) = stats.centroid();
        let (cuu, cuv, cvv) = stats.covariance();
        let mean = (cuu + cvv) / 2.0;
        let diff = ((cuu - cvv) / 2.0).hypot(cuv);
        let (l0, l1) = (mean + diff, mean - diff);
        if l1 <= 0.0 || !l0.is_finite() {
            return None;
        }
        let angle = if diff > 0.0 {
            0.5 * (2.0 * cuv).atan2(cuu - cvv)
        } else {
            0.0
        };
        Some(Ellipse {
            u,
            v,
            a: 2.0 * l0.sqrt(),
            b: 2.0 * l1.sqrt(),
            angle,
        })
    }

    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.a * self.b
    }

    /// The point at parameter t: centre + a·cos t along the major axis +
    /// b·sin t along the minor axis.
    pub fn point(&self, t: f64) -> (f64, f64) {
        let (s, c) = self.angle.sin_cos();
        let (x, y) = (self.a * t.cos(), self.b * t.sin());
        (self.u + x * c - y * s, self.v + x * s + y * c)
    }

    /// The same ellipse scaled about its centre.
    pub fn scaled(&self, k: f64) -> Ellipse {
        Ellipse {
            a: self.a * k,
            b: self.b * k,
            ..*self
        }
    }

    /// The ellipse of a conic A x² + B xy + C y² + D x + E y + F = 0, if it
    /// is a real ellipse.
    pub fn from_conic(k: [f64; 6]) -> Option<Ellipse> {
        let [a, b, c, d, e, f] = k;
        let det = 4.0 * a * c - b * b;
        if det <= 0.0 {
            return None;
        }
        let u = (b * e - 2.0 * c * d) / det;
        let v = (b * d - 2.0 * a * e) / det;
        // Value of the conic at the centre: the quadratic form equals -f0 there.
        let f0 = f + (d * u + e * v) / 2.0;
        let mean = (a + c) / 2.0;
        let diff = ((a - c) / 2.0).hypot(b / 2.0);
        let (l_small, l_large) = (mean - diff, mean + diff);
        // Normalise so that the form is positive definite.
        let (l_small, l_large, f0) = if l_small < 0.0 {
            (-l_large, -l_small, -f0)
        } else {
            (l_small, l_large, f0)
        };
        if l_small <= 0.0 || f0 >= 0.0 {
            return None;
        }
        let major = (-f0 / l_small).sqrt();
        let minor = (-f0 / l_large).sqrt();
        // The major axis is the eigenvector of the smaller eigenvalue.
        let mut angle = 0.5 * b.atan2(a - c) + std::f64::consts::FRAC_PI_2;
        if a + c < 0.0 {
            angle -= std::f64::consts::FRAC_PI_2;
        }
        Some(Ellipse {
            u,
            v,
            a: major,
            b: minor,
            angle: normalise_axis_angle(angle),
        })
    }
}

/// An axis direction has no sign: fold it into (-π/2, π/2].
pub fn normalise_axis_angle(angle: f64) -> f64 {
    use std::f64::consts::PI;
    let mut a = angle.rem_euclid(PI);
    if a > PI / 2.0 {
        a -= PI;
    }
    a
}

/// Bilinear interpolation; None outside the image.
#[inline]
pub fn sample(image: Gray<'_>, x: f64, y: f64) -> Option<f64> {
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    let (x0, y0) = (x as usize, y as usize);
    if x0 + 1 >= image.width || y0 + 1 >= image.height {
        return None;
    }
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let i = y0 * image.width + x0;
    let p = image.pixels;
    let top = f64::from(p[i]) + fx * (f64::from(p[i + 1]) - f64::from(p[i]));
    let bottom = f64::from(p[i + image.width])
        + fx * (f64::from(p[i + image.width + 1]) - f64::from(p[i + image.width]));
    Some(top + fy * (bottom - top))
}

/// Sub-pixel points on the outer edge of the black disc, found along rays
/// from the centre through the coarse ellipse: the 50 % crossing between
/// the darkest value inside and the brightest outside, nearest to the
/// coarse edge.
/// Returns the number of rays cast.
pub fn edge_points(image: Gray<'_>, coarse: &Ellipse, out: &mut Vec<(f64, f64)>) -> usize {
    out.clear();
    let perimeter = std::f64::consts::PI * (coarse.a + coarse.b);
    let rays = ((perimeter / 4.0) as usize).clamp(24, 64);
    // Profile from 0.75 to 1.3 of the edge radius, in steps of at most one
    // pixel; the black annulus is at least 0.4 R wide and the white margin
    // 0.3 R, so both levels are seen on every ray.
    let mut profile = [0.0f64; 48];
    for k in 0..rays {
        let t = std::f64::consts::TAU * (k as f64 + 0.5) / rays as f64;
        let (px, py) = coarse.point(t);
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
        let (px, py) = outer.point(t);
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

/// Least-squares conic through the points, normalised by A + C = 1 (never
/// zero for an ellipse), in coordinates centred on `origin` and scaled to
/// unit size for conditioning.
pub fn fit_conic(points: &[(f64, f64)], origin: (f64, f64), scale: f64) -> Option<Ellipse> {
    if points.len() < 6 {
        return None;
    }
    // Unknowns B, C, D, E, F with A = 1 - C:
    // (y² - x²) C + xy B + x D + y E + F = -x².
    let mut ata = nalgebra::Matrix5::<f64>::zeros();
    let mut atb = nalgebra::Vector5::<f64>::zeros();
    for &(px, py) in points {
        let (x, y) = ((px - origin.0) / scale, (py - origin.1) / scale);
        let row = nalgebra::Vector5::new(x * y, y * y - x * x, x, y, 1.0);
        ata += row * row.transpose();
        atb += row * (-x * x);
    }
    let sol = ata.lu().solve(&atb)?;
    let (b, c, d, e, f) = (sol[0], sol[1], sol[2], sol[3], sol[4]);
    let unit = Ellipse::from_conic([1.0 - c, b, c, d, e, f])?;
    Some(Ellipse {
        u: origin.0 + unit.u * scale,
        v: origin.1 + unit.v * scale,
        a: unit.a * scale,
        b: unit.b * scale,
        angle: unit.angle,
    })
}

/// Approximate distance of a point from an ellipse (exact on the axes),
/// via the radial scaling of the point onto the curve.
pub fn radial_distance(e: &Ellipse, x: f64, y: f64) -> f64 {
    let (s, c) = e.angle.sin_cos();
    let (dx, dy) = (x - e.u, y - e.v);
    let (p, q) = (dx * c + dy * s, -dx * s + dy * c);
    let r = p.hypot(q);
    let k = ((p / e.a).powi(2) + (q / e.b).powi(2)).sqrt();
    if k == 0.0 {
        return e.b;
    }
    (r - r / k).abs()
}

/// A refined outline and how well the edge fits it.
#[derive(Debug, Clone, Copy)]
pub struct Refined {
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
    let scale = coarse.a.max(1.0);
    let first = fit_conic(scratch, (coarse.u, coarse.v), scale)?;
    let mut residuals: Vec<f64> = scratch
        .iter()
        .map(|&(x, y)| radial_distance(&first, x, y))
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
    let fitted = fit_conic(scratch, (coarse.u, coarse.v), scale)?;
    let consistent = (fitted.u - coarse.u).hypot(fitted.v - coarse.v) < 0.25 * coarse.b + 1.0
        && (fitted.a / coarse.a - 1.0).abs() < 0.25
        && (fitted.b / coarse.b - 1.0).abs() < 0.25;
    if !consistent {
        return None;
    }
    let sum_sq: f64 = scratch
        .iter()
        .map(|&(x, y)| radial_distance(&fitted, x, y).powi(2))
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
    fn conic_of_a_rotated_ellipse_round_trips() {
        let e = Ellipse {
            u: 40.3,
            v: 21.7,
            a: 12.0,
            b: 5.0,
            angle: 0.6,
        };
        let points: Vec<(f64, f64)> = (0..20).map(|k| e.point(k as f64 * 0.31)).collect();
        let fitted = fit_conic(&points, (40.0, 20.0), 12.0).unwrap();
        assert!((fitted.u - e.u).abs() < 1e-9 && (fitted.v - e.v).abs() < 1e-9);
        assert!((fitted.a - e.a).abs() < 1e-9 && (fitted.b - e.b).abs() < 1e-9);
        assert!((fitted.angle - e.angle).abs() < 1e-9, "{}", fitted.angle);
        for &(x, y) in &points {
            assert!(radial_distance(&fitted, x, y) < 1e-9);
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
        let e = Ellipse::from_moments(&s).unwrap();
        assert!((e.u - 100.0).abs() < 1e-9 && (e.v - 100.0).abs() < 1e-9);
        assert!(
            (e.a - 30.0).abs() < 0.6 && (e.b - 30.0).abs() < 0.6,
            "{e:?}"
        );
    }
}
