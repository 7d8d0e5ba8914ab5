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

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::camera::Camera;
use crate::math::ellipse::{fit_conic, Ellipse};

mod choose;
mod full;
mod refine;

pub use choose::{
    choose_by_centre_estimate, choose_by_circle_points, choose_by_inner_circle,
    choose_by_radial_points, choose_by_settled_normal, circle_point_rms, inner_edge_errors,
    RadialPoint,
};
pub use full::{
    estimate_pose, full_pose, full_pose_from_ring, full_pose_from_yaw, intersect_marker_plane,
    project_marker_point, reprojection_rms, PointMatch, Pose, PoseEstimate,
};
pub use refine::{refine_circle_pose, refit_circle_pose};

/// One solution for a circle in space: its centre (camera frame, metres)
/// and unit plane normal pointing towards the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CirclePose {
    /// Circle centre in the camera frame, metres.
    pub center: Vector3<f64>,
    /// Unit normal of the circle's plane, towards the camera.
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

    /// The other solution of the two-fold ambiguity: the circle of radius
    /// `radius_m` that casts the same cone as this one. A front end that
    /// knows the plane a marker lies in (a calibration sheet, a board)
    /// takes whichever of the two faces that plane, where the detector
    /// alone, on a small or nearly face-on marker, may have picked by a
    /// coin toss. `None` when the circle is not in front of the camera.
    pub fn twin(&self, radius_m: f64) -> Option<CirclePose> {
        // Rays x meet the plane n·X = n·C at X = (n·C / n·x) x; that point
        // lies on the circle when |X − C|² = r². Multiplied by (n·x)² this
        // is a quadratic form in x: the cone.
        let (c, n) = (self.center, self.normal.normalize());
        let d = n.dot(&c);
        let cone = Matrix3::identity() * (d * d) - (c * n.transpose() + n * c.transpose()) * d
            + n * n.transpose() * (c.norm_squared() - radius_m * radius_m);
        let [a, b] = circle_poses_from_cone(&cone, radius_m)?;
        let nearer_first = a.normal.dot(&n) >= b.normal.dot(&n);
        Some(if nearer_first { b } else { a })
    }
}

/// Of a marker's pose and its twin ([`CirclePose::twin`]), the circle
/// whose plane is nearer to `plane_normal` (either sign), and whether that
/// is the twin. Markers printed on one plane share its normal, so this
/// undoes the detector's wrong picks on it.
pub fn facing_plane(
    pose: &Pose,
    radius_m: f64,
    plane_normal: &Vector3<f64>,
) -> Option<(CirclePose, bool)> {
    let own = CirclePose {
        center: pose.position,
        normal: pose.rotation.column(2).into_owned(),
    };
    let twin = own.twin(radius_m)?;
    let alignment = |c: &CirclePose| c.normal.dot(plane_normal).abs();
    Some(if alignment(&twin) > alignment(&own) {
        (twin, true)
    } else {
        (own, false)
    })
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
pub(crate) fn plane_basis(normal: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
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

/// Where the viewing ray of pixel (u, v) meets the circle's plane, if in
/// front of the camera.
pub(crate) fn intersect_plane(
    camera: &Camera,
    circle: &CirclePose,
    u: f64,
    v: f64,
) -> Option<Vector3<f64>> {
    let ray = camera.ray(u, v);
    let denominator = circle.normal.dot(&ray);
    if denominator.abs() < 1e-12 {
        return None;
    }
    let t = circle.normal.dot(&circle.center) / denominator;
    (t > 0.0 && t.is_finite()).then(|| ray * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circles_twin_casts_the_same_ellipse_and_its_twin_is_the_circle() {
        let camera = Camera::ideal(1280, 960, 1000.0);
        let circle = CirclePose {
            center: Vector3::new(0.08, -0.05, 0.5),
            normal: Vector3::new(0.3, 0.2, -1.0).normalize(),
        };
        let radius = 0.015;
        let twin = circle.twin(radius).unwrap();
        assert!(twin.normal.angle(&circle.normal) > 0.2, "{twin:?}");
        let (a, b) = (
            project_circle(&camera, &circle, radius).unwrap(),
            project_circle(&camera, &twin, radius).unwrap(),
        );
        assert!((a.u - b.u).abs() < 1e-6 && (a.v - b.v).abs() < 1e-6);
        assert!((a.semi_major - b.semi_major).abs() < 1e-6);
        assert!((a.semi_minor - b.semi_minor).abs() < 1e-6);
        // Their centres project apart: the point of choosing between them.
        let (pa, pb) = (
            projected_center(&camera, &circle).unwrap(),
            projected_center(&camera, &twin).unwrap(),
        );
        assert!((pa.0 - pb.0).hypot(pa.1 - pb.1) > 0.05);
        let back = twin.twin(radius).unwrap();
        assert!((back.center - circle.center).norm() < 1e-9);
        assert!(back.normal.angle(&circle.normal) < 1e-9);
    }
}
