//! Choosing between the two circle poses that cast the same outer ellipse.
//!
//! Every witness here compares what each candidate predicts with something
//! measured in the image: a concentric circle's ellipse or edge points, the
//! ring's estimate of where the marker's centre projects, or the normal a
//! tracked marker settled on in earlier frames.

use nalgebra::Vector3;

use super::{intersect_plane, project_circle, CirclePose};
use crate::camera::Camera;
use crate::math::Ellipse;

/// Resolve the two-fold ambiguity with a concentric inner circle (radius
/// `inner_ratio · radius_m`) whose image ellipse was measured: each candidate
/// predicts where the inner circle's image must lie, and the one whose
/// prediction is closer to the measured inner ellipse centre wins.
///
/// Returns the chosen index and the margin: how much farther (pixels) the
/// rejected candidate's prediction is from the measurement. Compare the
/// margin with the measurement noise of the inner ellipse centre; a margin
/// below it means the choice is a guess. The cue is a perspective effect;
/// measured on exact projections it is about
/// `(1 - inner_ratio²) · a² / f · sin(2·tilt)` pixels (a = outer semi-major
/// axis in pixels, f = focal length in pixels, tilt = angle between the
/// normal and the line of sight); `ambiguity_margin_follows_the_documented_rule_of_thumb`
/// (tests/integration/pose_synthetic.rs) checks it. The wrong candidate's normal is off by twice the tilt. The cue vanishes
/// for small tilts (where the candidates converge to one) and for
/// markers far away (where the image is nearly affine and the two normals
/// are mirror images about the viewing ray that no image of concentric
/// circles can tell apart).
pub fn choose_by_inner_circle(
    camera: &Camera,
    candidates: &[CirclePose; 2],
    inner: &Ellipse,
    inner_ratio: f64,
    radius_m: f64,
) -> (usize, f64) {
    let error = |candidate: &CirclePose| {
        project_circle(camera, candidate, inner_ratio * radius_m)
            .map(|predicted| (predicted.u - inner.u).hypot(predicted.v - inner.v))
            .filter(|e| e.is_finite())
    };
    pick_smaller(error(&candidates[0]), error(&candidates[1]))
}

/// Resolve the ambiguity from image points known to lie on a circle of
/// radius `radius_on_marker_m` around the marker centre (e.g. edge points of
/// the white inner disc). Each point's viewing ray is intersected with the
/// candidate's plane; the candidate whose intersections lie closer to that
/// radius wins.
///
/// Returns the chosen index and the margin: the difference of the two RMS
/// radial residuals, in metres.
pub fn choose_by_circle_points(
    camera: &Camera,
    candidates: &[CirclePose; 2],
    points_px: &[(f64, f64)],
    radius_on_marker_m: f64,
) -> (usize, f64) {
    let error = |candidate: &CirclePose| {
        radial_rms(
            camera,
            candidate,
            points_px.iter().map(|&p| (p, radius_on_marker_m)),
        )
    };
    pick_smaller(error(&candidates[0]), error(&candidates[1]))
}

/// An image point (u, v) and the radius (metres) of the marker circle it
/// lies on.
pub type RadialPoint = ((f64, f64), f64);

/// [`choose_by_circle_points`] for points on several concentric circles at
/// once. On a WhyCode marker the code ring's borders are only visible in
/// part: the 0.6 R border where a sector is white, the 0.343 R border where
/// it is black; together they go all the way round.
pub fn choose_by_radial_points(
    camera: &Camera,
    candidates: &[CirclePose; 2],
    points: &[RadialPoint],
) -> (usize, f64) {
    let error = |candidate: &CirclePose| radial_rms(camera, candidate, points.iter().copied());
    pick_smaller(error(&candidates[0]), error(&candidates[1]))
}

/// RMS difference (metres) between `radius_on_marker_m` and the distances
/// from the candidate's centre of the points where the pixels' viewing rays
/// meet the candidate's plane. `None` if no point meets the plane in front
/// of the camera.
pub fn circle_point_rms(
    camera: &Camera,
    circle: &CirclePose,
    points_px: &[(f64, f64)],
    radius_on_marker_m: f64,
) -> Option<f64> {
    radial_rms(
        camera,
        circle,
        points_px.iter().map(|&p| (p, radius_on_marker_m)),
    )
}

