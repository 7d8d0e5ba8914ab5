//! Refining a circle pose on every concentric edge of the marker at once.
//!
//! The closed-form pose reads the normal off one ellipse's eccentricity,
//! which near face-on is quadratic in the tilt: at 1° the minor axis of a
//! 100 px marker is 0.008 px shorter than the major, far below what edge
//! points measure. Concentric circles of known radii carry a cue that is
//! linear in the tilt instead: perspective shifts each circle's image
//! centre by an amount that grows with the square of its radius, so the
//! inner edges' ellipses sit off the outer one's centre in the direction
//! and by the amount of the tilt. Fitting one plane pose to the outer edge
//! and the inner edges together uses that cue.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::{plane_basis, CirclePose, RadialPoint};
use crate::camera::Camera;

type Params = SVector<f64, 5>;

/// Points (normalised image coordinates) and the radius of the circle each
/// lies on, metres.
struct Observations {
    points: Vec<(f64, f64, f64)>,
    /// Pixels per unit of normalised image coordinate.
    focal: f64,
}

/// A circle pose moved by `p`: three centre offsets relative to the
/// initial distance, two tilts of the normal.
fn moved(initial: &CirclePose, basis: &(Vector3<f64>, Vector3<f64>), p: &Params) -> CirclePose {
    let scale = initial.center.norm();
    CirclePose {
        center: initial.center + scale * Vector3::new(p[0], p[1], p[2]),
        normal: (initial.normal + p[3] * basis.0 + p[4] * basis.1).normalize(),
    }
}

/// The map from normalised image points to the circle plane's coordinates
/// (the inverse of the plane-to-image homography [e1 e2 c]).
fn image_to_plane(circle: &CirclePose) -> Option<Matrix3<f64>> {
    let (e1, e2) = plane_basis(&circle.normal);
    Matrix3::from_columns(&[e1, e2, circle.center]).try_inverse()
}

impl Observations {
    /// Signed distance in pixels of each point from the image of its
    /// circle (Sampson's first-order distance to the conic).
    fn residuals(&self, circle: &CirclePose, out: &mut [f64]) -> bool {
        let Some(g) = image_to_plane(circle) else {
            return false;
        };
        for (slot, &(x, y, r)) in out.iter_mut().zip(&self.points) {
            let plane = g * Vector3::new(x, y, 1.0);
            let weighted = Vector3::new(plane.x, plane.y, -r * r * plane.z);
            let value = plane.dot(&weighted);
            let gradient = 2.0 * (g.transpose() * weighted);
            let norm = (gradient.x * gradient.x + gradient.y * gradient.y).sqrt();
            if !(norm > 0.0 && value.is_finite()) {
                return false;
            }
            *slot = self.focal * value / norm;
        }
        true
    }

    /// The residuals at `circle` and their derivatives by the parameters
    /// of [`moved`] at zero (`basis` is the plane basis of its normal),
    /// worked out in closed form: tilting the normal towards a basis vector
    /// turns that vector towards the old normal, and the residual, which
    /// does not depend on how the basis is turned in its plane, follows.
    ///
    /// Each point's residual and row of derivatives go to `take`, in the
    /// points' order (the solver sums them into its normal equations as
    /// they come, with no table of rows to fill and clear).
    fn linearise(
        &self,
        circle: &CirclePose,
        basis: &(Vector3<f64>, Vector3<f64>),
        mut take: impl FnMut(f64, &[f64; 5]),
    ) -> bool {
        let Some(g) = Matrix3::from_columns(&[basis.0, basis.1, circle.center]).try_inverse()
        else {
            return false;
        };
        let scale = circle.center.norm();
        let n = circle.normal;
        let gn = g * n;
        let rows = [0, 1, 2].map(|i| g.row(i).transpose());
        // g^T D v, first two components, for D = diag(1, 1, -r²).
        let through = |v: &Vector3<f64>, r2: f64| {
            (
                v.x * rows[0].x + v.y * rows[1].x - r2 * v.z * rows[2].x,
                v.x * rows[0].y + v.y * rows[1].y - r2 * v.z * rows[2].y,
            )
        };
        let columns = [0, 1, 2].map(|k| g.column(k).into_owned());
        let mut row = [0.0f64; 5];
        for &(x, y, r) in &self.points {
            let r2 = r * r;
            let plane = g * Vector3::new(x, y, 1.0);
            let weighted = Vector3::new(plane.x, plane.y, -r2 * plane.z);
            let value = plane.dot(&weighted);
            let dual = plane.x * rows[0] + plane.y * rows[1] - r2 * plane.z * rows[2];
            // Not `hypot`, a library call: the terms are far from overflow.
            let half_norm = (dual.x * dual.x + dual.y * dual.y).sqrt();
            if !(half_norm > 0.0 && value.is_finite()) {
                return false;
            }
            let norm = 2.0 * half_norm;
            let residual = self.focal * value / norm;
            let derivative = |d_value: f64, d_dual: (f64, f64)| {
                let d_norm = 2.0 * (dual.x * d_dual.0 + dual.y * d_dual.1) / half_norm;
                self.focal * (d_value * norm - value * d_norm) / (norm * norm)
            };
            for (k, column) in columns.iter().enumerate() {
                let b = through(column, r2);
                let d_dual = (
                    -scale * (plane.z * b.0 + dual[k] * rows[2].x),
                    -scale * (plane.z * b.1 + dual[k] * rows[2].y),
                );
                row[k] = derivative(-2.0 * scale * plane.z * dual[k], d_dual);
            }
            let a = through(&gn, r2);
            let along_normal = n.dot(&dual);
            let weighted_normal = weighted.dot(&gn);
            for (k, along) in [(3, plane.x), (4, plane.y)] {
                let d_dual = (
                    along * a.0 + along_normal * rows[k - 3].x,
                    along * a.1 + along_normal * rows[k - 3].y,
                );
                row[k] = derivative(2.0 * along * weighted_normal, d_dual);
            }
            take(residual, &row);
        }
        true
    }
}

