//! Views of one marker under a known (affine) map, for ring-reading round
//! trips: drawn by `whycode::simulate` with optional motion blur, focus blur
//! and noise, with the exact image ellipse of its outline.
#![allow(dead_code)]

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::geometry::Marker;
use whycode::math::Ellipse;
use whycode::simulate::{self, Background, LooseMarker, MotionBlur, Placement, Scene, SceneObject};

pub const BLACK: f64 = 30.0;
pub const WHITE: f64 = 225.0;

/// How the marker is seen. Lengths in pixels, angles in radians.
#[derive(Debug, Clone, Copy)]
pub struct View {
    pub bits: u32,
    pub code: u32,
    /// Outer diameter of the black disc, pixels (face-on).
    pub diameter: f64,
    /// Visual counter-clockwise rotation of the marker in the image.
    pub rotation: f64,
    /// Foreshortening: the marker is squeezed by cos(tilt) along `tilt_direction`.
    pub tilt: f64,
    pub tilt_direction: f64,
    /// Sub-pixel position of the centre inside its pixel.
    pub offset: (f64, f64),
    pub gaussian_blur: f64,
    /// Motion blur length in pixels along `motion_direction`.
    pub motion_blur: f64,
    pub motion_direction: f64,
    /// Standard deviation of additive Gaussian noise, grey levels.
    pub noise: f64,
    pub seed: u64,
}

impl View {
    pub fn new(bits: u32, code: u32, diameter: f64, rotation: f64) -> View {
        View {
            bits,
            code,
            diameter,
            rotation,
            tilt: 0.0,
            tilt_direction: 0.0,
            offset: (0.37, 0.21),
            gaussian_blur: 0.0,
            motion_blur: 0.0,
            motion_direction: 0.0,
            noise: 0.0,
            seed: 1,
        }
    }
}

/// A rendered view with what the ring reader is given and what it should find.
pub struct Rendered {
    pub image: GrayImage,
    pub ellipse: Ellipse,
    /// Image direction of the marker's +x axis, atan2(dv, du).
    pub yaw: f64,
}

pub fn render(view: &View) -> Rendered {
    let marker = Marker::whycode(view.bits, view.code, view.diameter);
    render_marker(view, &marker)
}

/// The marker through `whycode::simulate`, seen through a narrow (5°) lens
/// from far away so the view is affine to well under a hundredth of a
/// pixel; the ellipse and yaw are the simulator's truth.
pub fn render_marker(view: &View, marker: &Marker) -> Rendered {
    let side = (view.diameter * 1.6 + 2.0 * view.motion_blur + 12.0).ceil() as u32;
    let camera = Camera::ideal(side, side, 5.0);
    let centre = (
        f64::from(side / 2) + view.offset.0,
        f64::from(side / 2) + view.offset.1,
    );
    // Foreshortening by cos(tilt) along the visual direction
    // `tilt_direction` (y up): a turn about the in-plane axis across it.
    let (sa, ca) = view.tilt_direction.sin_cos();
    let placement = Placement::at_pixel(
        &camera,
        marker,
        centre,
        view.diameter,
        0.0,
        0.0,
        view.rotation,
    )
    .tilted(view.tilt, Vector3::new(sa, ca, 0.0));
    let mut scene = Scene::new(camera);
    scene.background = Background::Uniform(WHITE / 255.0);
    scene.paper_reflectance = WHITE / 255.0;
    scene.ink_reflectance = BLACK / 255.0;
    scene.objects = vec![SceneObject::Marker(LooseMarker::new(*marker, 0, placement))];
    if view.motion_blur > 0.0 {
        scene.motion_blur = Some(MotionBlur {
            length_px: view.motion_blur,
            angle: view.motion_direction,
        });
    }
    scene.focus_blur_px = view.gaussian_blur;
    scene.noise = view.noise;
    scene.seed = view.seed;
    let (image, truth) = simulate::render(&scene);
    let m = &truth.markers[0];
    let e = m.ellipse.expect("the marker is in view");
    Rendered {
        image,
        ellipse: Ellipse {
            u: e.u,
            v: e.v,
            semi_major: e.semi_major,
            semi_minor: e.semi_minor,
            angle: e.angle,
        },
        yaw: m.yaw,
    }
}
