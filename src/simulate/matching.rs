//! Scoring a detector against the ground truth: which report is about
//! which true target (nearest centre within a reach, each report used
//! once), which reports are about nothing, and each pair's errors (ID,
//! centre, yaw, normal, rotation about the normal).
//!
//! Targets are the view's markers and printed squares ([`TrueTarget`]);
//! reports are our [`Detection`]s or any detector's [`Sighting`]s, so the
//! tests, the examples and the benchmarks score ours and other detectors
//! with the same rules.

use super::{GroundTruth, TrueMarker, TrueSquare};
use crate::detect::Detection;
use crate::math::angle::wrap_angle;
use nalgebra::{Matrix3, Vector3};

/// Anything found or true at an image position: what matching pairs up.
pub trait Located {
    /// Image position (u, v), pixels.
    fn centre(&self) -> (f64, f64);
}

/// One true target of a simulated view, a marker or a printed square, in
/// the terms scoring uses.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueTarget {
    /// Family ID of a marker (0 for a legacy one), the square's ID.
    pub id: u32,
    /// Projected true centre, pixels.
    pub u: f64,
    /// Row of the projected true centre, pixels.
    pub v: f64,
    /// Longest projected size, pixels: a marker's disc diameter, a
    /// square's side.
    pub size_px: f64,
    /// Facing the camera and wholly inside the frame.
    pub visible: bool,
    /// Image direction of the target's +x axis, atan2(dv, du), radians.
    pub yaw: f64,
    /// Rotation target → camera (columns +x, +y, normal).
    pub rotation: Matrix3<f64>,
    /// Centre in the camera frame, metres.
    pub position: Vector3<f64>,
}

fn matrix(rows: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| rows[i][j])
}

impl From<&TrueMarker> for TrueTarget {
    fn from(m: &TrueMarker) -> TrueTarget {
        TrueTarget {
            id: m.id,
            u: m.u,
            v: m.v,
            size_px: m.diameter_px,
            visible: m.visible,
            yaw: m.yaw,
            rotation: matrix(&m.rotation),
            position: Vector3::from(m.position),
        }
    }
}

impl From<&TrueSquare> for TrueTarget {
    fn from(q: &TrueSquare) -> TrueTarget {
        // The image of +x at the centre: from the left edge's midpoint to
        // the right edge's.
        let c = &q.corners;
        let du = (c[1][0] + c[2][0] - c[0][0] - c[3][0]) / 2.0;
        let dv = (c[1][1] + c[2][1] - c[0][1] - c[3][1]) / 2.0;
        TrueTarget {
            id: q.id,
            u: q.u,
            v: q.v,
            size_px: q.side_px,
            visible: q.visible,
            yaw: dv.atan2(du),
            rotation: matrix(&q.rotation),
            position: Vector3::from(q.position),
        }
    }
}

impl GroundTruth {
    /// The view's targets: its markers, in order, then its printed squares.
    pub fn targets(&self) -> Vec<TrueTarget> {
        let markers = self.markers.iter().map(TrueTarget::from);
        markers
            .chain(self.squares.iter().map(TrueTarget::from))
            .collect()
    }
}

/// What a report says of a target's ID.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdRead {
    /// The target's own ID.
    Right,
    /// No ID ("unknown").
    Unknown,
    /// Another ID: a guess that went wrong.
    Wrong,
}

impl TrueTarget {
    /// Unit normal of the printed face, camera frame.
    pub fn normal(&self) -> Vector3<f64> {
        self.rotation.column(2).into_owned()
    }

    /// Angle between the normal and the direction to the camera, radians
    /// (0 face-on).
    pub fn view_angle(&self) -> f64 {
        let to_camera = -self.position.normalize();
        self.normal().dot(&to_camera).clamp(-1.0, 1.0).acos()
    }

    /// What a reported ID (`None`: unknown; see [`Sighting::id`]) says of
    /// this target.
    pub fn id_read(&self, id: Option<u32>) -> IdRead {
        match id {
            None => IdRead::Unknown,
            Some(id) if id == self.id => IdRead::Right,
            Some(_) => IdRead::Wrong,
        }
    }

    /// Distance of a reported centre from the true one, pixels.
    pub fn centre_error(&self, (u, v): (f64, f64)) -> f64 {
        (u - self.u).hypot(v - self.v)
    }

    /// Signed error of a reported yaw, radians in [-π, π).
    pub fn yaw_error(&self, yaw: f64) -> f64 {
        wrap_angle(yaw - self.yaw)
    }

    /// Angle between a reported normal (any length) and the true one,
    /// radians.
    pub fn normal_error(&self, normal: &Vector3<f64>) -> f64 {
        normal
            .normalize()
            .dot(&self.normal())
            .clamp(-1.0, 1.0)
            .acos()
    }

