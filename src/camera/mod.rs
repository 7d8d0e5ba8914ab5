//! Pinhole camera with OpenCV "plumb bob" lens distortion. Reading and
//! writing calibration files ([`Camera::load`], [`Camera::to_ros_yaml`])
//! lives in `calibration.rs`.
//!
//! Conventions: camera frame is the OpenCV optical frame (x right, y down,
//! z forward); pixel coordinates have their origin at the *centre* of the
//! top-left pixel (u right, v down), which is also OpenCV's convention for
//! the principal point.

mod calibration;

pub use calibration::{CalibrationFormat, ImplausibleCamera, LensProblem, OtherCamera};

use nalgebra::{Matrix2, Vector2, Vector3};

/// Intrinsic calibration of one camera.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (origin at the top-left pixel's centre).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// k1, k2, p1, p2, k3 (OpenCV order, "plumb_bob" in ROS).
    pub distortion: [f64; 5],
    /// Image width the calibration was made for, pixels: an image of another size needs [`Camera::for_image`].
    pub width: u32,
    /// Image height the calibration was made for, pixels.
    pub height: u32,
}

/// Points closer to the camera plane than this (in z, metres or any unit)
/// are treated as not projectable.
const MIN_DEPTH: f64 = 1e-9;

/// Projects the points of one plane, given in its own coordinates (a, b):
/// [`Camera::project`] of `origin + a·x_axis + b·y_axis`. Without lens
/// distortion the plane maps to the image by a homography, and a point
/// costs one division (the ring stages project about a thousand points per
/// marker).
#[derive(Debug, Clone, Copy)]
pub struct PlaneProjection {
    camera: Camera,
    origin: Vector3<f64>,
    x_axis: Vector3<f64>,
    y_axis: Vector3<f64>,
    pixel_origin: Vector3<f64>,
    pixel_x: Vector3<f64>,
    pixel_y: Vector3<f64>,
    distorted: bool,
}

impl PlaneProjection {
    /// Pixel position of the plane point (a, b); `None` where
    /// [`Camera::project`] gives none.
    #[inline]
    pub fn project(&self, a: f64, b: f64) -> Option<(f64, f64)> {
        if self.distorted {
            return self
                .camera
                .project(&(self.origin + self.x_axis * a + self.y_axis * b));
        }
        dehomogenise(self.pixel_origin + self.pixel_x * a + self.pixel_y * b)
    }

    /// [`PlaneProjection::project`] of the points at angle (cos, sin) on
    /// circles of the given radii about the origin: the direction is worked
    /// out once for them all (a ring profile reads three radii per angle).
    #[inline]
    pub fn project_radii<const N: usize>(
        &self,
        (c, s): (f64, f64),
        radii: &[f64; N],
    ) -> [Option<(f64, f64)>; N] {
        let mut points = [None; N];
        if self.distorted {
            for (point, &r) in points.iter_mut().zip(radii) {
                *point = self.project(r * c, r * s);
            }
            return points;
        }
        let direction = self.pixel_x * c + self.pixel_y * s;
        // A loop, not `radii.map`: the closure behind an array map of
        // options was not inlined.
        for (point, &r) in points.iter_mut().zip(radii) {
            *point = dehomogenise(self.pixel_origin + direction * r);
        }
        points
    }
}

/// The pixel of homogeneous pixel coordinates `h`: `None` behind or at
/// the camera, or where they are not finite.
#[inline]
fn dehomogenise(h: Vector3<f64>) -> Option<(f64, f64)> {
    // Not above the least depth also when NaN.
    (h.z > MIN_DEPTH && h.x.is_finite() && h.y.is_finite()).then(|| {
        let inverse = 1.0 / h.z;
        (h.x * inverse, h.y * inverse)
    })
}

impl Camera {
    /// Distortion-free camera with square pixels, the principal point at the
    /// image centre and the given horizontal field of view (degrees, edge of
    /// the first pixel to edge of the last).
    pub fn ideal(width: u32, height: u32, horizontal_fov_deg: f64) -> Camera {
        let f = 0.5 * width as f64 / (0.5 * horizontal_fov_deg.to_radians()).tan();
        Camera {
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            distortion: [0.0; 5],
            width,
            height,
        }
    }

