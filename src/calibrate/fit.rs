//! The geometry of a calibration: a first guess from the planes'
//! homographies (Zhang), then Levenberg–Marquardt over the intrinsics, the
//! plumb_bob terms and every view's pose together.

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};

use crate::math::least_squares::levenberg_marquardt;

use super::{CalibrationError, Freedom, ViewPoints};
use crate::camera::Camera;
use crate::math::homography::Homography;

/// Intrinsic parameters in [`Camera`] order: fx, fy, cx, cy, k1, k2, p1, p2, k3.
pub const NAMES: [&str; 9] = ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"];

/// A camera's parameters in [`NAMES`]' order.
pub(crate) fn values(c: &Camera) -> [f64; 9] {
    let [k1, k2, p1, p2, k3] = c.distortion;
    [c.fx, c.fy, c.cx, c.cy, k1, k2, p1, p2, k3]
}

/// One view's pose: rotation vector and translation, board → camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ViewPose {
    pub(crate) rotation: Vector3<f64>,
    pub(crate) translation: Vector3<f64>,
}

impl ViewPose {
    pub(crate) fn matrix(&self) -> Matrix3<f64> {
        *Rotation3::new(self.rotation).matrix()
    }

    /// Angle between the board's normal and the optical axis.
    pub(crate) fn tilt(&self) -> f64 {
        self.matrix()[(2, 2)].abs().clamp(0.0, 1.0).acos()
    }
}

/// What a fit found: the camera, each view's pose, and the spread of the
/// free parameters.
#[derive(Debug, Clone)]
pub(crate) struct Fit {
    pub(crate) camera: Camera,
    pub(crate) poses: Vec<ViewPose>,
    /// Per view, per point: image residual (observed − projected), pixels.
    pub(crate) residuals: Vec<Vec<[f64; 2]>>,
    /// Standard deviation of each intrinsic parameter (0 when held fixed).
    pub(crate) std_devs: [f64; 9],
}

/// Which of the nine intrinsics move, and how the held ones are tied.
fn free_intrinsics(freedom: &Freedom) -> Vec<usize> {
    let mut free = vec![0];
    if !freedom.fix_aspect {
        free.push(1);
    }
    if !freedom.fix_principal_point {
        free.extend([2, 3]);
    }
    free.extend([4, 5]);
    if freedom.tangential {
        free.extend([6, 7]);
    }
    if freedom.k3 {
        free.push(8);
    }
    free
}

fn camera_of(full: &[f64; 9], freedom: &Freedom, width: u32, height: u32) -> Camera {
    Camera {
        fx: full[0],
        fy: if freedom.fix_aspect { full[0] } else { full[1] },
        cx: full[2],
        cy: full[3],
        distortion: [full[4], full[5], full[6], full[7], full[8]],
        width,
        height,
    }
}

/// A first camera without distortion: the principal point at the image
/// centre, the focal lengths from the homographies' orthogonality
/// constraints (OpenCV's `initIntrinsicParams` does the same); then every
/// view's pose from its homography.
pub(crate) fn initial_guess(
    views: &[ViewPoints],
    freedom: &Freedom,
    width: u32,
    height: u32,
) -> Result<(Camera, Vec<ViewPose>), CalibrationError> {
    let (cx, cy) = (
        (f64::from(width) - 1.0) / 2.0,
        (f64::from(height) - 1.0) / 2.0,
    );
    let shift = Matrix3::new(1.0, 0.0, -cx, 0.0, 1.0, -cy, 0.0, 0.0, 1.0);
    let mut homographies = Vec::with_capacity(views.len());
    // Rows of a·A + b·B = -C, one pair per view, with a = 1/fx², b = 1/fy².
    let mut rows: Vec<[f64; 3]> = Vec::new();
    for view in views {
        let pairs: Vec<_> = view
            .plane
            .iter()
            .zip(&view.pixels)
            .map(|(p, q)| ((p[0], p[1]), (q[0], q[1])))
            .collect();
        let h = Homography::fit(&pairs)
            .ok_or_else(|| CalibrationError::Degenerate(view.label.clone()))?
            .matrix;
        let m = shift * h;
        let m = m / m.column(0).norm().max(m.column(1).norm());
        rows.push([
            m[(0, 0)] * m[(0, 1)],
            m[(1, 0)] * m[(1, 1)],
            m[(2, 0)] * m[(2, 1)],
        ]);
        rows.push([
            m[(0, 0)].powi(2) - m[(0, 1)].powi(2),
            m[(1, 0)].powi(2) - m[(1, 1)].powi(2),
            m[(2, 0)].powi(2) - m[(2, 1)].powi(2),
        ]);
        homographies.push(h);
    }
    let solve_square = || {
        let (num, den) = rows.iter().fold((0.0, 0.0), |(num, den), r| {
            let a = r[0] + r[1];
            (num - a * r[2], den + a * a)
        });
        (num / den, num / den)
    };
    let (a, b) = if freedom.fix_aspect {
        solve_square()
    } else {
        let mut ata = nalgebra::Matrix2::zeros();
        let mut atb = nalgebra::Vector2::zeros();
        for r in &rows {
            let row = nalgebra::Vector2::new(r[0], r[1]);
            ata += row * row.transpose();
            atb -= row * r[2];
        }
        match ata.try_inverse().map(|inv| inv * atb) {
            Some(s) if s.x > 0.0 && s.y > 0.0 && (s.x / s.y - 1.0).abs() < 0.5 => (s.x, s.y),
            _ => solve_square(),
        }
    };
    let plausible = |f: f64, side: u32| {
        let fov = 2.0 * (0.5 * f64::from(side) / f).atan().to_degrees();
        f.is_finite() && (5.0..=170.0).contains(&fov)
    };
    let (fx, fy) = (1.0 / a.sqrt(), 1.0 / b.sqrt());
    if !(a > 0.0 && b > 0.0 && plausible(fx, width) && plausible(fy, height)) {
        return Err(CalibrationError::FrontoParallel { largest_tilt: None });
    }
    let camera = Camera {
        fx,
        fy,
        cx,
        cy,
        distortion: [0.0; 5],
        width,
        height,
    };
    let poses = homographies
        .iter()
        .map(|h| pose_from_homography(&camera, h))
        .collect();
    Ok((camera, poses))
}

