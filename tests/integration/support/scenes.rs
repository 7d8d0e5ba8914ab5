//! Camera views for the detector's tests and benchmarks: markers placed in
//! front of a pinhole camera and drawn by `whycode::simulate` on white
//! paper, with optional light gradient, blur and noise. Ground truth comes
//! from the same projection.
#![allow(dead_code)]

use image::GrayImage;
use nalgebra::{Matrix3, Vector3};
use whycode::camera::Camera;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{self, Background, LooseMarker, Scene, SceneObject};

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

/// Draws the markers on white paper that fills the frame, with
/// `whycode::simulate` (each marker's card is cut to its black disc's
/// square, so neighbouring cards never cover a marker).
pub fn render(
    width: u32,
    height: u32,
    camera: &Pinhole,
    markers: &[Placement],
    look: Look,
) -> GrayImage {
    let mut scene = Scene::new(Camera {
        fx: camera.f,
        fy: camera.f,
        cx: camera.cx,
        cy: camera.cy,
        distortion: [0.0; 5],
        width,
        height,
    });
    let paper = look.white / 255.0;
    scene.background = Background::Uniform(paper);
    scene.paper_reflectance = paper;
    scene.ink_reflectance = look.black / 255.0;
    scene.gradient = 1.0 / look.gradient_right;
    // A box blur of radius r applied twice has the variance of a Gaussian
    // of sigma² = 2 ((2r + 1)² - 1) / 12.
    let r = f64::from(look.blur);
    scene.focus_blur_px = (((2.0 * r + 1.0).powi(2) - 1.0) / 6.0).sqrt();
    scene.noise = look.noise;
    scene.objects = markers
        .iter()
        .map(|m| {
            let placement = simulate::Placement::new(m.position / 1000.0, m.rotation);
            let mut loose = LooseMarker::new(m.marker, 0, placement);
            loose.card_half_mm = m.marker.outer_radius();
            SceneObject::Marker(loose)
        })
        .collect();
    simulate::render(&scene).0
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
