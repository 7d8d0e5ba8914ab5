//! The one ellipse type: a marker's outline in an image, as the detector
//! measures it, as pose reads it and as the simulator's ground truth states it.
//!
//! Two fits, because the two callers need different things:
//! - [`Ellipse::fit`] (Fitzgibbon's direct fit, Halíř–Flusser form) always
//!   returns an ellipse or nothing whatever the units, which pose needs for
//!   boundary points in normalised camera coordinates;
//! - [`Ellipse::fit_near`] (linear least squares with A + C = 1 around a
//!   known centre and scale) is a 5×5 solve, cheap enough for every edge
//!   refinement of every candidate in every frame of the detector.

use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::angle::normalize_axis_angle;

/// An ellipse in pixel coordinates (origin at the top-left pixel's centre,
/// v down).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ellipse {
    /// Centre column, pixels.
    pub u: f64,
    /// Centre row, pixels.
    pub v: f64,
    /// Semi-major axis, pixels.
    pub semi_major: f64,
    /// Semi-minor axis, pixels.
    pub semi_minor: f64,
    /// Direction of the major axis, atan2(dv, du), in (-π/2, π/2].
    pub angle: f64,
}

impl Ellipse {
    /// The ellipse of a uniformly filled region with this centroid and these
    /// second central moments (paper eq. 2-3): its covariance has eigenvalues
    /// a²/4 and b²/4. None for a degenerate (line-like) region.
    pub fn from_moments(u: f64, v: f64, (cuu, cuv, cvv): (f64, f64, f64)) -> Option<Ellipse> {
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
            semi_major: 2.0 * l0.sqrt(),
            semi_minor: 2.0 * l1.sqrt(),
            angle,
        })
    }

    /// Least-squares ellipse through boundary points (direct ellipse-specific
    /// fit of Fitzgibbon et al. in the numerically stable form of Halíř and
    /// Flusser, on centred and scaled coordinates). `None` for fewer than 5
    /// points, degenerate configurations or data that fit no ellipse.
    pub fn fit(points: &[(f64, f64)]) -> Option<Ellipse> {
        Ellipse::from_conic(&fit_conic(points)?)
    }

    /// Least-squares conic through the points, normalised by A + C = 1 (never
    /// zero for an ellipse), in coordinates centred on `origin` and scaled by
    /// `scale` for conditioning. `None` for fewer than 6 points or a conic
    /// that is not a real ellipse.
    pub fn fit_near(points: &[(f64, f64)], origin: (f64, f64), scale: f64) -> Option<Ellipse> {
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
        let unit = Ellipse::from_conic_coefficients([1.0 - c, b, c, d, e, f])?;
        Some(Ellipse {
            u: origin.0 + unit.u * scale,
            v: origin.1 + unit.v * scale,
            semi_major: unit.semi_major * scale,
            semi_minor: unit.semi_minor * scale,
            angle: unit.angle,
        })
    }

    /// The ellipse described by a conic matrix C (points p = (u, v, 1) with
    /// pᵀ C p = 0), if it is a real ellipse.
    pub fn from_conic(conic: &Matrix3<f64>) -> Option<Ellipse> {
        let c = 0.5 * (conic + conic.transpose());
        let quadratic = Matrix2::new(c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]);
        let linear = Vector2::new(c[(0, 2)], c[(1, 2)]);
        let centre = -quadratic.try_inverse()? * linear;
        let value_at_centre = linear.dot(&centre) + c[(2, 2)];
        if !(value_at_centre.is_finite() && value_at_centre != 0.0) {
            return None;
        }
        let shape = quadratic / -value_at_centre;
        let (a, b, d) = (shape[(0, 0)], shape[(0, 1)], shape[(1, 1)]);
        let mean = 0.5 * (a + d);
        let spread = (0.25 * (a - d).powi(2) + b * b).sqrt();
        let (small, large) = (mean - spread, mean + spread);
        if !(small > 0.0 && large.is_finite()) {
            return None;
        }
        // The major axis belongs to the smaller eigenvalue of the shape matrix.
        let minor_direction = 0.5 * (2.0 * b).atan2(a - d);
        let ellipse = Ellipse {
            u: centre.x,
            v: centre.y,
            semi_major: 1.0 / small.sqrt(),
            semi_minor: 1.0 / large.sqrt(),
            angle: normalize_axis_angle(minor_direction + std::f64::consts::FRAC_PI_2),
        };
        ellipse.is_valid().then_some(ellipse)
    }

    /// The ellipse of a conic A x² + B xy + C y² + D x + E y + F = 0, if it
    /// is a real ellipse.
    fn from_conic_coefficients(k: [f64; 6]) -> Option<Ellipse> {
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
            semi_major: major,
            semi_minor: minor,
            angle: normalize_axis_angle(angle),
        })
    }

    /// Conic matrix C with pᵀ C p = 0 on the ellipse (p = (u, v, 1)), scaled
    /// so that it is negative at the centre.
    pub fn conic(&self) -> Matrix3<f64> {
        let (s, c) = self.angle.sin_cos();
        let (ia, ib) = (
            1.0 / (self.semi_major * self.semi_major),
            1.0 / (self.semi_minor * self.semi_minor),
        );
        let m00 = c * c * ia + s * s * ib;
        let m01 = c * s * (ia - ib);
        let m11 = s * s * ia + c * c * ib;
        let (u, v) = (self.u, self.v);
        let l0 = -(m00 * u + m01 * v);
        let l1 = -(m01 * u + m11 * v);
        let k = m00 * u * u + 2.0 * m01 * u * v + m11 * v * v - 1.0;
        Matrix3::new(m00, m01, l0, m01, m11, l1, l0, l1, k)
    }

    /// Area, square pixels.
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.semi_major * self.semi_minor
    }

    /// Boundary point at parameter t: centre + a·cos t along the major axis
    /// (t = 0 is its end in the `angle` direction) + b·sin t along the minor.
    pub fn point_at(&self, t: f64) -> (f64, f64) {
        let (s, c) = self.angle.sin_cos();
        let (a, b) = (self.semi_major * t.cos(), self.semi_minor * t.sin());
        (self.u + a * c - b * s, self.v + a * s + b * c)
    }

    /// `n` boundary points evenly spaced in the parameter.
    pub fn boundary_points(&self, n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| self.point_at(std::f64::consts::TAU * i as f64 / n as f64))
            .collect()
    }

    /// The same ellipse scaled about its centre.
    pub fn scaled(&self, k: f64) -> Ellipse {
        Ellipse {
            semi_major: self.semi_major * k,
            semi_minor: self.semi_minor * k,
            ..*self
        }
    }

    /// Approximate distance of a point from the ellipse (exact on the axes),
    /// via the radial scaling of the point onto the curve.
    pub fn radial_distance(&self, x: f64, y: f64) -> f64 {
        self.radial_distance_turned(self.angle.sin_cos(), x, y)
    }

    /// [`Ellipse::radial_distance`] of each point, the axes' direction
    /// worked out once (a sine and cosine per point were most of the cost).
    pub fn radial_distances<'a>(
        &'a self,
        points: &'a [(f64, f64)],
    ) -> impl Iterator<Item = f64> + 'a {
        let turn = self.angle.sin_cos();
        points
            .iter()
            .map(move |&(x, y)| self.radial_distance_turned(turn, x, y))
    }

    fn radial_distance_turned(&self, (s, c): (f64, f64), x: f64, y: f64) -> f64 {
        let (dx, dy) = (x - self.u, y - self.v);
        let (p, q) = (dx * c + dy * s, -dx * s + dy * c);
        let r = p.hypot(q);
        let k = ((p / self.semi_major).powi(2) + (q / self.semi_minor).powi(2)).sqrt();
        if k == 0.0 {
            return self.semi_minor;
        }
        (r - r / k).abs()
    }

    /// Finite centre and angle, 0 < semi_minor <= semi_major < ∞.
    pub fn is_valid(&self) -> bool {
        self.u.is_finite()
            && self.v.is_finite()
            && self.angle.is_finite()
            && self.semi_minor > 0.0
            && self.semi_major >= self.semi_minor
            && self.semi_major.is_finite()
    }
}

