//! The pose stage: a candidate's 6-DoF pose from its outline and the
//! ring's edges, with a calibrated camera and the marker's diameter.
//!
//! The outline gives two circle poses ([`crate::pose`]); which one is the
//! marker's is told by where the ring shows the marker's centre, by the
//! normal the marker's track settled on, by last frame's fit, or by the
//! inner white edges. The chosen pose is refined on the outer and inner
//! edges together (away from the ring's sector sides), its rotation taken
//! from the ring's yaw and measured again on the rectified ring
//! (`rectify.rs`). A followed marker whose code is known is posed from
//! its track's fit, its rotation measured on the code's edges at once.

use nalgebra::Vector3;

use super::ring::RingRead;
use super::segment::Gray;
use super::tracking::track::{Fitted, PoseMemory};
use super::{ellipse, rectify, Candidate, Detection, Detector, Workspace};
use crate::camera::Camera;
use crate::family::Family;
use crate::geometry::{sector_is_black, sector_width, Design, WHYCODE_WHITE_RATIO};
use crate::math::angle;
use crate::pose::{self, CirclePose, Pose};

/// What the ring reading and the marker's track tell the pose stage.
#[derive(Debug, Clone, Copy)]
struct PoseHints {
    yaw: Option<f64>,
    axis_point: Option<(f64, f64)>,
    centre_estimate: Option<(f64, f64)>,
    settled_normal: Option<Vector3<f64>>,
    /// The circle pose the track fitted last frame.
    previous: Option<Fitted>,
    /// An unsure pick between the candidates is made afresh this frame.
    recheck: bool,
    /// Bit count of the code ring, whose sector sides break its circles.
    bits: Option<u32>,
    /// The ring's code, whose sectors' colours say on which of the ring's
    /// circles each shows an edge.
    code: Option<u32>,
}

/// What the pose stage found for a candidate.
#[derive(Debug, Clone, Copy)]
pub(super) struct Posed {
    pose: Pose,
    /// The normal was told apart from the other candidate with confidence.
    settled: bool,
    /// The circle pose fitted to the edges (before the rotation was
    /// measured), where the next frame's fit starts.
    fitted: Fitted,
}

/// A followed marker's pose, its rotation measured on the known code's
/// edges.
#[derive(Debug, Clone, Copy)]
pub(super) struct FollowedPose {
    pub(super) posed: Posed,
    /// Image direction of +x at the projected centre.
    pub(super) yaw: f64,
}

impl Detector {
    /// The pose of candidate `c` with the camera and diameter configured
    /// (none without), from what the ring read (`ring`) and what the
    /// detection says after the ID filter (`d`'s yaw, bits and code); a
    /// followed marker's pose comes `followed` already. Puts the pose in
    /// `d`, with the centre and yaw it tells; returns what the track keeps
    /// for the next frame.
    pub(super) fn measure_pose(
        &self,
        ws: &mut Workspace,
        gray: Gray<'_>,
        c: &Candidate,
        d: &mut Detection,
        ring: &RingRead,
        followed: Option<Posed>,
    ) -> PoseMemory {
        let (Some(camera), Some(diameter)) = (self.frame_camera, self.config.diameter_m) else {
            return PoseMemory::default();
        };
        let family_bits = self.config.target.family().map(Family::bits);
        let hints = PoseHints {
            yaw: d.yaw,
            axis_point: ring.axis_point,
            centre_estimate: ring.centre_estimate,
            settled_normal: c.track.and_then(|i| self.tracks[i].normal),
            previous: c.track.and_then(|i| self.tracks[i].fitted),
            recheck: c.track.is_none_or(|i| self.recheck(i)),
            bits: d.bits.or(family_bits),
            code: d.code,
        };
        let posed = match followed {
            Some(posed) => Some(posed),
            None => self.pose(ws, &camera, diameter / 2.0, gray, c, hints),
        };
        d.pose = posed.map(|p| p.pose);
        let memory = posed.map_or_else(PoseMemory::default, |posed| PoseMemory {
            settled_normal: posed
                .settled
                .then(|| posed.pose.rotation.column(2).into_owned()),
            fitted: Some(posed.fitted),
        });
        // A followed pose's rotation was measured on the code's edges
        // already; a ring of another family's count has no member's edges.
        let member_code = d
            .code
            .filter(|_| followed.is_none() && (d.bits.is_none() || d.bits == family_bits));
        if let (Some(pose), Some(code), Some(bits)) = (&d.pose, member_code, family_bits) {
            if let Some(better) =
                rectify::refine_rotation(gray, &camera, pose, diameter / 2.0, bits, code)
            {
                d.pose = Some(better);
            }
        }
        // Under perspective the centre of the outer ellipse is not the
        // image of the marker's centre, nor is the ellipse-based yaw
        // the direction of +x at that centre: the pose knows both.
        if let Some(pose) = &d.pose {
            if let Some((u, v)) = camera.project(&pose.position) {
                d.u = u;
                d.v = v;
            }
            if d.yaw.is_some() {
                d.yaw = pose.image_yaw(&camera).or(d.yaw);
            }
        }
        memory
    }

