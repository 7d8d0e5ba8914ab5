//! Synthetic camera views for the detector's tests and benchmarks: markers
//! drawn by point-sampling `geometry::Marker::is_black_at` (3 x 3 samples a
//! pixel) through a pinhole projection, with optional light gradient, blur
//! and noise. Ground truth comes from the same projection.
#![allow(dead_code)]

use image::GrayImage;
use nalgebra::{Matrix3, Vector3};
use whycode::geometry::Marker;
use whycode::simulate::rng::Pcg32;

/// A marker placed in front of a pinhole camera.
#[derive(Debug, Clone, Copy)]
pub struct Placement {
    pub marker: Marker,
    /// Marker → camera rotation (OpenCV optical frame).
    pub rotation: Matrix3<f64>,
    /// Marker centre in the camera frame, millimetres.
    pub position: Vector3<f64>,
}

/// A pinhole camera without distortion.
#[derive(Debug, Clone, Copy)]
pub struct Pinhole {
    pub f: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Pinhole {
    pub fn project(&self, p: Vector3<f64>) -> (f64, f64) {
        (self.cx + self.f * p.x / p.z, self.cy + self.f * p.y / p.z)
    }
}

fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

impl Placement {
    /// A marker whose centre projects to (u, v), `diameter_px` across when
    /// seen face-on at that distance, turned visually CCW by `psi` in its
    /// own plane and tilted by `tilt` about an in-plane axis at `tilt_axis`.
    pub fn at(
        camera: &Pinhole,
        marker: Marker,
        (u, v): (f64, f64),
        diameter_px: f64,
        psi: f64,
        tilt: f64,
        tilt_axis: f64,
    ) -> Placement {
        let z = camera.f * marker.diameter_mm / diameter_px;
        let position = Vector3::new(
            (u - camera.cx) * z / camera.f,
            (v - camera.cy) * z / camera.f,
            z,
        );
        let face_on = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
        let tilt_rot = rot_z(tilt_axis) * rot_x(tilt) * rot_z(-tilt_axis);
        Placement {
            marker,
            rotation: tilt_rot * face_on * rot_z(psi),
            position,
        }
    }

    fn in_camera(&self, x: f64, y: f64) -> Vector3<f64> {
        self.rotation * Vector3::new(x, y, 0.0) + self.position
    }

    /// The projected centre.
    pub fn centre(&self, camera: &Pinhole) -> (f64, f64) {
        camera.project(self.position)
    }

    /// Image direction of the marker's +x axis at its centre, atan2(dv, du).
    pub fn yaw(&self, camera: &Pinhole) -> f64 {
        let (u0, v0) = self.centre(camera);
        let (u1, v1) = camera.project(self.in_camera(self.marker.diameter_mm * 1e-3, 0.0));
        (v1 - v0).atan2(u1 - u0)
    }

    /// Image → marker-plane map (a homography), for sampling.
    fn inverse(&self, camera: &Pinhole) -> Matrix3<f64> {
        let k = Matrix3::new(
            camera.f, 0.0, camera.cx, 0.0, camera.f, camera.cy, 0.0, 0.0, 1.0,
        );
        let r = self.rotation;
        let h = k * Matrix3::from_columns(&[r.column(0).into(), r.column(1).into(), self.position]);
        h.try_inverse().expect("marker plane seen edge-on")
    }

