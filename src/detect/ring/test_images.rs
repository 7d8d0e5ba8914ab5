//! Small images for the ring modules' unit tests: literal pixel arrays
//! (`gray_image!`, as imageproc writes them) and markers drawn pixel by
//! pixel from [`Marker::is_black_at`], each pixel the mean of a grid of
//! samples over its area (no renderer, no blur unless asked).

use image::GrayImage;

use crate::geometry::Marker;
use crate::math::Ellipse;

/// A grey image from rows of pixel values, rows separated by `;`.
macro_rules! gray_image {
    ($($($value:expr),+);+ $(;)?) => {{
        let rows: Vec<Vec<u8>> = vec![$(vec![$($value),+]),+];
        let (height, width) = (rows.len() as u32, rows[0].len() as u32);
        image::GrayImage::from_raw(width, height, rows.concat()).expect("rows of one width")
    }};
}

/// Grey levels of ink and paper in the drawn markers.
pub const INK: u8 = 20;
pub const PAPER: u8 = 230;

/// A face-on marker `diameter` pixels across centred at (`u`, `v`) in an
/// image `size` pixels square, turned visually counter-clockwise by
/// `turn` radians (its +x axis then points along image angle `-turn`);
/// each pixel averages 8x8 samples. Also its outline.
pub fn draw(
    marker: &Marker,
    diameter: f64,
    size: u32,
    (u, v): (f64, f64),
    turn: f64,
) -> (GrayImage, Ellipse) {
    const GRID: u32 = 8;
    let mm_per_px = 2.0 * marker.outer_radius() / diameter;
    let (s, c) = turn.sin_cos();
    let image = GrayImage::from_fn(size, size, |x, y| {
        let mut black = 0;
        for i in 0..GRID {
            for j in 0..GRID {
                let du = f64::from(x) - 0.5 + (f64::from(i) + 0.5) / f64::from(GRID) - u;
                let dv = f64::from(y) - 0.5 + (f64::from(j) + 0.5) / f64::from(GRID) - v;
                // Image v points down, the marker's y up; undo the turn.
                let (px, py) = (du * mm_per_px, -dv * mm_per_px);
                let (mx, my) = (c * px + s * py, -s * px + c * py);
                black += u32::from(marker.is_black_at(mx, my));
            }
        }
        let share = f64::from(black) / f64::from(GRID * GRID);
        let grey = f64::from(PAPER) - share * f64::from(PAPER - INK);
        image::Luma([grey.round() as u8])
    });
    let outline = Ellipse {
        u,
        v,
        semi_major: diameter / 2.0,
        semi_minor: diameter / 2.0,
        angle: 0.0,
    };
    (image, outline)
}

/// The smallest difference between two angles, radians.
pub fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}