    /// The pose of a followed marker whose code is known, its rotation
    /// measured on the rectified ring from where last frame's yaw puts the
    /// code's edges; every edge must show with the code's polarity, which
    /// confirms the code as [`rectify::follow_ring`] would. None without a
    /// camera and a diameter, or when the edges do not show (then the ring
    /// is followed or read as for a marker without a pose).
    pub(super) fn follow_pose(
        &self,
        ws: &mut Workspace,
        gray: Gray<'_>,
        c: &Candidate,
        index: usize,
    ) -> Option<FollowedPose> {
        let (camera, diameter) = (self.frame_camera?, self.config.diameter_m?);
        let radius_m = diameter / 2.0;
        let track = &self.tracks[index];
        let bits = self.config.target.family().map(Family::bits)?;
        let (code, previous_yaw) = (track.code?, track.yaw?);
        let hints = PoseHints {
            yaw: Some(previous_yaw),
            axis_point: None,
            centre_estimate: None,
            settled_normal: track.normal,
            previous: track.fitted,
            recheck: self.recheck(index),
            bits: Some(bits),
            code: Some(code),
        };
        let mut posed = self.pose(ws, &camera, radius_m, gray, c, hints)?;
        posed.pose = rectify::refine_rotation(gray, &camera, &posed.pose, radius_m, bits, code)?;
        let yaw = posed.pose.image_yaw(&camera)?;
        Some(FollowedPose { posed, yaw })
    }

    /// Whether track `index` makes its unsure pick between the pose
    /// candidates afresh this frame.
    fn recheck(&self, index: usize) -> bool {
        (self.tracks[index].hits as usize + index).is_multiple_of(RECHECK_FRAMES)
    }

