//! The full 6-DoF pose: a circle pose completed with the in-plane rotation
//! the ring gives, and the helpers that project marker points with it.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use super::{
    choose_by_inner_circle, intersect_plane, plane_basis, projected_center, try_circle_poses,
    CirclePose,
};
use crate::camera::Camera;
use crate::math::Ellipse;

/// Full 6-DoF pose of a marker: marker → camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Marker centre in the camera frame (metres).
    pub position: Vector3<f64>,
    /// Columns are the marker's x, y, z axes in the camera frame.
    pub rotation: Matrix3<f64>,
    /// The same rotation as a unit quaternion [x, y, z, w], w >= 0.
    pub quaternion: [f64; 4],
}

impl Pose {
    /// The rotation as a Rodrigues vector (the axis scaled by the angle,
    /// radians): OpenCV's `rvec`, from the quaternion, which is unit.
    pub fn rotation_vector(&self) -> Vector3<f64> {
        let [x, y, z, w] = self.quaternion;
        UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(w, x, y, z)).scaled_axis()
    }

    /// Pose from a position and a rotation matrix (re-orthonormalised).
    pub fn new(position: Vector3<f64>, rotation: Matrix3<f64>) -> Pose {
        let orthonormal = (rotation.transpose() * rotation - Matrix3::identity()).norm() < 1e-9
            && rotation.determinant() > 0.0;
        let q = if orthonormal {
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation))
        } else {
            UnitQuaternion::from_matrix(&rotation)
        };
        let q = if q.w < 0.0 {
            UnitQuaternion::new_unchecked(-q.into_inner())
        } else {
            q
        };
        Pose {
            position,
            rotation: *Rotation3::from(q).matrix(),
            quaternion: [q.i, q.j, q.k, q.w],
        }
    }

    /// A point given in the marker frame (metres), in the camera frame.
    pub fn marker_to_camera(&self, marker_point: &Vector3<f64>) -> Vector3<f64> {
        self.position + self.rotation * marker_point
    }

    /// The marker's +z axis (out of the printed face) in the camera frame.
    pub fn normal(&self) -> Vector3<f64> {
        self.rotation.column(2).into_owned()
    }

    /// The circle part of the pose.
    pub fn circle(&self) -> CirclePose {
        CirclePose {
            center: self.position,
            normal: self.normal(),
        }
    }

    /// Angle in radians of the rotation taking this pose's orientation to
    /// the other's.
    pub fn rotation_angle_to(&self, other: &Pose) -> f64 {
        let relative = self.rotation.transpose() * other.rotation;
        ((relative.trace() - 1.0) * 0.5).clamp(-1.0, 1.0).acos()
    }

    /// Roll, pitch, yaw (radians) with rotation = Rz(yaw)·Ry(pitch)·Rx(roll),
    /// in the camera (optical) frame.
    pub fn roll_pitch_yaw(&self) -> (f64, f64, f64) {
        Rotation3::from_matrix_unchecked(self.rotation).euler_angles()
    }

    /// The same pose spun by `angle` (radians) about the marker's own +z
    /// axis: the new +x axis is the old marker direction at angle `angle`
    /// (counter-clockwise as seen looking at the printed face).
    ///
    /// Useful for ring reading under perspective: build a provisional pose
    /// with [`full_pose_from_yaw`]`(.., 0.0)`, sample the ring at marker
    /// angles through [`project_marker_point`], and spin the pose by the
    /// decoded rotation.
    pub fn spun(&self, angle: f64) -> Pose {
        let spin = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
        Pose::new(self.position, self.rotation * spin.matrix())
    }

    /// Image direction of the marker's +x axis at its centre, atan2(dv, du)
    /// (the detector's `yaw`). `None` if the centre does not project.
    pub fn image_yaw(&self, camera: &Camera) -> Option<f64> {
        // Small enough that lens distortion does not bend the step.
        let step = 1e-6 * self.position.norm().max(1e-9);
        let (u0, v0) = camera.project(&self.position)?;
        let (u1, v1) = camera.project(&(self.position + step * self.rotation.column(0)))?;
        Some((v1 - v0).atan2(u1 - u0))
    }
}

/// Complete a circle pose with the in-plane rotation, given an image point
/// on the marker's +x axis (any distance from the centre, e.g. the ring
/// sample at marker angle 0): its viewing ray is intersected with the
/// marker plane, +x points from the centre to that intersection, +z is the
/// circle normal and +y = z × x.
///
/// If the pixel's ray misses the plane (or hits the centre), the image
/// direction from the projected centre to the pixel is used instead.
pub fn full_pose(camera: &Camera, circle: &CirclePose, x_axis_pixel: (f64, f64)) -> Pose {
    let normal = circle.normal.normalize();
    let in_plane = |d: Vector3<f64>| d - normal * normal.dot(&d);
    let (u, v) = x_axis_pixel;
    let from_intersection =
        intersect_plane(camera, circle, u, v).map(|hit| in_plane(hit - circle.center));
    let direction = match from_intersection {
        Some(d) if d.norm() > 1e-12 * circle.center.norm() => d,
        _ => {
            let towards = camera.ray(u, v).normalize() - circle.center.normalize();
            let d = in_plane(towards);
            if d.norm() > 1e-15 {
                d
            } else {
                plane_basis(&normal).0
            }
        }
    };
    let x = direction.normalize();
    let y = normal.cross(&x);
    Pose::new(circle.center, Matrix3::from_columns(&[x, y, normal]))
}