/// Least-squares conic through points (Fitzgibbon's ellipse-specific fit,
/// Halíř–Flusser formulation), as a symmetric matrix C with pᵀ C p = 0 for
/// p = (x, y, 1), scaled to unit Frobenius norm. `None` if the points are
/// too few, not finite or degenerate.
pub fn fit_conic(points: &[(f64, f64)]) -> Option<Matrix3<f64>> {
    if points.len() < 5 || points.iter().any(|p| !p.0.is_finite() || !p.1.is_finite()) {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(sx, sy), p| (sx + p.0 / n, sy + p.1 / n));
    let rms = (points
        .iter()
        .map(|p| (p.0 - mx).powi(2) + (p.1 - my).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    if rms.is_nan() || rms <= 0.0 {
        return None;
    }
    // Centre and scale so the scatter matrix is well conditioned whatever
    // the units (pixels or normalised camera coordinates).
    let scale = std::f64::consts::SQRT_2 / rms;
    let mut s1 = Matrix3::zeros();
    let mut s2 = Matrix3::zeros();
    let mut s3 = Matrix3::zeros();
    for p in points {
        let (x, y) = ((p.0 - mx) * scale, (p.1 - my) * scale);
        let quadratic = Vector3::new(x * x, x * y, y * y);
        let linear = Vector3::new(x, y, 1.0);
        s1 += quadratic * quadratic.transpose();
        s2 += quadratic * linear.transpose();
        s3 += linear * linear.transpose();
    }
    let linear_from_quadratic = -s3.try_inverse()? * s2.transpose();
    let reduced = s1 + s2 * linear_from_quadratic;
    let reduced = 0.5 * (reduced + reduced.transpose());
    // Minimise aᵀ M a subject to 4ac - b² = 1: with M = L Lᵀ this is the
    // largest eigenvalue of the symmetric L⁻¹ C L⁻ᵀ. The tiny ridge keeps
    // Cholesky alive for noise-free points, where M is singular and its
    // null vector is the exact answer.
    let ridge = 1e-13 * reduced.trace().max(f64::MIN_POSITIVE);
    let cholesky = (reduced + Matrix3::identity() * ridge).cholesky()?;
    let l_inv = cholesky.l().try_inverse()?;
    let constraint = Matrix3::new(0.0, 0.0, 2.0, 0.0, -1.0, 0.0, 2.0, 0.0, 0.0);
    let eigen = SymmetricEigen::new(l_inv * constraint * l_inv.transpose());
    let best = eigen.eigenvalues.imax();
    if eigen.eigenvalues[best].is_nan() || eigen.eigenvalues[best] <= 0.0 {
        return None;
    }
    let quadratic = l_inv.transpose() * eigen.eigenvectors.column(best);
    let linear = linear_from_quadratic * quadratic;
    let (a, b, c) = (quadratic[0], quadratic[1], quadratic[2]);
    let (d, e, f) = (linear[0], linear[1], linear[2]);
    let normalized = Matrix3::new(
        a,
        0.5 * b,
        0.5 * d,
        0.5 * b,
        c,
        0.5 * e,
        0.5 * d,
        0.5 * e,
        f,
    );
    let to_normalized = Matrix3::new(
        scale,
        0.0,
        -scale * mx,
        0.0,
        scale,
        -scale * my,
        0.0,
        0.0,
        1.0,
    );
    let conic = to_normalized.transpose() * normalized * to_normalized;
    let norm = conic.norm();
    (norm > 0.0 && norm.is_finite()).then(|| conic / norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conic_matrix_round_trip() {
        let e = Ellipse {
            u: 120.5,
            v: -33.0,
            semi_major: 40.0,
            semi_minor: 12.5,
            angle: 2.0,
        };
        let back = Ellipse::from_conic(&(e.conic() * -3.0)).unwrap();
        assert!((back.u - e.u).abs() < 1e-9 && (back.v - e.v).abs() < 1e-9);
        assert!((back.semi_major - 40.0).abs() < 1e-9 && (back.semi_minor - 12.5).abs() < 1e-9);
        assert!((back.angle - normalize_axis_angle(2.0)).abs() < 1e-12);
        for (u, v) in e.boundary_points(7) {
            let p = Vector3::new(u, v, 1.0);
            assert!((p.transpose() * e.conic() * p)[0].abs() < 1e-12);
        }
    }

    #[test]
    fn both_fits_recover_a_rotated_ellipse() {
        let e = Ellipse {
            u: 40.3,
            v: 21.7,
            semi_major: 12.0,
            semi_minor: 5.0,
            angle: 0.6,
        };
        let points: Vec<(f64, f64)> = (0..20).map(|k| e.point_at(k as f64 * 0.31)).collect();
        for fitted in [
            Ellipse::fit_near(&points, (40.0, 20.0), 12.0).unwrap(),
            Ellipse::fit(&points).unwrap(),
        ] {
            assert!((fitted.u - e.u).abs() < 1e-9 && (fitted.v - e.v).abs() < 1e-9);
            assert!((fitted.semi_major - e.semi_major).abs() < 1e-9);
            assert!((fitted.semi_minor - e.semi_minor).abs() < 1e-9);
            assert!((fitted.angle - e.angle).abs() < 1e-9, "{}", fitted.angle);
            for &(x, y) in &points {
                assert!(fitted.radial_distance(x, y) < 1e-9);
            }
        }
    }

    #[test]
    fn moments_of_filled_ellipse() {
        // A filled ellipse with semi-axes a, b has variances a²/4, b²/4.
        let (a, b, angle) = (30.0f64, 10.0f64, 0.4f64);
        let (s, c) = angle.sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        let cov = r * Matrix2::new(a * a / 4.0, 0.0, 0.0, b * b / 4.0) * r.transpose();
        let e = Ellipse::from_moments(5.0, 6.0, (cov[(0, 0)], cov[(0, 1)], cov[(1, 1)])).unwrap();
        assert!((e.semi_major - a).abs() < 1e-9 && (e.semi_minor - b).abs() < 1e-9);
        assert!((e.angle - angle).abs() < 1e-12);
        let round = Ellipse::from_moments(0.0, 0.0, (1.0, 0.0, 1.0)).unwrap();
        assert_eq!(
            (round.semi_major, round.semi_minor, round.angle),
            (2.0, 2.0, 0.0)
        );
        assert!(Ellipse::from_moments(0.0, 0.0, (1.0, 1.0, 1.0)).is_none());
    }

    #[test]
    fn fit_rejects_degenerate_input() {
        assert!(Ellipse::fit(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 3.0)]).is_none());
        let line: Vec<_> = (0..20).map(|i| (i as f64, 2.0 * i as f64)).collect();
        assert!(Ellipse::fit(&line).is_none());
        assert!(Ellipse::fit_near(&line, (10.0, 20.0), 10.0).is_none());
        assert!(Ellipse::fit(&[(1.0, 1.0); 10]).is_none());
    }
}
