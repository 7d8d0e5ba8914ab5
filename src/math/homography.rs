//! Plane-to-image homographies: normalised DLT, RANSAC over matched pairs,
//! and the image of a circle (whose centre is not the image of the
//! circle's centre under perspective).

use super::{Ellipse, Pcg32};
use nalgebra::{DMatrix, Matrix2, Matrix3, SymmetricEigen, Vector3};

/// A plane point and the image point it maps to.
pub type PointPair = ((f64, f64), (f64, f64));

/// A projective map of the plane, page millimetres → image pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography {
    /// The 3×3 matrix acting on homogeneous points (x, y, 1).
    pub matrix: Matrix3<f64>,
}

impl Homography {
    /// Maps a plane point to the image; `None` at the horizon.
    pub fn apply(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let p = self.matrix * Vector3::new(x, y, 1.0);
        (p.z.abs() > 1e-12).then(|| (p.x / p.z, p.y / p.z))
    }

    /// The map back from image to plane; `None` when degenerate.
    pub fn inverse(&self) -> Option<Homography> {
        self.matrix
            .try_inverse()
            .map(|matrix| Homography { matrix })
    }

    /// The local linear map (Jacobian) at a plane point.
    pub fn jacobian(&self, x: f64, y: f64) -> Matrix2<f64> {
        let m = &self.matrix;
        let w = m[(2, 0)] * x + m[(2, 1)] * y + m[(2, 2)];
        let u = m[(0, 0)] * x + m[(0, 1)] * y + m[(0, 2)];
        let v = m[(1, 0)] * x + m[(1, 1)] * y + m[(1, 2)];
        Matrix2::new(
            (m[(0, 0)] * w - u * m[(2, 0)]) / (w * w),
            (m[(0, 1)] * w - u * m[(2, 1)]) / (w * w),
            (m[(1, 0)] * w - v * m[(2, 0)]) / (w * w),
            (m[(1, 1)] * w - v * m[(2, 1)]) / (w * w),
        )
    }

    /// The image of the circle of radius `r` about (x, y) as an ellipse:
    /// (centre u, centre v, semi-major, semi-minor, major-axis angle).
    pub fn circle_image(&self, x: f64, y: f64, r: f64) -> Option<Ellipse> {
        let c = Matrix3::new(1.0, 0.0, -x, 0.0, 1.0, -y, -x, -y, x * x + y * y - r * r);
        let inv = self.matrix.try_inverse()?;
        let conic = inv.transpose() * c * inv;
        Ellipse::from_conic(&conic)
    }

    /// Least-squares fit (normalised DLT) to at least four pairs
    /// (plane point, image point).
    pub fn fit(pairs: &[PointPair]) -> Option<Homography> {
        if pairs.len() < 4 {
            return None;
        }
        let (ts, src) = normalise(pairs.iter().map(|p| p.0));
        let (td, dst) = normalise(pairs.iter().map(|p| p.1));
        let mut a = DMatrix::<f64>::zeros(2 * pairs.len(), 9);
        for (k, (s, d)) in src.iter().zip(&dst).enumerate() {
            let (x, y, u, v) = (s.0, s.1, d.0, d.1);
            let r0 = [-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u];
            let r1 = [0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v];
            for j in 0..9 {
                a[(2 * k, j)] = r0[j];
                a[(2 * k + 1, j)] = r1[j];
            }
        }
        let ata = a.transpose() * &a;
        let eigen = SymmetricEigen::new(ata);
        let (smallest, _) = eigen
            .eigenvalues
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))?;
        let h = eigen.eigenvectors.column(smallest);
        let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
        let matrix = td.try_inverse()? * hn * ts;
        let scale = matrix[(2, 2)];
        if !scale.is_finite() || scale.abs() < 1e-15 {
            return None;
        }
        let matrix = matrix / scale;
        matrix
            .iter()
            .all(|v| v.is_finite())
            .then_some(Homography { matrix })
    }
}

