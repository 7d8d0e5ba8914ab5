//! Camera views for the detector's round trips and benchmarks: markers
//! placed at pixels of a distortion-free camera and drawn by
//! `whycode::simulate` on white paper that fills the frame, with an
//! optional light gradient, blur and noise; the truth is the simulator's.

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{
    self, Background, GroundTruth, LooseMarker, Placement, Scene, SceneObject,
};

/// A camera without distortion, square pixels of focal length `f` and the
/// principal point at the image's centre.
pub fn camera(width: u32, height: u32, f: f64) -> Camera {
    Camera {
        fx: f,
        fy: f,
        cx: f64::from(width) / 2.0,
        cy: f64::from(height) / 2.0,
        distortion: [0.0; 5],
        width,
        height,
    }
}

/// `marker` (with ID `id`) centred on the pixel (u, v), `diameter_px`
/// across face-on, turned by `roll` in its own plane and then tilted by
/// `tilt` about the axis across the image at `axis` radians from +u
/// towards +v (see [`Placement::at_pixel`], [`Placement::tilted`]).
pub fn marker_at(
    camera: &Camera,
    (marker, id): (Marker, u32),
    (u, v): (f64, f64),
    diameter_px: f64,
    roll: f64,
    (tilt, axis): (f64, f64),
) -> LooseMarker {
    let placement = Placement::at_pixel(camera, &marker, (u, v), diameter_px, 0.0, 0.0, roll)
        .tilted(tilt, Vector3::new(axis.cos(), axis.sin(), 0.0));
    LooseMarker::new(marker, id, placement)
}

/// How the paper, the ink and the camera's picture look.
#[derive(Debug, Clone, Copy)]
pub struct Look {
    /// Grey of the paper.
    pub white: f64,
    /// Grey of the ink.
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

/// The markers on white paper that fills the frame, ready for
/// `whycode::simulate` (each marker's card is cut to its black disc's
/// square, so neighbouring cards never cover a marker).
pub fn scene(camera: &Camera, markers: &[LooseMarker], look: Look) -> Scene {
    let mut scene = Scene::new(*camera);
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
            SceneObject::Marker(LooseMarker {
                card_half_mm: m.marker.outer_radius(),
                ..m.clone()
            })
        })
        .collect();
    scene
}

/// Draws [`scene`]: the image and the truth of every marker.
pub fn render(camera: &Camera, markers: &[LooseMarker], look: Look) -> (GrayImage, GroundTruth) {
    simulate::render(&scene(camera, markers, look))
}

/// Places `count` markers of `diameters` pixels at random, without
/// overlapping footprints, face-on, each turned at random in its plane;
/// `make(k)` gives the k-th marker and its ID. Fewer than `count` when
/// the frame is too full.
pub fn scatter(
    rng: &mut Pcg32,
    camera: &Camera,
    count: usize,
    diameters: (f64, f64),
    make: &mut dyn FnMut(usize) -> (Marker, u32),
) -> Vec<LooseMarker> {
    let (width, height) = (f64::from(camera.width), f64::from(camera.height));
    let mut placed: Vec<(f64, f64, f64)> = Vec::new();
    let mut out = Vec::new();
    let mut attempts = 0;
    while out.len() < count && attempts < count * 200 {
        attempts += 1;
        let d = rng.range(diameters.0, diameters.1);
        let reach = d * 0.5 * 1.35 + 2.0;
        let u = rng.range(reach, width - reach);
        let v = rng.range(reach, height - reach);
        if placed
            .iter()
            .any(|&(pu, pv, pr)| (pu - u).hypot(pv - v) < pr + reach)
        {
            continue;
        }
        placed.push((u, v, reach));
        let marker = make(out.len());
        let roll = rng.range(0.0, std::f64::consts::TAU);
        out.push(marker_at(camera, marker, (u, v), d, roll, (0.0, 0.0)));
    }
    out
}

/// Darkens the image beyond a straight soft-edged line (a cast shadow,
/// which the simulator's smooth light cannot draw):
/// pixels on the far side of the line through (u0, v0) with direction
/// `angle` get `factor` of their light, over a `soft` px transition.
pub fn cast_shadow(
    image: &mut GrayImage,
    (u0, v0): (f64, f64),
    angle: f64,
    factor: f64,
    soft: f64,
) {
    let (s, c) = angle.sin_cos();
    for (x, y, p) in image.enumerate_pixels_mut() {
        // Signed distance from the line, positive on the shadow side.
        let d = -(f64::from(x) - u0) * s + (f64::from(y) - v0) * c;
        let t = (d / soft + 0.5).clamp(0.0, 1.0);
        let light = 1.0 - (1.0 - factor) * t;
        p.0[0] = (f64::from(p.0[0]) * light).round().clamp(0.0, 255.0) as u8;
    }
}