    /// Signed error of a reported full rotation about the normal: the
    /// reported +x axis seen in the true target's frame, radians.
    pub fn roll_error(&self, rotation: &Matrix3<f64>) -> f64 {
        let x = self.rotation.transpose() * rotation.column(0).into_owned();
        x.y.atan2(x.x)
    }
}

/// One detector's report of a target, in the terms scoring uses: ours
/// (from a [`Detection`]) or another detector's, converted into our frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Sighting {
    /// Reported centre, pixels.
    pub u: f64,
    /// Row of the reported centre, pixels.
    pub v: f64,
    /// `None`: reported without an ID ("unknown"). Our detections' ID 0
    /// becomes `None`; another family's 0 (tag 0) stays an ID.
    pub id: Option<u32>,
    /// Image direction of the target's +x axis, radians.
    pub yaw: Option<f64>,
    /// Unit normal of the printed face, camera frame.
    pub normal: Option<Vector3<f64>>,
    /// Full orientation: rotation target → camera (columns +x, +y, normal).
    pub rotation: Option<Matrix3<f64>>,
    /// Centre in the camera frame, metres.
    pub position: Option<Vector3<f64>>,
}

impl From<&Detection> for Sighting {
    fn from(d: &Detection) -> Sighting {
        Sighting {
            u: d.u,
            v: d.v,
            id: (d.id != 0).then_some(d.id),
            yaw: d.yaw,
            normal: d.pose.as_ref().map(|p| p.rotation.column(2).into_owned()),
            rotation: d.pose.as_ref().map(|p| p.rotation),
            position: d.pose.as_ref().map(|p| p.position),
        }
    }
}

impl Located for Detection {
    fn centre(&self) -> (f64, f64) {
        (self.u, self.v)
    }
}

impl Located for Sighting {
    fn centre(&self) -> (f64, f64) {
        (self.u, self.v)
    }
}

impl Located for TrueMarker {
    fn centre(&self) -> (f64, f64) {
        (self.u, self.v)
    }
}

/// How far from a target's true centre a report may lie and still be
/// about it: `of_size` times the target's size plus `px` pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Share of the target's projected size ([`TrueTarget::size_px`]).
    pub of_size: f64,
    /// Pixels on top.
    pub px: f64,
}

impl Reach {
    /// A fixed radius in pixels, whatever the target's size.
    pub fn pixels(px: f64) -> Reach {
        Reach { of_size: 0.0, px }
    }

    /// The radius for a target `size_px` across.
    pub fn radius(&self, size_px: f64) -> f64 {
        self.of_size * size_px + self.px
    }
}

impl Default for Reach {
    /// A quarter of the target's size plus 2 px: a detector's centre is
    /// far closer, a neighbour's far away.
    fn default() -> Reach {
        Reach {
            of_size: 0.25,
            px: 2.0,
        }
    }
}

/// A report closer than this share of any true target's size (plus 2 px,
/// or the reach if larger) is about that target, not a false one: a
/// marker's card reaches 0.75 of its diameter from the centre, a blurred
/// outline a little past half of it.
const ON_TARGET: f64 = 0.6;

/// Reports paired with a view's targets by [`match_reports`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Matching {
    /// For each visible target, in order: its index among the targets and
    /// the index of the report paired with it, if any.
    pub pairs: Vec<(usize, Option<usize>)>,
    /// Reports about no target: paired with none and near none (visible
    /// or not).
    pub false_reports: Vec<usize>,
}

impl Matching {
    /// The visible targets no report was paired with.
    pub fn missed(&self) -> Vec<usize> {
        self.pairs
            .iter()
            .filter(|(_, report)| report.is_none())
            .map(|&(target, _)| target)
            .collect()
    }
}

/// Pairs reports with targets: for each target in order, the nearest
/// report not yet paired within `reach`. Hidden targets take their
/// reports too (a report of a marker cut by the frame's edge is neither
/// a find nor a false report) but are left out of the pairs.
pub fn match_reports<R: Located>(targets: &[TrueTarget], reports: &[R], reach: Reach) -> Matching {
    let mut used = vec![false; reports.len()];
    let mut pairs = Vec::new();
    for (t, target) in targets.iter().enumerate() {
        let radius = reach.radius(target.size_px);
        let best = reports
            .iter()
            .enumerate()
            .filter(|(k, r)| !used[*k] && target.centre_error(r.centre()) < radius)
            .min_by(|a, b| {
                target
                    .centre_error(a.1.centre())
                    .total_cmp(&target.centre_error(b.1.centre()))
            })
            .map(|(k, _)| k);
        if let Some(k) = best {
            used[k] = true;
        }
        if target.visible {
            pairs.push((t, best));
        }
    }
    let false_reports = (0..reports.len())
        .filter(|&k| {
            !used[k]
                && !targets.iter().any(|target| {
                    let near = (ON_TARGET * target.size_px + 2.0).max(reach.radius(target.size_px));
                    target.centre_error(reports[k].centre()) < near
                })
        })
        .collect();
    Matching {
        pairs,
        false_reports,
    }
}

