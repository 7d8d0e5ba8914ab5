//! Synthetic views of one marker under a known affine map, for ring-reading
//! round trips: point-sampled from `geometry::Marker::is_black_at` with
//! supersampling, then optional motion blur, Gaussian blur and noise.
#![allow(dead_code)]

use image::GrayImage;
use whycode::detect::ring::ImageEllipse;
use whycode::geometry::Marker;
use whycode::simulate::rng::Pcg32;

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
    pub ellipse: ImageEllipse,
    /// Image direction of the marker's +x axis, atan2(dv, du).
    pub yaw: f64,
}

/// 2x2 matrix mapping marker-frame units (y up) to image pixels (v down).
fn linear_map(view: &View) -> [[f64; 2]; 2] {
    let scale = 1.0; // marker millimetres are pixels here
    let (sa, ca) = view.tilt_direction.sin_cos();
    let (sr, cr) = view.rotation.sin_cos();
    let k = view.tilt.cos();
    // Visual frame (y up): R(a) diag(1, k) R(-a) R(rotation).
    let squeeze = [
        [ca * ca + k * sa * sa, ca * sa * (1.0 - k)],
        [ca * sa * (1.0 - k), sa * sa + k * ca * ca],
    ];
    let rot = [[cr, -sr], [sr, cr]];
    let mut m = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            m[i][j] = scale * (squeeze[i][0] * rot[0][j] + squeeze[i][1] * rot[1][j]);
        }
    }
    // Image v points down.
    [[m[0][0], m[0][1]], [-m[1][0], -m[1][1]]]
}

pub fn render(view: &View) -> Rendered {
    let marker = Marker::whycode(view.bits, view.code, view.diameter);
    render_marker(view, &marker)
}

pub fn render_marker(view: &View, marker: &Marker) -> Rendered {
    let m = linear_map(view);
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let inv = [
        [m[1][1] / det, -m[0][1] / det],
        [-m[1][0] / det, m[0][0] / det],
    ];
    let radius = view.diameter / 2.0;
    let side = (view.diameter * 1.6 + 2.0 * view.motion_blur + 12.0).ceil() as u32;
    let cu = f64::from(side / 2) + view.offset.0;
    let cv = f64::from(side / 2) + view.offset.1;
    const SS: usize = 4;
    let motion_steps = if view.motion_blur > 0.0 {
        (view.motion_blur * 4.0).ceil() as usize + 1
    } else {
        1
    };
    let (ms, mc) = view.motion_direction.sin_cos();
    let mut data = vec![0f64; (side * side) as usize];
    for py in 0..side {
        for px in 0..side {
            let mut white = 0usize;
            let mut total = 0usize;
            for step in 0..motion_steps {
                let shift = if motion_steps > 1 {
                    view.motion_blur * (step as f64 / (motion_steps - 1) as f64 - 0.5)
                } else {
                    0.0
                };
                for sy in 0..SS {
                    for sx in 0..SS {
                        let x =
                            f64::from(px) - 0.5 + (sx as f64 + 0.5) / SS as f64 - cu - shift * mc;
                        let y =
                            f64::from(py) - 0.5 + (sy as f64 + 0.5) / SS as f64 - cv - shift * ms;
                        let mx = inv[0][0] * x + inv[0][1] * y;
                        let my = inv[1][0] * x + inv[1][1] * y;
                        if !marker.is_black_at(mx, my) {
                            white += 1;
                        }
                        total += 1;
                    }
                }
            }
            data[(py * side + px) as usize] = BLACK + (WHITE - BLACK) * white as f64 / total as f64;
        }
    }
    let mut image = GrayImage::new(side, side);
    for (i, p) in image.pixels_mut().enumerate() {
        p.0[0] = data[i].round().clamp(0.0, 255.0) as u8;
    }
    if view.gaussian_blur > 0.0 {
        image = image::imageops::blur(&image, view.gaussian_blur as f32);
    }
    if view.noise > 0.0 {
        let mut rng = Pcg32::new(view.seed, 0);
        for p in image.pixels_mut() {
            let n = rng.gaussian() * view.noise;
            p.0[0] = (f64::from(p.0[0]) + n).round().clamp(0.0, 255.0) as u8;
        }
    }
    // The outer circle of radius R through the map: M M^T's eigen-system.
    let a = m[0][0] * m[0][0] + m[0][1] * m[0][1];
    let b = m[0][0] * m[1][0] + m[0][1] * m[1][1];
    let c = m[1][0] * m[1][0] + m[1][1] * m[1][1];
    let mean = 0.5 * (a + c);
    let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    let ellipse = ImageEllipse {
        u: cu,
        v: cv,
        semi_major: radius * (mean + root).sqrt(),
        semi_minor: radius * (mean - root).max(0.0).sqrt(),
        angle,
    };
    Rendered {
        image,
        ellipse,
        yaw: m[1][0].atan2(m[0][0]),
    }
}