fn radial_rms(
    camera: &Camera,
    circle: &CirclePose,
    points: impl Iterator<Item = RadialPoint>,
) -> Option<f64> {
    let mut sum = 0.0;
    let mut count = 0usize;
    for ((u, v), radius) in points {
        if let Some(hit) = intersect_plane(camera, circle, u, v) {
            sum += ((hit - circle.center).norm() - radius).powi(2);
            count += 1;
        }
    }
    (count > 0).then(|| (sum / count as f64).sqrt())
}

fn pick_smaller(first: Option<f64>, second: Option<f64>) -> (usize, f64) {
    match (first, second) {
        (Some(a), Some(b)) if b < a => (1, a - b),
        (Some(a), Some(b)) => (0, b - a),
        (None, Some(_)) => (1, f64::INFINITY),
        (Some(_), None) => (0, f64::INFINITY),
        (None, None) => (0, 0.0),
    }
}

/// Least image distance between the two candidates' centres at which the
/// ring's centre estimate decides between them; closer, the estimate's
/// scatter under blur and noise could pick either.
const CENTRE_SEPARATION_PX: f64 = 0.3;

/// How much closer (as a fraction of the candidates' separation) the
/// estimate must lie to one candidate's centre: small enough that blurred,
/// noisy tilted markers are still decided here rather than by the weaker
/// inner-edge test. Chosen on simulated 12-bit markers at 8-60° tilt;
/// `tilted_markers_of_8_to_16_bits_give_ids_yaw_and_pose`
/// (tests/integration/detect_simulated.rs) guards it.
const CENTRE_MARGIN: f64 = 0.2;

/// How much nearer (radians) one candidate's normal must be to the normal a
/// track settled on than the other's, for the track to decide.
const SETTLED_NORMAL_MARGIN: f64 = 0.1;

/// Both candidates cast the same outer ellipse, but each puts the marker's
/// centre at a different image point, and the ring's radial edges all run
/// through the real one (`measured`, pixels). Under blur and noise this is a
/// far steadier witness than the inner edges' sub-pixel positions, as long
/// as the two points are apart by more than the estimate's own scatter.
/// `None` when it cannot tell.
pub fn choose_by_centre_estimate(
    camera: &Camera,
    candidates: &[CirclePose; 2],
    measured: (f64, f64),
) -> Option<usize> {
    let distance = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1);
    let first = camera.project(&candidates[0].center)?;
    let second = camera.project(&candidates[1].center)?;
    let apart = distance(first, second);
    let (m0, m1) = (distance(first, measured), distance(second, measured));
    (apart >= CENTRE_SEPARATION_PX && (m0 - m1).abs() >= CENTRE_MARGIN * apart)
        .then_some(usize::from(m1 < m0))
}

/// A followed marker turns little between frames, while the two candidates
/// lie twice its tilt apart: the one nearer the normal `settled` earlier is
/// the same solution, and no edge needs sampling. `None` when it cannot tell.
pub fn choose_by_settled_normal(
    candidates: &[CirclePose; 2],
    settled: &Vector3<f64>,
) -> Option<usize> {
    let turn = |k: usize| candidates[k].normal.angle(settled);
    let (t0, t1) = (turn(0), turn(1));
    ((t0 - t1).abs() >= SETTLED_NORMAL_MARGIN).then_some(usize::from(t1 < t0))
}

/// Each candidate's squared radial misfit (metres², summed over the points)
/// to edge points of a concentric circle of radius `radius_on_marker_m`: the
/// detector adds these up over the marker's inner edges and keeps the
/// smaller total.
pub fn inner_edge_errors(
    camera: &Camera,
    candidates: &[CirclePose; 2],
    points_px: &[(f64, f64)],
    radius_on_marker_m: f64,
) -> [f64; 2] {
    candidates.map(|candidate| {
        circle_point_rms(camera, &candidate, points_px, radius_on_marker_m)
            .map_or(0.0, |r| r * r * points_px.len() as f64)
    })
}