/// The item nearest (u, v), if closer than `within` pixels.
pub fn nearest<T: Located>(items: &[T], (u, v): (f64, f64), within: f64) -> Option<&T> {
    let distance = |item: &T| {
        let (iu, iv) = item.centre();
        (iu - u).hypot(iv - v)
    };
    items
        .iter()
        .filter(|item| distance(item) < within)
        .min_by(|a, b| distance(a).total_cmp(&distance(b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target(id: u32, u: f64, v: f64, visible: bool) -> TrueTarget {
        TrueTarget {
            id,
            u,
            v,
            size_px: 40.0,
            visible,
            yaw: 0.0,
            rotation: Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
            position: Vector3::new(0.0, 0.0, 1.0),
        }
    }

    fn seen(u: f64, v: f64, id: Option<u32>) -> Sighting {
        Sighting {
            u,
            v,
            id,
            yaw: None,
            normal: None,
            rotation: None,
            position: None,
        }
    }

    #[test]
    fn each_report_pairs_once_with_the_nearest_target_and_the_rest_are_false() {
        let targets = [
            target(1, 100.0, 100.0, true),
            target(2, 112.0, 100.0, true),
            target(3, 300.0, 100.0, false),
            target(4, 500.0, 100.0, true),
        ];
        let reports = [
            seen(105.0, 100.0, Some(1)),
            seen(301.0, 100.0, None),
            seen(700.0, 100.0, Some(9)),
            seen(120.0, 100.0, Some(2)),
        ];
        let matched = match_reports(&targets, &reports, Reach::default());
        // The report at 105 is target 1's (nearer to 1 than to 2); target 2
        // takes the one at 120, not the one target 1 took.
        assert_eq!(matched.pairs, vec![(0, Some(0)), (1, Some(3)), (3, None)]);
        assert_eq!(matched.missed(), vec![3]);
        // The hidden target's report is no false one; the one far away is.
        assert_eq!(matched.false_reports, vec![2]);
        assert_eq!(targets[0].id_read(reports[0].id), IdRead::Right);
        assert_eq!(targets[0].id_read(Some(2)), IdRead::Wrong);
        assert_eq!(targets[0].id_read(None), IdRead::Unknown);
        assert_eq!(targets[0].centre_error(reports[0].centre()), 5.0);
    }

    #[test]
    fn a_report_on_a_targets_card_is_not_false_but_beyond_it_is() {
        let targets = [target(1, 100.0, 100.0, true)];
        // Reach 12 px, the card 26 px (0.6 of 40, plus 2).
        let on_card = [seen(100.0, 113.0, None), seen(100.0, 125.0, None)];
        let matched = match_reports(&targets, &on_card, Reach::default());
        assert_eq!(matched.pairs, vec![(0, None)]);
        assert!(matched.false_reports.is_empty());
        let beyond = [seen(100.0, 127.0, None)];
        assert_eq!(
            match_reports(&targets, &beyond, Reach::default()).false_reports,
            vec![0]
        );
        assert_eq!(Reach::pixels(5.0).radius(80.0), 5.0);
        let near = nearest(&on_card, (100.0, 100.0), 20.0);
        assert_eq!(near.map(|s| s.v), Some(113.0));
        assert!(nearest(&on_card, (100.0, 100.0), 13.0).is_none());
    }

    #[test]
    fn errors_are_signed_and_wrapped() {
        let t = TrueTarget {
            yaw: 3.1,
            ..target(1, 0.0, 0.0, true)
        };
        assert!((t.yaw_error(-3.1) - (std::f64::consts::TAU - 6.2)).abs() < 1e-12);
        let tilted = Vector3::new(0.0, (0.1f64).sin(), -(0.1f64).cos());
        assert!((t.normal_error(&(2.0 * tilted)) - 0.1).abs() < 1e-12);
        // Turned by 0.2 rad about the normal (-z here): +x goes to -y in
        // the camera, +y in the target's frame.
        let (s, c) = 0.2f64.sin_cos();
        let turned = t.rotation * Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        assert!((t.roll_error(&turned) - 0.2).abs() < 1e-12);
        assert!(t.view_angle().abs() < 1e-12);
    }
}