/// Hartley normalisation: centroid to the origin, mean distance √2.
fn normalise(points: impl Iterator<Item = (f64, f64)>) -> (Matrix3<f64>, Vec<(f64, f64)>) {
    let pts: Vec<(f64, f64)> = points.collect();
    let n = pts.len() as f64;
    let (mx, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let mean_dist = pts.iter().map(|p| (p.0 - mx).hypot(p.1 - my)).sum::<f64>() / n;
    let s = if mean_dist > 1e-12 {
        std::f64::consts::SQRT_2 / mean_dist
    } else {
        1.0
    };
    let t = Matrix3::new(s, 0.0, -s * mx, 0.0, s, -s * my, 0.0, 0.0, 1.0);
    let out = pts
        .iter()
        .map(|p| (s * (p.0 - mx), s * (p.1 - my)))
        .collect();
    (t, out)
}

/// One plane ↔ image correspondence with its own inlier tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correspondence {
    /// The point on the plane (page mm).
    pub plane: (f64, f64),
    /// Where it was seen, image pixels.
    pub image: (f64, f64),
    /// Largest reprojection error (pixels) at which the pair agrees.
    pub tolerance: f64,
}

/// Result of a robust fit: the homography and which pairs agree with it.
#[derive(Debug, Clone)]
pub struct RobustFit {
    /// The fitted map.
    pub homography: Homography,
    /// For each correspondence, whether it agrees within its tolerance.
    pub inliers: Vec<bool>,
    /// Root-mean-square reprojection error of the inliers, pixels.
    pub rms_px: f64,
}

fn reprojection_error(h: &Homography, c: &Correspondence) -> f64 {
    h.apply(c.plane.0, c.plane.1)
        .map_or(f64::INFINITY, |(u, v)| (u - c.image.0).hypot(v - c.image.1))
}

/// RANSAC over minimal samples of four pairs (all of them when there are
/// few, a fixed-seed random selection otherwise, so results repeat), then
/// least-squares refinement on the consensus set.
pub fn fit_robust(pairs: &[Correspondence]) -> Option<RobustFit> {
    let n = pairs.len();
    if n < 4 {
        return None;
    }
    let samples: Vec<[usize; 4]> = if n <= 14 {
        let mut all = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                for c in b + 1..n {
                    for d in c + 1..n {
                        all.push([a, b, c, d]);
                    }
                }
            }
        }
        all
    } else {
        let mut rng = Pcg32::new(0x5eed, 41);
        (0..1500)
            .filter_map(|_| {
                let mut s = [0usize; 4];
                for slot in s.iter_mut() {
                    *slot = (rng.next_u32() as usize) % n;
                }
                let distinct = (0..4).all(|i| (i + 1..4).all(|j| s[i] != s[j]));
                distinct.then_some(s)
            })
            .collect()
    };
    let score = |h: &Homography| -> (usize, f64) {
        let mut count = 0;
        let mut cost = 0.0;
        for c in pairs {
            let e = reprojection_error(h, c);
            if e <= c.tolerance {
                count += 1;
                cost += e / c.tolerance;
            } else {
                cost += 1.0;
            }
        }
        (count, cost)
    };
    let mut best: Option<(Homography, usize, f64)> = None;
    for s in samples {
        let minimal: Vec<_> = s
            .iter()
            .map(|&k| (pairs[k].plane, pairs[k].image))
            .collect();
        if collinear_triple(&minimal) {
            continue;
        }
        let Some(h) = Homography::fit(&minimal) else {
            continue;
        };
        let (count, cost) = score(&h);
        let better = match &best {
            None => true,
            Some((_, bc, bcost)) => count > *bc || (count == *bc && cost < *bcost),
        };
        if better {
            best = Some((h, count, cost));
        }
    }
    let (mut h, count, _) = best?;
    if count < 4 {
        return None;
    }
    let mut inliers: Vec<bool> = pairs
        .iter()
        .map(|c| reprojection_error(&h, c) <= c.tolerance)
        .collect();
    for _ in 0..5 {
        let set: Vec<_> = pairs
            .iter()
            .zip(&inliers)
            .filter(|(_, &i)| i)
            .map(|(c, _)| (c.plane, c.image))
            .collect();
        let Some(refined) = Homography::fit(&set) else {
            break;
        };
        let next: Vec<bool> = pairs
            .iter()
            .map(|c| reprojection_error(&refined, c) <= c.tolerance)
            .collect();
        if next.iter().filter(|&&i| i).count() < 4 {
            break;
        }
        h = refined;
        let stable = next == inliers;
        inliers = next;
        if stable {
            break;
        }
    }
    let errors: Vec<f64> = pairs
        .iter()
        .zip(&inliers)
        .filter(|(_, &i)| i)
        .map(|(c, _)| reprojection_error(&h, c).powi(2))
        .collect();
    let rms_px = (errors.iter().sum::<f64>() / errors.len().max(1) as f64).sqrt();
    Some(RobustFit {
        homography: h,
        inliers,
        rms_px,
    })
}