    /// Position and normal from the outer edge, the two-fold ambiguity
    /// decided by where the ring shows the marker's centre, else by the
    /// normal this marker's track settled on, else by the normal it was
    /// fitted with last frame, else by the inner white edges; then refined
    /// on the outer and inner edges together (from last frame's fit when
    /// that still fits); the rotation from the yaw.
    fn pose(
        &self,
        ws: &mut Workspace,
        camera: &Camera,
        radius_m: f64,
        gray: Gray<'_>,
        c: &Candidate,
        hints: PoseHints,
    ) -> Option<Posed> {
        let PoseHints {
            yaw,
            axis_point,
            centre_estimate,
            settled_normal,
            previous,
            recheck,
            bits,
            code,
        } = hints;
        // The outline was fitted to the edge points in pixels; without lens
        // distortion its conic maps exactly into the camera's coordinates,
        // and fitting the points again there (a fifteenth of a posed
        // marker's time) gives the same cone.
        let candidates = if camera.has_distortion() {
            pose::circle_poses_from_points(camera, &c.edge, radius_m)
                .or_else(|| pose::try_circle_poses(camera, &c.outer, radius_m))?
        } else {
            pose::try_circle_poses(camera, &c.outer, radius_m)?
        };
        let by_centre = centre_estimate
            .and_then(|measured| pose::choose_by_centre_estimate(camera, &candidates, measured));
        let by_track = || pose::choose_by_settled_normal(&candidates, &settled_normal?);
        let settled = by_centre.or_else(by_track);
        // The candidate nearer the normal fitted last frame. It decides
        // near face-on, where the two lie too close together for the track
        // to settle: there they differ by less than the fit corrects, and
        // the inner edges' test (a fifth of a posed marker's time) is
        // spared. Farther apart, where neither the ring's centre nor the
        // track settled the pick (a small or distant marker's view is
        // nearly affine, and the inner edges' test all but a coin toss),
        // the pick is kept between rechecks: an unsure pick (a marker cut
        // by the border, say) outlives its frame by a few frames at most.
        let nearer_previous = previous.map(|p| {
            let turn = |k: usize| candidates[k].normal.angle(&p.circle.normal);
            usize::from(turn(1) < turn(0))
        });
        let close = candidates[0].normal.angle(&candidates[1].normal) < CLOSE_CANDIDATES_RAD;
        let by_previous = nearer_previous.filter(|_| close || !recheck);
        let design = self.config.target.design();
        let mut errors = [0.0f64; 2];
        if settled.is_none() && by_previous.is_none() {
            let mid = (c.black + c.white) / 2.0;
            for &ratio in design.inner_edge_ratios() {
                ellipse::inner_edge_points(
                    gray,
                    &c.outer,
                    ratio,
                    mid,
                    &mut ws.spokes,
                    &mut ws.inner_scratch,
                );
                let found = pose::inner_edge_errors(
                    camera,
                    &candidates,
                    &ws.inner_scratch,
                    ratio * radius_m,
                );
                for (error, e) in errors.iter_mut().zip(found) {
                    *error += e;
                }
            }
        }
        let pick = settled
            .or(by_previous)
            .unwrap_or(usize::from(errors[1] < errors[0]));
        let chosen = candidates[pick];
        let rough = pose::full_pose_from_ring(camera, &chosen, yaw, axis_point);
        // The concentric edges sharpen the normal (see
        // `pose::refine_circle_pose`). A WhyCode ring's circles break
        // where its sectors meet; the ring's rotation says where, and
        // its code which circle each sector borders.
        let sector_sides = match design {
            Design::WhyCon => Some(None),
            Design::WhyCode => bits
                .filter(|_| yaw.is_some())
                .map(|bits| Some(RingSides::new(camera, &rough, bits, code))),
        };
        let mut points = std::mem::take(&mut ws.pose_points);
        points.clear();
        let min_rise = 0.5 * (c.white - c.black);
        let rays = if self.config.fine_edges {
            ellipse::EdgeRays::FINE
        } else {
            ellipse::EdgeRays::POSE
        };
        let everywhere = |_: (f64, f64)| true;
        ellipse::concentric_edge_points(
            gray,
            &c.outer,
            1.0,
            min_rise,
            rays,
            everywhere,
            &mut ws.spokes,
            &mut ws.inner_scratch,
        );
        points.extend(ws.inner_scratch.iter().map(|&p| (p, radius_m)));
        if let Some(sides) = sector_sides {
            for &ratio in design.inner_edge_ratios() {
                let radius = ratio * radius_m;
                // The white centre meets the black sectors, the black
                // annulus the white ones.
                let edge_on_black = ratio < WHYCODE_WHITE_RATIO;
                let wanted = |p: (f64, f64)| {
                    sides
                        .as_ref()
                        .is_none_or(|s| s.shows_edge(p, radius, edge_on_black))
                };
                ellipse::concentric_edge_points(
                    gray,
                    &c.outer,
                    ratio,
                    min_rise,
                    rays,
                    wanted,
                    &mut ws.spokes,
                    &mut ws.inner_scratch,
                );
                points.extend(ws.inner_scratch.iter().map(|&p| (p, radius)));
            }
        }
        // Last frame's fit, moved as far as the closed-form centre moved,
        // is a closer start than the closed-form candidate when it lies on
        // the same side (a marker that stood still starts where its fit
        // ends).
        let refit = previous
            .filter(|_| nearer_previous == Some(pick))
            .map(|p| CirclePose {
                center: p.circle.center + (chosen.center - p.closed_form_centre),
                normal: p.circle.normal,
            })
            .filter(|start| start.normal.dot(&start.center) < 0.0)
            .and_then(|start| pose::refit_circle_pose(camera, &start, &points));
        let circle = refit
            .or_else(|| pose::refine_circle_pose(camera, &chosen, &points))
            .unwrap_or(chosen);
        ws.pose_points = points;
        Some(Posed {
            pose: pose::full_pose_from_ring(camera, &circle, yaw, axis_point),
            settled: settled.is_some(),
            fitted: Fitted {
                circle,
                closed_form_centre: chosen.center,
            },
        })
    }
}

/// Every this many frames a followed marker's unsure pick between the pose
/// candidates is made afresh by the inner edges' test (markers take turns,
/// so each frame rechecks a share of them).
const RECHECK_FRAMES: usize = 4;

/// Angle between the two candidates' normals under which last frame's
/// fit picks between them: where a track's settled normal could not (see
/// `pose::choose_by_settled_normal`, whose margin this is).
const CLOSE_CANDIDATES_RAD: f64 = 0.1;