/// Complete a circle pose from the image direction of the marker's +x axis
/// at its centre (atan2(dv, du), the detector's `yaw`); the inverse of
/// [`Pose::image_yaw`]. Without lens distortion the image of the marker's
/// x axis is a straight line through the *projected true centre* (see
/// [`projected_center`]), not through the ellipse centre, so the direction
/// is taken from there.
pub fn full_pose_from_yaw(camera: &Camera, circle: &CirclePose, image_yaw: f64) -> Pose {
    // The image of the axis is curved by lens distortion; a tiny step takes
    // its tangent at the centre, which is what `image_yaw` measures. The
    // ray intersection stays accurate to ~1e-11 at this step.
    const STEP_PX: f64 = 0.01;
    let (u, v) = projected_center(camera, circle).unwrap_or((camera.cx, camera.cy));
    let (s, c) = image_yaw.sin_cos();
    full_pose(camera, circle, (u + STEP_PX * c, v + STEP_PX * s))
}

/// The pose stage in one call, as the detector uses it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEstimate {
    /// The chosen pose (marker → camera).
    pub pose: Pose,
    /// The other solution of the two-fold ambiguity, completed the same way.
    pub alternative: Pose,
    /// How much better the chosen candidate explains the inner ellipse
    /// (pixels, see [`choose_by_inner_circle`]); 0 without an inner ellipse.
    pub ambiguity_margin_px: f64,
    /// Image position of the true marker centre (differs from the ellipse
    /// centre under perspective).
    pub center_px: (f64, f64),
}

/// Pose of a marker from its outer ellipse (outer radius `radius_m`),
/// optionally disambiguated by a concentric inner ellipse (`inner` with its
/// radius relative to the outer one, e.g. the legacy WhyCon white disc at
/// 50/122), and completed with the image direction of the marker's +x axis
/// (`image_yaw`, atan2(dv, du), e.g. from the code ring).
///
/// Without an inner ellipse the first candidate is returned (a coin toss
/// unless the marker is seen nearly face-on). Without a yaw (legacy
/// markers) the +x axis is placed towards image +u: roll and pitch are then
/// meaningful, the rotation about the normal is not. `None` for an invalid
/// ellipse.
pub fn estimate_pose(
    camera: &Camera,
    outer: &Ellipse,
    radius_m: f64,
    inner: Option<(&Ellipse, f64)>,
    image_yaw: Option<f64>,
) -> Option<PoseEstimate> {
    let candidates = try_circle_poses(camera, outer, radius_m)?;
    let (chosen, margin) = match inner {
        Some((ellipse, ratio)) if ellipse.is_valid() => {
            choose_by_inner_circle(camera, &candidates, ellipse, ratio, radius_m)
        }
        _ => (0, 0.0),
    };
    let yaw = image_yaw.unwrap_or(0.0);
    let pose = full_pose_from_yaw(camera, &candidates[chosen], yaw);
    Some(PoseEstimate {
        pose,
        alternative: full_pose_from_yaw(camera, &candidates[1 - chosen], yaw),
        ambiguity_margin_px: margin,
        center_px: projected_center(camera, &candidates[chosen])?,
    })
}

/// Pixel position of a point (x_m, y_m) in metres on the marker plane.
pub fn project_marker_point(
    camera: &Camera,
    pose: &Pose,
    x_m: f64,
    y_m: f64,
) -> Option<(f64, f64)> {
    camera.project(&pose.marker_to_camera(&Vector3::new(x_m, y_m, 0.0)))
}

/// Where the viewing ray of a pixel meets the marker's plane, in marker
/// coordinates (metres; z is 0); `None` if it meets it behind the camera.
pub fn intersect_marker_plane(
    camera: &Camera,
    pose: &Pose,
    pixel: (f64, f64),
) -> Option<Vector3<f64>> {
    let hit = intersect_plane(camera, &pose.circle(), pixel.0, pixel.1)?;
    Some(pose.rotation.transpose() * (hit - pose.position))
}

/// A marker-plane point (x, y in metres) and the pixel (u, v) where it was
/// seen.
pub type PointMatch = ((f64, f64), (f64, f64));

/// RMS reprojection error (pixels) of marker-plane points (metres) against
/// their measured pixels; `None` if a point does not project or the list is
/// empty. Scores a full pose candidate from e.g. decoded ring edge points.
pub fn reprojection_rms(
    camera: &Camera,
    pose: &Pose,
    correspondences: &[PointMatch],
) -> Option<f64> {
    if correspondences.is_empty() {
        return None;
    }
    let mut sum = 0.0;
    for &((x_m, y_m), (u, v)) in correspondences {
        let (pu, pv) = project_marker_point(camera, pose, x_m, y_m)?;
        sum += (pu - u).powi(2) + (pv - v).powi(2);
    }
    Some((sum / correspondences.len() as f64).sqrt())
}

/// Completes a circle pose with what the ring told: the image of a point on
/// the +x axis when known, else the yaw, else (legacy markers, unreadable
/// rings) an arbitrary 0.
pub fn full_pose_from_ring(
    camera: &Camera,
    circle: &CirclePose,
    yaw: Option<f64>,
    axis_point: Option<(f64, f64)>,
) -> Pose {
    match (axis_point, yaw) {
        (Some(p), _) => full_pose(camera, circle, p),
        (None, Some(yaw)) => full_pose_from_yaw(camera, circle, yaw),
        (None, None) => full_pose_from_yaw(camera, circle, 0.0),
    }
}