/// Gauss-Newton on the five pose parameters, relinearised around each
/// accepted step, halving a step that does not lower the cost; the start
/// is close (the closed-form pose, then the first round's fit, or the last
/// frame's fit), so a few steps converge.
fn solve(observations: &Observations, initial: &CirclePose, steps: usize) -> Option<CirclePose> {
    let n = observations.points.len();
    let mut trial = vec![0.0; n];
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut circle = *initial;
    for _ in 0..steps {
        let basis = plane_basis(&circle.normal);
        // JᵀJ is symmetric: the sums of its upper triangle, in plain
        // arrays, are mirrored below once (a product j[a]·j[b] is the same
        // number either way round, so the matrix is the one the full
        // outer products would sum, bit for bit).
        let mut upper = [[0.0f64; 5]; 5];
        let mut gradient = [0.0f64; 5];
        let mut current = 0.0;
        let linearised = observations.linearise(&circle, &basis, |r, j| {
            for a in 0..5 {
                for b in a..5 {
                    upper[a][b] += j[a] * j[b];
                }
                gradient[a] += j[a] * r;
            }
            current += r * r;
        });
        if !linearised {
            return None;
        }
        let normal = SMatrix::<f64, 5, 5>::from_fn(|a, b| upper[a.min(b)][a.max(b)]);
        let gradient = Params::from(gradient);
        let Some(mut step) = normal.cholesky().map(|c| c.solve(&-gradient)) else {
            break;
        };
        // Converged (see below): a step this small is taken without the
        // trial that checks it lowers the cost. A followed marker's fit
        // starts at last frame's optimum and mostly ends here, sparing
        // residuals whose change is lost in rounding anyway.
        if step.norm() < CONVERGED_STEP {
            circle = moved(&circle, &basis, &step);
            break;
        }
        let mut accepted = false;
        for _ in 0..4 {
            let q = moved(&circle, &basis, &step);
            if observations.residuals(&q, &mut trial) && cost(&trial) <= current {
                circle = q;
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        if !accepted || step.norm() < CONVERGED_STEP {
            break;
        }
    }
    Some(circle)
}

/// Step norm (relative centre shift, normal tilt in radians) under which
/// the fit has converged: the normal turns by less than 0.0006°, the centre
/// moves by less than 1e-6 of its distance.
const CONVERGED_STEP: f64 = 1e-5;

/// The circle pose that best explains edge points of several concentric
/// circles of the marker (each image point with the radius, metres, of the
/// circle it lies on), starting from `initial` (one of the two closed-form
/// candidates, already chosen). Points far off the fit (a ray along a ring
/// sector's side, a speck) are dropped in two rounds. `None` when fewer
/// than 12 points remain or the fit fails; callers keep `initial` then.
///
/// It stays in the initial candidate's basin: the choice between the two
/// candidates is made before, by the witnesses in `choose`.
pub fn refine_circle_pose(
    camera: &Camera,
    initial: &CirclePose,
    points_px: &[RadialPoint],
) -> Option<CirclePose> {
    // Outlier limits of the two rounds, pixels: loose around the
    // closed-form start, tight around the first fit.
    fit(
        camera,
        initial,
        points_px,
        &[(0.6, 3), (0.3, 1)],
        f64::INFINITY,
    )
}

/// Median misfit (pixels) of this frame's edge points to a start taken from
/// the last frame's fit, up to which that start counts as close: about
/// three times the edge points' own scatter on a settled fit.
const CLOSE_START_PX: f64 = 0.25;

/// [`refine_circle_pose`] from a start already close to the optimum: a
/// followed marker's fit from the last frame, moved to where this frame's
/// outline puts its centre. One round with the tight outlier limit, whose
/// first step is usually the last when the marker barely moved. `None`
/// when the start does not fit this frame's edges (the marker turned) or
/// the fit fails: callers refine from a closed-form candidate then.
pub fn refit_circle_pose(
    camera: &Camera,
    start: &CirclePose,
    points_px: &[RadialPoint],
) -> Option<CirclePose> {
    fit(camera, start, points_px, &[(0.3, 3)], CLOSE_START_PX)
}

/// Rounds of outlier rejection (limit floor in pixels, Gauss-Newton steps)
/// and fitting from `initial`; `None` also when the median misfit at the
/// start exceeds `close_px`.
fn fit(
    camera: &Camera,
    initial: &CirclePose,
    points_px: &[RadialPoint],
    rounds: &[(f64, usize)],
    close_px: f64,
) -> Option<CirclePose> {
    const MIN_POINTS: usize = 12;
    if points_px.len() < MIN_POINTS {
        return None;
    }
    let mut observations = Observations {
        points: points_px
            .iter()
            .map(|&((u, v), r)| {
                let (x, y) = camera.undistort(u, v);
                (x, y, r)
            })
            .collect(),
        focal: 0.5 * (camera.fx + camera.fy),
    };
    let mut circle = *initial;
    for (round, &(floor, steps)) in rounds.iter().enumerate() {
        let mut residual = vec![0.0; observations.points.len()];
        if !observations.residuals(&circle, &mut residual) {
            return None;
        }
        let mut sorted: Vec<f64> = residual.iter().map(|r| r.abs()).collect();
        let middle = sorted.len() / 2;
        let median = *sorted.select_nth_unstable_by(middle, f64::total_cmp).1;
        if round == 0 && median > close_px {
            return None;
        }
        let limit = (3.0 * median).max(floor);
        let mut keep = residual.iter().map(|r| r.abs() <= limit);
        observations.points.retain(|_| keep.next().unwrap_or(false));
        if observations.points.len() < MIN_POINTS {
            return None;
        }
        circle = solve(&observations, &circle, steps)?;
    }
    let facing = circle.normal.dot(&circle.center) < 0.0;
    (facing && circle.center.z > 0.0 && circle.center.iter().all(|x| x.is_finite()))
        .then_some(circle)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form derivatives agree with finite differences.
    #[test]
    fn linearised_residuals_match_finite_differences() {
        let circle = CirclePose {
            center: Vector3::new(0.12, -0.05, 0.9),
            normal: Vector3::new(0.3, -0.2, -1.0).normalize(),
        };
        let points: Vec<(f64, f64, f64)> = (0..24)
            .map(|k| {
                let t = k as f64 * 0.41;
                let r = [0.05, 0.03, 0.017][k % 3];
                (0.13 + 0.06 * t.cos(), -0.05 + 0.05 * t.sin(), r)
            })
            .collect();
        let observations = Observations {
            points,
            focal: 1000.0,
        };
        let n = observations.points.len();
        let basis = plane_basis(&circle.normal);
        let (mut residual, mut jacobian) = (Vec::new(), Vec::new());
        assert!(observations.linearise(&circle, &basis, |r, row| {
            residual.push(r);
            jacobian.push(*row);
        }));
        let mut plain = vec![0.0; n];
        assert!(observations.residuals(&circle, &mut plain));
        let (mut ahead, mut behind) = (vec![0.0; n], vec![0.0; n]);
        const DELTA: f64 = 1e-6;
        for k in 0..5 {
            let mut p = Params::zeros();
            p[k] = DELTA;
            assert!(observations.residuals(&moved(&circle, &basis, &p), &mut ahead));
            p[k] = -DELTA;
            assert!(observations.residuals(&moved(&circle, &basis, &p), &mut behind));
            for i in 0..n {
                assert!((residual[i] - plain[i]).abs() < 1e-9);
                let numeric = (ahead[i] - behind[i]) / (2.0 * DELTA);
                let scale = numeric.abs().max(1.0);
                assert!(
                    (jacobian[i][k] - numeric).abs() < 1e-4 * scale,
                    "point {i}, parameter {k}: {} against {numeric}",
                    jacobian[i][k]
                );
            }
        }
    }
}