    /// Horizontal field of view in degrees (ignoring distortion).
    pub fn horizontal_fov_deg(&self) -> f64 {
        2.0 * (0.5 * self.width as f64 / self.fx).atan().to_degrees()
    }

    /// True if any distortion coefficient is non-zero.
    pub fn has_distortion(&self) -> bool {
        self.distortion.iter().any(|&k| k != 0.0)
    }

    /// The same camera at another image resolution (e.g. a calibration made
    /// at full resolution used on binned or resized images). Assumes the
    /// whole sensor area is rescaled, not cropped.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        // Scaling acts on pixel *edges*; pixel centres sit half a pixel in.
        Camera {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            distortion: self.distortion,
            width,
            height,
        }
    }

    /// The calibration for an image of `width` x `height`: itself, or
    /// rescaled when the image is the same sensor at another resolution. A
    /// different aspect ratio means another camera or a crop, for which no
    /// rescaling is right, and is refused.
    pub fn for_image(&self, width: u32, height: u32) -> Result<Camera, OtherCamera> {
        if self.width == width && self.height == height {
            return Ok(*self);
        }
        let aspect = |w: u32, h: u32| f64::from(w) / f64::from(h);
        if height == 0
            || self.height == 0
            || (aspect(self.width, self.height) / aspect(width, height) - 1.0).abs() > 0.01
        {
            return Err(OtherCamera {
                image: [width, height],
                calibration: [self.width, self.height],
            });
        }
        Ok(self.with_resolution(width, height))
    }

    /// Pixel position of a point in the camera frame, with distortion.
    /// `None` for points on or behind the camera plane.
    pub fn project(&self, p: &Vector3<f64>) -> Option<(f64, f64)> {
        if p.z.is_nan() || p.z <= MIN_DEPTH || !p.x.is_finite() || !p.y.is_finite() {
            return None;
        }
        Some(self.distort_normalized(p.x / p.z, p.y / p.z))
    }

    /// Projection of the points `origin + a·x_axis + b·y_axis` of a plane
    /// (camera frame), for stages that sample a marker plane at many
    /// points: see [`PlaneProjection`].
    pub fn plane_projection(
        &self,
        origin: Vector3<f64>,
        x_axis: Vector3<f64>,
        y_axis: Vector3<f64>,
    ) -> PlaneProjection {
        // The plane's points in pixel units before the perspective
        // division: K applied to origin and axes.
        let pixel = |p: Vector3<f64>| {
            Vector3::new(
                self.fx * p.x + self.cx * p.z,
                self.fy * p.y + self.cy * p.z,
                p.z,
            )
        };
        PlaneProjection {
            camera: *self,
            origin,
            x_axis,
            y_axis,
            pixel_origin: pixel(origin),
            pixel_x: pixel(x_axis),
            pixel_y: pixel(y_axis),
            distorted: self.has_distortion(),
        }
    }

    /// Pixel position of an ideal normalised image point (x/z, y/z).
    pub fn distort_normalized(&self, x: f64, y: f64) -> (f64, f64) {
        let (xd, yd) = self.distort_point(x, y);
        (self.fx * xd + self.cx, self.fy * yd + self.cy)
    }

    /// Pixel position of an ideal normalised point without applying the lens
    /// distortion (for rectified images).
    pub fn pinhole(&self, x: f64, y: f64) -> (f64, f64) {
        (self.fx * x + self.cx, self.fy * y + self.cy)
    }

    /// Ideal normalised image coordinates (x/z, y/z) of a pixel: the inverse
    /// of [`Camera::distort_normalized`]. Exact (to ~1e-12) wherever the
    /// distortion polynomial is invertible, which holds inside the image for
    /// real calibrations; beyond the radius where the polynomial folds back
    /// it returns the finite point of least residual.
    // Inlined, with the lens's Newton iteration out of line: the pose
    // stages undistort a few hundred edge points per marker, mostly with
    // cameras without distortion.
    #[inline]
    pub fn undistort(&self, u: f64, v: f64) -> (f64, f64) {
        let target = Vector2::new((u - self.cx) / self.fx, (v - self.cy) / self.fy);
        if !self.has_distortion() || !target.x.is_finite() || !target.y.is_finite() {
            return (target.x, target.y);
        }
        self.undistort_lens(target)
    }

    #[inline(never)]
    fn undistort_lens(&self, target: Vector2<f64>) -> (f64, f64) {
        // Damped Newton on distort(x) = target. The plain fixed-point
        // iteration OpenCV uses stalls in image corners with strong barrel
        // distortion; Newton converges in a handful of steps there.
        let residual = |p: &Vector2<f64>| {
            let (xd, yd) = self.distort_point(p.x, p.y);
            Vector2::new(xd, yd) - target
        };
        let mut p = target;
        let mut r = residual(&p);
        for _ in 0..50 {
            let err = r.norm();
            if err < 1e-15 {
                break;
            }
            let step = match self.distortion_jacobian(p.x, p.y).try_inverse() {
                Some(inv) => inv * r,
                None => r,
            };
            let mut scale = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                let candidate = p - step * scale;
                let rc = residual(&candidate);
                if rc.norm() < err {
                    p = candidate;
                    r = rc;
                    accepted = true;
                    break;
                }
                scale *= 0.5;
            }
            if !accepted {
                break;
            }
        }
        (p.x, p.y)
    }

    /// Unit-free viewing ray (x, y, 1) through a pixel.
    pub fn ray(&self, u: f64, v: f64) -> Vector3<f64> {
        let (x, y) = self.undistort(u, v);
        Vector3::new(x, y, 1.0)
    }

    /// Apply the plumb-bob model to ideal normalised coordinates, giving
    /// distorted normalised coordinates.
    fn distort_point(&self, x: f64, y: f64) -> (f64, f64) {
        let [k1, k2, p1, p2, k3] = self.distortion;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        (xd, yd)
    }

    fn distortion_jacobian(&self, x: f64, y: f64) -> Matrix2<f64> {
        let [k1, k2, p1, p2, k3] = self.distortion;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        // d(radial)/d(r2)
        let dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        let dxd_dx = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
        let dxd_dy = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyd_dx = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
        let dyd_dy = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
        Matrix2::new(dxd_dx, dxd_dy, dyd_dx, dyd_dy)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A typical calibrated webcam, shared with the calibration-file tests.
    pub(crate) fn distorted() -> Camera {
        Camera {
            fx: 610.0,
            fy: 612.0,
            cx: 318.4,
            cy: 243.1,
            distortion: [-0.28, 0.09, 0.0012, -0.0008, -0.012],
            width: 640,
            height: 480,
        }
    }

    #[test]
    fn ideal_camera_geometry() {
        let cam = Camera::ideal(640, 480, 60.0);
        assert!((cam.cx - 319.5).abs() < 1e-12 && (cam.cy - 239.5).abs() < 1e-12);
        assert!((cam.horizontal_fov_deg() - 60.0).abs() < 1e-9);
        // The optical axis lands on the principal point.
        let (u, v) = cam.project(&Vector3::new(0.0, 0.0, 2.0)).unwrap();
        assert_eq!((u, v), (319.5, 239.5));
        // A point at the edge of the field of view lands on the image edge
        // (half a pixel beyond the last pixel centre).
        let half = 30f64.to_radians();
        let (u, _) = cam.project(&Vector3::new(half.tan(), 0.0, 1.0)).unwrap();
        assert!((u - 639.5).abs() < 1e-9, "{u}");
    }

    #[test]
    fn project_rejects_points_behind_camera() {
        let cam = distorted();
        assert!(cam.project(&Vector3::new(0.1, 0.1, -1.0)).is_none());
        assert!(cam.project(&Vector3::new(0.1, 0.1, 0.0)).is_none());
        assert!(cam.project(&Vector3::new(0.1, 0.1, 0.5)).is_some());
    }

    #[test]
    fn a_plane_projection_projects_as_the_camera_does() {
        let origin = Vector3::new(0.05, -0.03, 0.8);
        let x_axis = Vector3::new(0.9, 0.1, -0.3).normalize();
        let y_axis = Vector3::new(-0.2, 0.95, 0.1).normalize();
        for cam in [distorted(), Camera::ideal(640, 480, 60.0)] {
            let plane = cam.plane_projection(origin, x_axis, y_axis);
            for k in 0..50 {
                let (a, b) = (0.004 * f64::from(k) - 0.1, 0.1 - 0.003 * f64::from(k));
                let (u, v) = plane.project(a, b).unwrap();
                let (pu, pv) = cam.project(&(origin + x_axis * a + y_axis * b)).unwrap();
                assert!(
                    (u - pu).abs() < 1e-9 && (v - pv).abs() < 1e-9,
                    "{u} {v} {pu} {pv}"
                );
            }
            // A plane through the camera's centre: its far side is behind.
            let edge_on = cam.plane_projection(Vector3::new(0.0, 0.0, 0.1), x_axis, Vector3::z());
            assert!(edge_on.project(0.0, -0.2).is_none());
        }
    }

    #[test]
    fn undistort_inverts_distortion_over_the_whole_image() {
        let cam = distorted();
        let (w, h) = (cam.width as f64 - 1.0, cam.height as f64 - 1.0);
        let mut worst: f64 = 0.0;
        for &(u, v) in &[
            (0.0, 0.0),
            (w, 0.0),
            (0.0, h),
            (w, h),
            (cam.cx, cam.cy),
            (17.0, 400.0),
        ] {
            let (x, y) = cam.undistort(u, v);
            let (u2, v2) = cam.distort_normalized(x, y);
            worst = worst.max((u2 - u).hypot(v2 - v));
        }
        assert!(worst < 1e-8, "round trip error {worst} px");
        for i in 0..=20 {
            for j in 0..=20 {
                let (x, y) = (-0.55 + 0.055 * i as f64, -0.42 + 0.042 * j as f64);
                let (u, v) = cam.distort_normalized(x, y);
                let (x2, y2) = cam.undistort(u, v);
                assert!((x2 - x).hypot(y2 - y) < 1e-10, "({x},{y}) -> ({x2},{y2})");
            }
        }
    }

    #[test]
    fn undistort_handles_strong_barrel_distortion_in_corners() {
        // A wide-angle lens (~110° diagonal after undistortion): corners are
        // pulled in strongly.
        let cam = Camera {
            fx: 700.0,
            fy: 700.0,
            cx: 639.5,
            cy: 359.5,
            distortion: [-0.25, 0.07, 0.0, 0.0, -0.008],
            width: 1280,
            height: 720,
        };
        for &(u, v) in &[(0.0, 0.0), (1279.0, 0.0), (0.0, 719.0), (1279.0, 719.0)] {
            let (x, y) = cam.undistort(u, v);
            let (u2, v2) = cam.distort_normalized(x, y);
            assert!((u2 - u).hypot(v2 - v) < 1e-7, "({u},{v}) -> ({u2},{v2})");
        }
        // Far outside the calibrated region the polynomial folds back and
        // has no inverse; the answer must still be finite.
        let (x, y) = cam.undistort(-5000.0, -4000.0);
        assert!(x.is_finite() && y.is_finite());
    }

    #[test]
    fn resolution_scaling_keeps_rays() {
        let cam = distorted();
        let half = cam.with_resolution(320, 240);
        // Pixel centre (u, v) at full resolution is at ((u+0.5)/2-0.5, ...) at half.
        let (x, y) = cam.undistort(100.0, 50.0);
        let (x2, y2) = half.undistort(49.75, 24.75);
        assert!((x - x2).abs() < 1e-12 && (y - y2).abs() < 1e-12);
    }
}
