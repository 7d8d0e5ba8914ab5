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

use nalgebra::{Matrix2, Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector2, Vector3};

use crate::camera::Camera;

/// An ellipse in pixel coordinates (origin at the top-left pixel's centre,
/// v down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageEllipse {
    pub u: f64,
    pub v: f64,
    pub semi_major: f64,
    pub semi_minor: f64,
    /// Direction of the major axis, atan2(dv, du), in (-π/2, π/2].
    pub angle: f64,
}

impl ImageEllipse {
    /// Ellipse of a uniformly filled elliptical region from the covariance
    /// of its pixel coordinates (paper eq. 2-3: semi-axis = 2·sqrt(λ)).
    pub fn from_covariance(u: f64, v: f64, covariance: &Matrix2<f64>) -> ImageEllipse {
        let (cuu, cuv, cvv) = (
            covariance[(0, 0)],
            0.5 * (covariance[(0, 1)] + covariance[(1, 0)]),
            covariance[(1, 1)],
        );
        let mean = 0.5 * (cuu + cvv);
        let spread = (0.25 * (cuu - cvv).powi(2) + cuv * cuv).sqrt();
        let major = mean + spread;
        let minor = (mean - spread).max(0.0);
        ImageEllipse {
            u,
            v,
            semi_major: 2.0 * major.max(0.0).sqrt(),
            semi_minor: 2.0 * minor.sqrt(),
            angle: normalize_axis_angle(0.5 * (2.0 * cuv).atan2(cuu - cvv)),
        }
    }

    /// Least-squares ellipse through boundary points (direct ellipse-specific
    /// fit of Fitzgibbon et al. in the numerically stable form of Halíř and
    /// Flusser, on centred and scaled coordinates). `None` for fewer than 5
    /// points, degenerate configurations or data that fit no ellipse.
    pub fn fit(points: &[(f64, f64)]) -> Option<ImageEllipse> {
        ImageEllipse::from_conic(&fit_conic(points)?)
    }

    /// The ellipse described by a conic matrix C (points p = (u, v, 1) with
    /// pᵀ C p = 0), if it is a real ellipse.
    pub fn from_conic(conic: &Matrix3<f64>) -> Option<ImageEllipse> {
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
        let ellipse = ImageEllipse {
            u: centre.x,
            v: centre.y,
            semi_major: 1.0 / small.sqrt(),
            semi_minor: 1.0 / large.sqrt(),
            angle: normalize_axis_angle(minor_direction + std::f64::consts::FRAC_PI_2),
        };
        ellipse.is_valid().then_some(ellipse)
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

    /// Boundary point at parameter t (t = 0 is the end of the major axis in
    /// the `angle` direction).
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

fn normalize_axis_angle(angle: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut a = angle.rem_euclid(pi);
    if a > 0.5 * pi {
        a -= pi;
    }
    a
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
/// [`ImageEllipse::is_valid`]) the result has NaN fields; use
/// [`try_circle_poses`] to get `None` instead.
pub fn circle_poses(camera: &Camera, ellipse: &ImageEllipse, radius_m: f64) -> [CirclePose; 2] {
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
    ellipse: &ImageEllipse,
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
pub fn project_circle(camera: &Camera, circle: &CirclePose, radius_m: f64) -> Option<ImageEllipse> {
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
        return ImageEllipse::fit(&points);
    }
    // The plane-to-image homography H = K [e1 e2 c] maps the plane conic
    // diag(1, 1, -r²) to H⁻ᵀ diag(1, 1, -r²) H⁻¹.
    let homography = intrinsic_matrix(camera) * Matrix3::from_columns(&[e1, e2, circle.center]);
    let inverse = homography.try_inverse()?;
    let plane_conic = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -radius_m * radius_m));
    ImageEllipse::from_conic(&(inverse.transpose() * plane_conic * inverse))
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
    inner: &ImageEllipse,
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
    outer: &ImageEllipse,
    radius_m: f64,
    inner: Option<(&ImageEllipse, f64)>,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_conic_round_trip() {
        let e = ImageEllipse {
            u: 120.5,
            v: -33.0,
            semi_major: 40.0,
            semi_minor: 12.5,
            angle: 2.0,
        };
        let back = ImageEllipse::from_conic(&(e.conic() * -3.0)).unwrap();
        assert!((back.u - e.u).abs() < 1e-9 && (back.v - e.v).abs() < 1e-9);
        assert!((back.semi_major - 40.0).abs() < 1e-9 && (back.semi_minor - 12.5).abs() < 1e-9);
        assert!((back.angle - normalize_axis_angle(2.0)).abs() < 1e-12);
        for (u, v) in e.boundary_points(7) {
            let p = Vector3::new(u, v, 1.0);
            assert!((p.transpose() * e.conic() * p)[0].abs() < 1e-12);
        }
    }

    #[test]
    fn covariance_of_filled_ellipse() {
        // A filled ellipse with semi-axes a, b has variances a²/4, b²/4.
        let (a, b, angle) = (30.0f64, 10.0f64, 0.4f64);
        let (s, c) = angle.sin_cos();
        let r = Matrix2::new(c, -s, s, c);
        let cov = r * Matrix2::new(a * a / 4.0, 0.0, 0.0, b * b / 4.0) * r.transpose();
        let e = ImageEllipse::from_covariance(5.0, 6.0, &cov);
        assert!((e.semi_major - a).abs() < 1e-9 && (e.semi_minor - b).abs() < 1e-9);
        assert!((e.angle - angle).abs() < 1e-12);
        let round = ImageEllipse::from_covariance(0.0, 0.0, &Matrix2::identity());
        assert_eq!((round.semi_major, round.semi_minor), (2.0, 2.0));
        assert!(round.angle.is_finite());
    }

    #[test]
    fn fit_rejects_degenerate_input() {
        assert!(ImageEllipse::fit(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 3.0)]).is_none());
        let line: Vec<_> = (0..20).map(|i| (i as f64, 2.0 * i as f64)).collect();
        assert!(ImageEllipse::fit(&line).is_none());
        assert!(ImageEllipse::fit(&[(1.0, 1.0); 10]).is_none());
    }
}