/// The board's pose from a plane-to-image homography through a camera
/// without distortion: K⁻¹H = s [r1 r2 t], the rotation made orthonormal.
pub(crate) fn pose_from_homography(camera: &Camera, h: &Matrix3<f64>) -> ViewPose {
    let k_inv = Matrix3::new(
        1.0 / camera.fx,
        0.0,
        -camera.cx / camera.fx,
        0.0,
        1.0 / camera.fy,
        -camera.cy / camera.fy,
        0.0,
        0.0,
        1.0,
    );
    let mut m = k_inv * h;
    let scale = 2.0 / (m.column(0).norm() + m.column(1).norm());
    m *= scale;
    // The board lies in front of the camera.
    if m[(2, 2)] < 0.0 {
        m = -m;
    }
    let r1 = m.column(0).into_owned();
    let r2 = m.column(1).into_owned();
    let r3 = r1.cross(&r2);
    let approx = Matrix3::from_columns(&[r1, r2, r3]);
    let svd = approx.svd(true, true);
    let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut rotation = u * v_t;
    if rotation.determinant() < 0.0 {
        rotation = -rotation;
    }
    ViewPose {
        rotation: Rotation3::from_matrix_unchecked(rotation).scaled_axis(),
        translation: m.column(2).into_owned(),
    }
}

/// Projection of every point of a view; `None` for a point behind the camera.
fn project_view(camera: &Camera, pose: &ViewPose, view: &ViewPoints) -> Option<Vec<[f64; 2]>> {
    let r = pose.matrix();
    view.plane
        .iter()
        .map(|p| {
            camera
                .project(&(r * Vector3::new(p[0], p[1], 0.0) + pose.translation))
                .map(|(u, v)| [u, v])
        })
        .collect()
}

fn view_residuals(camera: &Camera, pose: &ViewPose, view: &ViewPoints) -> Option<DVector<f64>> {
    let projected = project_view(camera, pose, view)?;
    let mut r = DVector::zeros(2 * projected.len());
    for (k, (p, q)) in projected.iter().zip(&view.pixels).enumerate() {
        r[2 * k] = q[0] - p[0];
        r[2 * k + 1] = q[1] - p[1];
    }
    Some(r)
}

fn pose_params(pose: &ViewPose) -> [f64; 6] {
    let (r, t) = (pose.rotation, pose.translation);
    [r.x, r.y, r.z, t.x, t.y, t.z]
}

fn pose_from(p: &[f64; 6]) -> ViewPose {
    ViewPose {
        rotation: Vector3::new(p[0], p[1], p[2]),
        translation: Vector3::new(p[3], p[4], p[5]),
    }
}

/// Steps for the numerical derivatives: small against each parameter's
/// scale, large against rounding (central differences leave ~1e-9 px).
fn intrinsic_step(index: usize, value: f64) -> f64 {
    match index {
        0..=3 => 1e-4 * value.abs().max(1.0),
        _ => 1e-7,
    }
}
const POSE_STEP: f64 = 1e-7;