/// Where a WhyCode ring's circles show edges, for a rough pose: away from
/// the sectors' sides, and (with the code known) only where a sector of the
/// colour that borders the circle lies.
struct RingSides {
    camera: Camera,
    /// Maps a pixel's viewing ray to the direction, in the marker plane's
    /// x-y axes, of the point where it meets the plane (first two rows).
    to_plane: [Vector3<f64>; 2],
    /// The same map from a pixel (u, v, 1), the camera's intrinsics folded
    /// in, where the lens has no distortion to undo.
    from_pixel: Option<[Vector3<f64>; 2]>,
    bits: u32,
    code: Option<u32>,
    /// Metres of marker plane per pixel near the marker.
    pixel_m: f64,
}

impl RingSides {
    fn new(camera: &Camera, pose: &Pose, bits: u32, code: Option<u32>) -> RingSides {
        // A ray r meets the plane at t·r, t = n·c / n·r > 0, which is
        // Rᵀ(t·r - c) in marker axes; times -n·r (positive for a plane
        // facing the camera) that is ((Rᵀc) nᵀ - (n·c) Rᵀ) r: the same
        // direction, without a division.
        let (rotation, centre) = (pose.rotation, pose.position);
        let normal = rotation.column(2).into_owned();
        let local_centre = rotation.transpose() * centre;
        let along = normal.dot(&centre);
        let map = local_centre * normal.transpose() - along * rotation.transpose();
        let to_plane = [0, 1].map(|i| map.row(i).transpose());
        // The ray of pixel (u, v) is ((u - cx) / fx, (v - cy) / fy, 1).
        let from_pixel = (!camera.has_distortion()).then(|| {
            to_plane.map(|t| {
                let (a, b) = (t.x / camera.fx, t.y / camera.fy);
                Vector3::new(a, b, t.z - a * camera.cx - b * camera.cy)
            })
        });
        RingSides {
            camera: *camera,
            to_plane,
            from_pixel,
            bits,
            code,
            pixel_m: centre.z / camera.fx,
        }
    }

    /// Whether a ring circle of radius `radius_m` shows an edge at pixel
    /// `point` whose sample did not see a sector's side (two pixels of
    /// arc clear of it), and, with a code, where its sector is black
    /// (`on_black`) or white.
    fn shows_edge(&self, point: (f64, f64), radius_m: f64, on_black: bool) -> bool {
        let (x, y) = match &self.from_pixel {
            Some([tx, ty]) => {
                let pixel = Vector3::new(point.0, point.1, 1.0);
                (tx.dot(&pixel), ty.dot(&pixel))
            }
            None => {
                let ray = self.camera.ray(point.0, point.1);
                (self.to_plane[0].dot(&ray), self.to_plane[1].dot(&ray))
            }
        };
        let width = sector_width(self.bits);
        // A whole turn is a whole number of sectors: no need to bring the
        // angle into [0, 2π) first.
        let turns = rough_atan2(y, x) / width;
        let index = angle::floor_to_int(turns);
        let into = width * (turns - index as f64);
        let arc_m = radius_m * into.min(width - into);
        let clear = arc_m > 2.0 * self.pixel_m;
        clear
            && self.code.is_none_or(|code| {
                let k = angle::wrap_index(index, 2 * i64::from(self.bits)) as u32;
                sector_is_black(self.bits, code, k) == on_black
            })
    }
}

/// atan2 to within 2e-5 radians (Hastings' polynomial on the octant): the
/// sector-side test needs two pixels of arc, a thousand times coarser,
/// and the library call was a tenth of a followed marker's pose.
fn rough_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (low, high) = (ax.min(ay), ax.max(ay));
    if high == 0.0 {
        return 0.0;
    }
    let a = low / high;
    let s = a * a;
    let mut r =
        a * (0.999_866 + s * (-0.330_299_5 + s * (0.180_141 + s * (-0.085_133 + s * 0.020_835_1))));
    if ay > ax {
        r = std::f64::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = std::f64::consts::PI - r;
    }
    if y < 0.0 {
        r = -r;
    }
    r
}

#[cfg(test)]
mod tests {
    #[test]
    fn rough_atan2_is_within_its_stated_error_all_round() {
        for k in 0..=3600 {
            let angle = -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / 3600.0;
            for length in [1e-3, 1.0, 250.0] {
                let (y, x) = (length * angle.sin(), length * angle.cos());
                let error = super::rough_atan2(y, x) - y.atan2(x);
                // The same angle either side of ±π.
                let error = (error + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                assert!(error.abs() < 2e-5, "{angle}: {error}");
            }
        }
    }
}
