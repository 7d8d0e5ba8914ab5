//! 6-DoF pose of a circular marker from its image ellipse (paper section 4,
//! eq. 5-8).
//!
//! A circle of known radius seen by a calibrated camera defines a cone
//! through the camera centre; its eigen-decomposition gives the circle's
//! centre and plane normal in closed form, up to a two-fold ambiguity (two
//! planes cut the same cone in circles of the same radius). The ambiguity is
//! resolved with a second, concentric circle of the marker (the inner disc or
//! the code ring), and the in-plane rotation comes from a known image point
//! on the marker's +x axis (e.g. found by decoding the code ring).
//!
//! Frames: camera frame is OpenCV optical (x right, y down, z forward);
//! marker frame has +x along code sector angle 0, +y along 90°, +z out of
//! the printed face. A [`CirclePose`] normal is the marker's +z axis and
//! points towards the camera (`normal · center < 0`).

use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};

use crate::camera::Camera;
use crate::math::ellipse::{fit_conic, Ellipse};

/// One solution for a circle in space: its centre (camera frame, metres)
/// and unit plane normal pointing towards the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CirclePose {
    pub center: Vector3<f64>,
    pub normal: Vector3<f64>,
}

impl CirclePose {
    /// Angle in radians between the two normals (0 = same orientation).
    pub fn normal_angle_to(&self, other: &CirclePose) -> f64 {
        self.normal.angle(&other.normal)
    }

    /// Tilt of the marker plane against the viewing ray to its centre
    /// (0 = seen face-on).
    pub fn view_angle(&self) -> f64 {
        (-self.normal).angle(&self.center)
    }
}

/// The two circle poses consistent with an image ellipse of a circle of
/// radius `radius_m` (paper eq. 6-8). Both candidates are always returned;
/// near face-on they coincide. For an invalid ellipse (see
/// [`Ellipse::is_valid`]) the result has NaN fields; use
/// [`try_circle_poses`] to get `None` instead.
pub fn circle_poses(camera: &Camera, ellipse: &Ellipse, radius_m: f64) -> [CirclePose; 2] {
    try_circle_poses(camera, ellipse, radius_m).unwrap_or(
        [CirclePose {
            center: Vector3::repeat(f64::NAN),
            normal: Vector3::repeat(f64::NAN),
        }; 2],
    )
}

/// [`circle_poses`], or `None` for an invalid ellipse or radius.
///
/// Without lens distortion the ellipse's conic is mapped exactly into
/// normalised camera coordinates. With distortion, 32 boundary points are
/// undistorted and a conic refitted, which is more faithful than
/// undistorting only the (co-)vertices as the reference does.
pub fn try_circle_poses(
    camera: &Camera,
    ellipse: &Ellipse,
    radius_m: f64,
) -> Option<[CirclePose; 2]> {
    if !ellipse.is_valid() {
        return None;
    }
    let cone = if camera.has_distortion() {
        let points: Vec<(f64, f64)> = ellipse
            .boundary_points(32)
            .into_iter()
            .map(|(u, v)| camera.undistort(u, v))
            .collect();
        fit_conic(&points)?
    } else {
        let k = intrinsic_matrix(camera);
        k.transpose() * ellipse.conic() * k
    };
    circle_poses_from_cone(&cone, radius_m)
}

/// Circle poses from raw image points on the circle's boundary (e.g.
/// sub-pixel edge points): the points are undistorted individually before
/// the conic fit, so lens distortion costs no accuracy.
pub fn circle_poses_from_points(
    camera: &Camera,
    boundary_px: &[(f64, f64)],
    radius_m: f64,
) -> Option<[CirclePose; 2]> {
    let points: Vec<(f64, f64)> = boundary_px
        .iter()
        .map(|&(u, v)| camera.undistort(u, v))
        .collect();
    circle_poses_from_cone(&fit_conic(&points)?, radius_m)
}

