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
}

/// Gauss-Newton on the five pose parameters, halving a step that does not
/// lower the cost; the start is close (the closed-form pose, then the first
/// round's fit), so a few steps converge.
fn solve(
    observations: &Observations,
    initial: &CirclePose,
    basis: &(Vector3<f64>, Vector3<f64>),
    steps: usize,
) -> Option<Params> {
    let n = observations.points.len();
    let mut residual = vec![0.0; n];
    let mut trial = vec![0.0; n];
    let mut jacobian = vec![[0.0f64; 5]; n];
    let mut p = Params::zeros();
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    if !observations.residuals(initial, &mut residual) {
        return None;
    }
    let mut current = cost(&residual);
    const DELTA: f64 = 1e-7;
    for _ in 0..steps {
        for k in 0..5 {
            let mut q = p;
            q[k] += DELTA;
            if !observations.residuals(&moved(initial, basis, &q), &mut trial) {
                return None;
            }
            for (row, (s, r)) in jacobian.iter_mut().zip(trial.iter().zip(&residual)) {
                row[k] = (s - r) / DELTA;
            }
        }
        let mut normal = SMatrix::<f64, 5, 5>::zeros();
        let mut gradient = Params::zeros();
        for (row, r) in jacobian.iter().zip(&residual) {
            let j = Params::from_column_slice(row);
            normal += j * j.transpose();
            gradient += j * *r;
        }
        let Some(mut step) = normal.cholesky().map(|c| c.solve(&-gradient)) else {
            return Some(p);
        };
        let mut accepted = false;
        for _ in 0..4 {
            let q = p + step;
            if observations.residuals(&moved(initial, basis, &q), &mut trial)
                && cost(&trial) <= current
            {
                p = q;
                current = cost(&trial);
                std::mem::swap(&mut residual, &mut trial);
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        // Converged: the normal turns by less than 0.0006°, the centre
        // moves by less than 1e-6 of its distance.
        if !accepted || step.norm() < 1e-5 {
            break;
        }
    }
    Some(p)
}

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
    fit(camera, initial, points_px, &[(0.6, 3), (0.3, 1)], f64::INFINITY)
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
        let basis = plane_basis(&circle.normal);
        let p = solve(&observations, &circle, &basis, steps)?;
        circle = moved(&circle, &basis, &p);
    }
    let facing = circle.normal.dot(&circle.center) < 0.0;
    (facing && circle.center.z > 0.0 && circle.center.iter().all(|x| x.is_finite()))
        .then_some(circle)
}
