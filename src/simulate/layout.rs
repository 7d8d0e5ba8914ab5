//! Ready-made arrangements: a sheet page in front of the camera, loose
//! markers in a grid or scattered, a blot over a marker's ring.

use super::{Blot, LooseMarker, Placement};
use crate::camera::Camera;
use crate::geometry::{sector_width, Marker, MarkerKind, RING_SAMPLE_RATIO};
use crate::math::Pcg32;
use nalgebra::Vector3;

/// Distance (metres) at which an object `width_mm` × `height_mm` seen
/// face-on fills `fill` (e.g. 0.8) of the frame in its tighter direction.
pub fn distance_to_fill(camera: &Camera, width_mm: f64, height_mm: f64, fill: f64) -> f64 {
    let by_width = camera.fx * width_mm / (fill * f64::from(camera.width));
    let by_height = camera.fy * height_mm / (fill * f64::from(camera.height));
    by_width.max(by_height) / 1000.0
}

/// An object centred in the view (on the ray through the principal point)
/// at `distance` metres, turned by tilt, pan and roll (see
/// [`Placement::viewed`]).
pub fn centred(distance: f64, tilt: f64, pan: f64, roll: f64) -> Placement {
    Placement::viewed(Vector3::new(0.0, 0.0, distance), tilt, pan, roll)
}

/// Markers on a flat board centred in the view: a grid with a spacing of
/// two diameters, rows filled left to right, top to bottom.
pub fn marker_grid(markers: &[(Marker, u32)], board: &Placement) -> Vec<LooseMarker> {
    let n = markers.len();
    if n == 0 {
        return Vec::new();
    }
    let cols = (n as f64 * 16.0 / 9.0).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(cols);
    let spacing = markers
        .iter()
        .map(|(m, _)| m.diameter_mm)
        .fold(0.0, f64::max)
        * 2.0;
    markers
        .iter()
        .enumerate()
        .map(|(k, &(marker, id))| {
            let (col, row) = ((k % cols) as f64, (k / cols) as f64);
            let x = (col - (cols as f64 - 1.0) / 2.0) * spacing;
            let y = ((rows as f64 - 1.0) / 2.0 - row) * spacing;
            let placement = Placement::new(board.to_camera_mm(x, y), board.rotation);
            LooseMarker::new(marker, id, placement)
        })
        .collect()
}

/// Markers scattered through the view at `distance` metres (± 30 %), each
/// with a random in-plane rotation and an out-of-plane turn of up to
/// `max_tilt` radians, kept apart from each other and inside the frame.
/// Markers that do not fit after many tries are left out.
pub fn marker_scatter(
    camera: &Camera,
    markers: &[(Marker, u32)],
    distance: f64,
    max_tilt: f64,
    seed: u64,
) -> Vec<LooseMarker> {
    let mut rng = Pcg32::new(seed, 31);
    let mut placed: Vec<(LooseMarker, f64, f64, f64)> = Vec::new();
    for &(marker, id) in markers {
        for _ in 0..200 {
            let z = distance * rng.range(0.7, 1.3);
            let u = rng.range(0.0, f64::from(camera.width));
            let v = rng.range(0.0, f64::from(camera.height));
            let (x, y) = camera.undistort(u, v);
            let position = Vector3::new(x * z, y * z, z);
            let radius_px = camera.fx * marker.outer_radius() * 1.6 / 1000.0 / z;
            let fits = u > radius_px
                && v > radius_px
                && u < f64::from(camera.width) - radius_px
                && v < f64::from(camera.height) - radius_px
                && placed
                    .iter()
                    .all(|(_, pu, pv, pr)| (pu - u).hypot(pv - v) > pr + radius_px);
            if fits {
                let tilt = rng.range(-max_tilt, max_tilt);
                let pan = rng.range(-max_tilt, max_tilt);
                let roll = rng.range(0.0, std::f64::consts::TAU);
                let placement = Placement::viewed(position, tilt, pan, roll);
                placed.push((LooseMarker::new(marker, id, placement), u, v, radius_px));
                break;
            }
        }
    }
    placed.into_iter().map(|(m, ..)| m).collect()
}

/// An ink smear over a marker's code ring: three overlapping black discs
/// along the ring over two adjacent white sectors of two neighbouring bits
/// (a 0 bit followed by a 1 bit: black-white, white-black), so that both
/// bits read as neither 0 nor 1. A single erased bit a decoder could still
/// recover from the family's distance; two it cannot with distance 2. The
/// smear stays inside the ring and leaves the black disc's outline alone.
/// The marker is centred at (x, y) in print coordinates with y down (a
/// page; `y_up = false`) or y up (a marker frame; `y_up = true`).
pub fn ring_blots(marker: &Marker, x: f64, y: f64, y_up: bool) -> Vec<Blot> {
    let r = marker.outer_radius();
    let (boundary, step) = match marker.kind {
        MarkerKind::WhyCode { bits, code } => {
            let bit = |i: u32| (code >> (bits - 1 - (i % bits))) & 1;
            let i = (0..bits)
                .find(|&i| bit(i) == 0 && bit(i + 1) == 1)
                .unwrap_or(0);
            let w = sector_width(bits);
            (f64::from(2 * i + 2) * w, 0.6 * w)
        }
        MarkerKind::WhyCon => (0.0, std::f64::consts::PI / 12.0),
    };
    let ring = RING_SAMPLE_RATIO * r;
    [-1.0, 0.0, 1.0]
        .iter()
        .map(|k| {
            let angle = boundary + k * step;
            let (dx, dy) = (ring * angle.cos(), ring * angle.sin());
            Blot {
                x_mm: x + dx,
                y_mm: if y_up { y + dy } else { y - dy },
                radius_mm: 0.12 * r,
                black: true,
            }
        })
        .collect()
}