/// Circle poses from the cone conic Q in normalised camera coordinates
/// (xᵀ Q x = 0 for viewing rays x = (x/z, y/z, 1) through the circle).
pub fn circle_poses_from_cone(cone: &Matrix3<f64>, radius_m: f64) -> Option<[CirclePose; 2]> {
    if !(radius_m > 0.0 && radius_m.is_finite()) || cone.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let norm = cone.norm();
    if norm == 0.0 {
        return None;
    }
    let q = 0.5 * (cone + cone.transpose()) / norm;
    let eigen = SymmetricEigen::new(q);
    let mut values = eigen.eigenvalues;
    // A real cone has one eigenvalue of one sign and two of the other; make
    // the lone one negative.
    if values.iter().filter(|&&l| l < 0.0).count() >= 2 {
        values = -values;
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| values[j].total_cmp(&values[i]));
    let (l0, l1, l2) = (values[order[0]], values[order[1]], values[order[2]]);
    if !(l1 > 0.0 && l2 < 0.0) {
        return None;
    }
    let q0: Vector3<f64> = eigen.eigenvectors.column(order[0]).into_owned();
    let q2: Vector3<f64> = eigen.eigenvectors.column(order[2]).into_owned();
    // Clamped: for a circle seen face-on l0 == l1 up to rounding, which may
    // make the difference slightly negative.
    let spread = l0 - l2;
    let a = ((l0 - l1) / spread).max(0.0).sqrt();
    let b = ((l1 - l2) / spread).max(0.0).sqrt();
    let scale = radius_m / (-l0 * l2).sqrt();
    let candidate = |s1: f64| {
        let mut normal = s1 * a * q0 + b * q2;
        let mut center = scale * (s1 * a * l2 * q0 + b * l0 * q2);
        if center.z < 0.0 {
            center = -center;
            normal = -normal;
        }
        if normal.dot(&center) > 0.0 {
            normal = -normal;
        }
        CirclePose {
            center,
            normal: normal.normalize(),
        }
    };
    Some([candidate(1.0), candidate(-1.0)])
}

fn intrinsic_matrix(camera: &Camera) -> Matrix3<f64> {
    Matrix3::new(
        camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0,
    )
}

/// Pixel position of the circle's true centre. Under perspective it differs
/// from the ellipse centre (by up to a few pixels for large, tilted
/// markers), so this is the point to report as the marker's image position
/// once the pose is known.
pub fn projected_center(camera: &Camera, circle: &CirclePose) -> Option<(f64, f64)> {
    camera.project(&circle.center)
}

/// Two unit vectors spanning the plane perpendicular to `normal`.
fn plane_basis(normal: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = normal.cross(&helper).normalize();
    let e2 = normal.cross(&e1);
    (e1, e2)
}

/// Image ellipse of a circle of radius `radius_m` lying in the candidate's
/// plane around its centre. Exact without lens distortion; with distortion
/// it is the ellipse best fitting 32 projected points of the (then not
/// exactly elliptical) image curve. `None` if part of the circle is behind
/// the camera.
pub fn project_circle(camera: &Camera, circle: &CirclePose, radius_m: f64) -> Option<Ellipse> {
    let normal = circle.normal.normalize();
    let (e1, e2) = plane_basis(&normal);
    let nearest_z = circle.center.z - radius_m * normal.xy().norm();
    if nearest_z.is_nan() || nearest_z <= 0.0 {
        return None;
    }
    if camera.has_distortion() {
        let points = (0..32)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 32.0;
                camera.project(&(circle.center + radius_m * (t.cos() * e1 + t.sin() * e2)))
            })
            .collect::<Option<Vec<_>>>()?;
        return Ellipse::fit(&points);
    }
    // The plane-to-image homography H = K [e1 e2 c] maps the plane conic
    // diag(1, 1, -r²) to H⁻ᵀ diag(1, 1, -r²) H⁻¹.
    let homography = intrinsic_matrix(camera) * Matrix3::from_columns(&[e1, e2, circle.center]);
    let inverse = homography.try_inverse()?;
    let plane_conic = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -radius_m * radius_m));
    Ellipse::from_conic(&(inverse.transpose() * plane_conic * inverse))
}

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
/// normal and the line of sight): for a 122 mm marker with a 640×480, 60°
/// camera, 1.7 px at 1 m, 0.44 px at 2 m, 0.19 px at 3 m for a 40° tilt.
/// The wrong candidate's normal is off by twice the tilt. The cue vanishes
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

/// Where the viewing ray of pixel (u, v) meets the circle's plane, if in
/// front of the camera.
fn intersect_plane(camera: &Camera, circle: &CirclePose, u: f64, v: f64) -> Option<Vector3<f64>> {
    let ray = camera.ray(u, v);
    let denominator = circle.normal.dot(&ray);
    if denominator.abs() < 1e-12 {
        return None;
    }
    let t = circle.normal.dot(&circle.center) / denominator;
    (t > 0.0 && t.is_finite()).then(|| ray * t)
}

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