/// Levenberg–Marquardt from `camera` and `poses` over the free parameters:
/// the free intrinsics first, then six per view.
pub(crate) fn refine(
    views: &[ViewPoints],
    camera: &Camera,
    poses: &[ViewPose],
    freedom: &Freedom,
) -> Result<Fit, CalibrationError> {
    let (width, height) = (camera.width, camera.height);
    let free = free_intrinsics(freedom);
    let ni = free.len();
    let n = ni + 6 * views.len();
    // The held intrinsics keep these values (no tangential or k3 term: 0).
    let held: [f64; 9] = [
        camera.fx,
        if freedom.fix_aspect {
            camera.fx
        } else {
            camera.fy
        },
        camera.cx,
        camera.cy,
        camera.distortion[0],
        camera.distortion[1],
        if freedom.tangential {
            camera.distortion[2]
        } else {
            0.0
        },
        if freedom.tangential {
            camera.distortion[3]
        } else {
            0.0
        },
        if freedom.k3 {
            camera.distortion[4]
        } else {
            0.0
        },
    ];
    let intrinsics = |x: &DVector<f64>| {
        let mut full = held;
        for (col, &index) in free.iter().enumerate() {
            full[index] = x[col];
        }
        camera_of(&full, freedom, width, height)
    };
    let pose_at = |x: &DVector<f64>, k: usize| {
        let p = x.rows(ni + 6 * k, 6);
        pose_from(&[p[0], p[1], p[2], p[3], p[4], p[5]])
    };
    let offsets: Vec<usize> = views
        .iter()
        .scan(0, |at, v| {
            let start = *at;
            *at += 2 * v.plane.len();
            Some(start)
        })
        .collect();
    let m: usize = views.iter().map(|v| 2 * v.plane.len()).sum();
    if m <= n {
        return Err(CalibrationError::TooFewPoints {
            points: m / 2,
            parameters: n,
        });
    }
    let residuals_of = |x: &DVector<f64>| -> Option<DVector<f64>> {
        let cam = intrinsics(x);
        let mut all = DVector::zeros(m);
        for (k, view) in views.iter().enumerate() {
            let r = view_residuals(&cam, &pose_at(x, k), view)?;
            all.rows_mut(offsets[k], r.len()).copy_from(&r);
        }
        Some(all)
    };
    // Each view's pose moves only that view's residuals: a block each.
    let jacobian_of = |x: &DVector<f64>| -> Option<DMatrix<f64>> {
        let mut j = DMatrix::zeros(m, n);
        for (col, &index) in free.iter().enumerate() {
            let h = intrinsic_step(index, x[col]);
            let (mut plus, mut minus) = (x.clone(), x.clone());
            plus[col] += h;
            minus[col] -= h;
            let d = (residuals_of(&plus)? - residuals_of(&minus)?) / (2.0 * h);
            j.column_mut(col).copy_from(&d);
        }
        let cam = intrinsics(x);
        for (k, view) in views.iter().enumerate() {
            let base = pose_params(&pose_at(x, k));
            for p in 0..6 {
                let (mut plus, mut minus) = (base, base);
                plus[p] += POSE_STEP;
                minus[p] -= POSE_STEP;
                let d = (view_residuals(&cam, &pose_from(&plus), view)?
                    - view_residuals(&cam, &pose_from(&minus), view)?)
                    / (2.0 * POSE_STEP);
                j.view_mut((offsets[k], ni + 6 * k + p), (d.len(), 1))
                    .copy_from(&d);
            }
        }
        Some(j)
    };
    let mut x0 = DVector::zeros(n);
    for (col, &index) in free.iter().enumerate() {
        x0[col] = held[index];
    }
    for (k, pose) in poses.iter().enumerate() {
        x0.rows_mut(ni + 6 * k, 6)
            .copy_from_slice(&pose_params(pose));
    }
    let minimum = levenberg_marquardt(x0, residuals_of, jacobian_of, 200)
        .ok_or(CalibrationError::Diverged)?;
    let camera = intrinsics(&minimum.x);
    let spread = minimum.std_devs().ok_or(CalibrationError::Undetermined {
        parameter: NAMES[free[ni - 1]],
        std_dev: f64::INFINITY,
    })?;
    let mut std_devs = [0.0; 9];
    for (col, &index) in free.iter().enumerate() {
        std_devs[index] = spread[col];
    }
    if freedom.fix_aspect {
        std_devs[1] = std_devs[0];
    }
    let poses: Vec<ViewPose> = (0..views.len()).map(|k| pose_at(&minimum.x, k)).collect();
    let residuals = views
        .iter()
        .zip(&poses)
        .map(|(view, pose)| {
            let projected = project_view(&camera, pose, view).unwrap_or_default();
            projected
                .iter()
                .zip(&view.pixels)
                .map(|(p, q)| [q[0] - p[0], q[1] - p[1]])
                .collect()
        })
        .collect();
    Ok(Fit {
        camera,
        poses,
        residuals,
        std_devs,
    })
}