    /// Pixel bounding box of the marker's footprint.
    fn bbox(&self, camera: &Pinhole, width: u32, height: u32) -> (u32, u32, u32, u32) {
        let r = self.marker.footprint_radius();
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for k in 0..64 {
            let t = k as f64 * std::f64::consts::TAU / 64.0;
            let (u, v) = camera.project(self.in_camera(r * 1.05 * t.cos(), r * 1.05 * t.sin()));
            x0 = x0.min(u);
            y0 = y0.min(v);
            x1 = x1.max(u);
            y1 = y1.max(v);
        }
        let clamp = |a: f64, hi: u32| a.clamp(0.0, f64::from(hi) - 1.0) as u32;
        (
            clamp(x0 - 2.0, width),
            clamp(y0 - 2.0, height),
            clamp(x1 + 2.0, width),
            clamp(y1 + 2.0, height),
        )
    }
}

/// Scene rendering options.
#[derive(Debug, Clone, Copy)]
pub struct Look {
    pub white: f64,
    pub black: f64,
    /// Light falls linearly from 1 at the left edge to this at the right.
    pub gradient_right: f64,
    /// Box blur radius (pixels, applied twice), 0 for none.
    pub blur: u32,
    /// Gaussian noise σ in grey levels.
    pub noise: f64,
}

impl Default for Look {
    fn default() -> Look {
        Look {
            white: 230.0,
            black: 25.0,
            gradient_right: 1.0,
            blur: 0,
            noise: 0.0,
        }
    }
}

/// Draws the markers on a white background.
pub fn render(
    width: u32,
    height: u32,
    camera: &Pinhole,
    markers: &[Placement],
    look: Look,
) -> GrayImage {
    // Reflectance 1 = white paper, 0 = black ink.
    let mut reflectance = vec![1.0f32; (width * height) as usize];
    const S: usize = 3;
    for m in markers {
        let inv = m.inverse(camera);
        let (x0, y0, x1, y1) = m.bbox(camera, width, height);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let mut black = 0;
                for j in 0..S {
                    for i in 0..S {
                        let px = f64::from(x) + (i as f64 + 0.5) / S as f64 - 0.5;
                        let py = f64::from(y) + (j as f64 + 0.5) / S as f64 - 0.5;
                        let p = inv * Vector3::new(px, py, 1.0);
                        if m.marker.is_black_at(p.x / p.z, p.y / p.z) {
                            black += 1;
                        }
                    }
                }
                if black > 0 {
                    let idx = (y * width + x) as usize;
                    reflectance[idx] = reflectance[idx].min(1.0 - black as f32 / (S * S) as f32);
                }
            }
        }
    }
    if look.blur > 0 {
        box_blur(
            &mut reflectance,
            width as usize,
            height as usize,
            look.blur as usize,
        );
        box_blur(
            &mut reflectance,
            width as usize,
            height as usize,
            look.blur as usize,
        );
    }
    let mut rng = Pcg32::new(0x9e37_79b9_7f4a_7c15, 0);
    let pixels: Vec<u8> = reflectance
        .iter()
        .enumerate()
        .map(|(i, &r)| {
            let x = (i % width as usize) as f64 / f64::from(width.max(1));
            let light = 1.0 + (look.gradient_right - 1.0) * x;
            let value = light * (look.black + (look.white - look.black) * f64::from(r));
            let noise = if look.noise > 0.0 {
                look.noise * rng.gaussian()
            } else {
                0.0
            };
            (value + noise).round().clamp(0.0, 255.0) as u8
        })
        .collect();
    GrayImage::from_raw(width, height, pixels).unwrap()
}

fn box_blur(data: &mut [f32], w: usize, h: usize, r: usize) {
    let mut tmp = data.to_vec();
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r).min(w - 1));
            tmp[y * w + x] = data[y * w + a..=y * w + b].iter().sum::<f32>() / (b - a + 1) as f32;
        }
    }
    for y in 0..h {
        let (a, b) = (y.saturating_sub(r), (y + r).min(h - 1));
        for x in 0..w {
            data[y * w + x] = (a..=b).map(|yy| tmp[yy * w + x]).sum::<f32>() / (b - a + 1) as f32;
        }
    }
}

/// Places `count` markers of 60-120 px (or the given range) at random
/// without overlapping footprints, face-on, random in-plane rotation.
pub fn scatter(
    rng: &mut Pcg32,
    camera: &Pinhole,
    width: u32,
    height: u32,
    count: usize,
    diameters: (f64, f64),
    make: &mut dyn FnMut(usize) -> Marker,
) -> Vec<Placement> {
    let mut placed: Vec<(f64, f64, f64)> = Vec::new();
    let mut out = Vec::new();
    let mut attempts = 0;
    while out.len() < count && attempts < count * 200 {
        attempts += 1;
        let d = rng.range(diameters.0, diameters.1);
        let reach = d * 0.5 * 1.35 + 2.0;
        let u = rng.range(reach, f64::from(width) - reach);
        let v = rng.range(reach, f64::from(height) - reach);
        if placed
            .iter()
            .any(|&(pu, pv, pr)| (pu - u).hypot(pv - v) < pr + reach)
        {
            continue;
        }
        placed.push((u, v, reach));
        let marker = make(out.len());
        let psi = rng.range(0.0, std::f64::consts::TAU);
        out.push(Placement::at(camera, marker, (u, v), d, psi, 0.0, 0.0));
    }
    out
}

/// For each placement, the detection nearest its projected centre within
/// `radius` pixels.
pub fn match_detections<'a>(
    camera: &Pinhole,
    placements: &[Placement],
    detections: &'a [whycode::detect::Detection],
    radius: f64,
) -> Vec<Option<&'a whycode::detect::Detection>> {
    placements
        .iter()
        .map(|p| {
            let (u, v) = p.centre(camera);
            detections
                .iter()
                .filter(|d| (d.u - u).hypot(d.v - v) < radius)
                .min_by(|a, b| {
                    (a.u - u)
                        .hypot(a.v - v)
                        .total_cmp(&(b.u - u).hypot(b.v - v))
                })
        })
        .collect()
}