/// True when three of the four plane points are (nearly) on a line, which
/// leaves the homography undetermined.
fn collinear_triple(pairs: &[PointPair]) -> bool {
    let pts: Vec<(f64, f64)> = pairs.iter().map(|p| p.0).collect();
    let span = pts
        .iter()
        .flat_map(|a| pts.iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1)))
        .fold(0.0, f64::max);
    for i in 0..4 {
        for j in i + 1..4 {
            for k in j + 1..4 {
                let (a, b, c) = (pts[i], pts[j], pts[k]);
                let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
                if cross.abs() < 1e-3 * span * span {
                    return true;
                }
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth() -> Homography {
        Homography {
            matrix: Matrix3::new(3.1, 0.4, 200.0, -0.2, 2.8, 150.0, 0.0009, -0.0004, 1.0),
        }
    }

    #[test]
    fn dlt_recovers_a_homography_from_exact_pairs() {
        let h = truth();
        let pairs: Vec<_> = [
            (0.0, 0.0),
            (200.0, 0.0),
            (200.0, 280.0),
            (0.0, 280.0),
            (90.0, 120.0),
        ]
        .iter()
        .map(|&(x, y)| ((x, y), h.apply(x, y).unwrap()))
        .collect();
        let fit = Homography::fit(&pairs).unwrap();
        for &(x, y) in &[(10.0, 10.0), (150.0, 200.0), (-20.0, 300.0)] {
            let (a, b) = (h.apply(x, y).unwrap(), fit.apply(x, y).unwrap());
            assert!((a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6);
        }
    }

    #[test]
    fn ransac_ignores_a_wrong_pair() {
        let h = truth();
        let mut pairs: Vec<Correspondence> = (0..12)
            .map(|k| {
                let (x, y) = (30.0 + 60.0 * (k % 3) as f64, 40.0 + 70.0 * (k / 3) as f64);
                Correspondence {
                    plane: (x, y),
                    image: h.apply(x, y).unwrap(),
                    tolerance: 5.0,
                }
            })
            .collect();
        pairs[5].image.0 += 80.0;
        let fit = fit_robust(&pairs).unwrap();
        assert!(!fit.inliers[5]);
        assert_eq!(fit.inliers.iter().filter(|&&i| i).count(), 11);
        assert!(fit.rms_px < 1e-6);
    }

    #[test]
    fn circle_image_of_identity_is_the_circle() {
        let h = Homography {
            matrix: Matrix3::identity(),
        };
        let e = h.circle_image(10.0, 20.0, 5.0).unwrap();
        assert!((e.u - 10.0).abs() < 1e-9 && (e.v - 20.0).abs() < 1e-9);
        assert!((e.semi_major - 5.0).abs() < 1e-9 && (e.semi_minor - 5.0).abs() < 1e-9);
    }
}
