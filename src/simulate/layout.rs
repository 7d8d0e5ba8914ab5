//! Ready-made arrangements: a marker at a pixel, a sheet page in front of
//! the camera, loose markers in a grid or scattered, a blot over a marker's
//! ring.

use super::{Blot, LooseMarker, Placement};
use crate::camera::Camera;
use crate::geometry::{sector_width, Marker, MarkerKind, RING_SAMPLE_RATIO};
use crate::math::Pcg32;
use nalgebra::{Matrix2, Rotation3, Unit, Vector3};

impl Placement {
    /// "This marker at this pixel, this many pixels across": the placement
    /// whose centre projects to the pixel (u, v) of `camera` (through its
    /// lens distortion), at the depth where `marker`, face-on (parallel to
    /// the image plane), is `diameter_px` across at its widest there; then
    /// turned by tilt, pan and roll as in [`Placement::viewed`].
    ///
    /// With distortion the size holds to first order: the lens's largest
    /// local stretch at (u, v) scales the depth.
    pub fn at_pixel(
        camera: &Camera,
        marker: &Marker,
        (u, v): (f64, f64),
        diameter_px: f64,
        tilt: f64,
        pan: f64,
        roll: f64,
    ) -> Placement {
        let (x, y) = camera.undistort(u, v);
        let z = pixels_per_unit(camera, x, y) * (marker.diameter_mm / 1000.0) / diameter_px;
        Placement::viewed(Vector3::new(x * z, y * z, z), tilt, pan, roll)
    }

    /// Turned by `tilt` radians about the line through its origin parallel
    /// to the image plane along `axis` (a direction in the camera's x-y
    /// plane: x right, y down; any length).
    pub fn tilted(self, tilt: f64, axis: Vector3<f64>) -> Placement {
        let turn = Rotation3::from_axis_angle(&Unit::new_normalize(axis), tilt);
        Placement::new(self.position, turn.matrix() * self.rotation)
    }

    /// A face-on placement (see [`Placement::at_pixel`]) turned to face its
    /// own line of sight instead of the optical axis, then tilted by `view`
    /// radians about an axis across that line: so `view` is the angle
    /// between the object's normal and the direction to the camera. `axis`
    /// is the tilt axis as it would lie for an object on the optical axis
    /// (a direction in the camera's x-y plane; any length). Off the optical
    /// axis a turn about the camera's axes ([`Placement::viewed`]) adds up
    /// to half the field of view to the view angle; this does not.
    pub fn tilted_from_sight(self, view: f64, axis: Vector3<f64>) -> Placement {
        let to_ray = Rotation3::rotation_between(&Vector3::z(), &self.position)
            .unwrap_or_else(Rotation3::identity);
        let tilt = Rotation3::from_axis_angle(&Unit::new_normalize(to_ray * axis), view);
        Placement::new(
            self.position,
            tilt.matrix() * to_ray.matrix() * self.rotation,
        )
    }
}

/// The lens's largest stretch at the ideal normalised point (x, y): pixels
/// per unit of the normalised image plane, along the direction stretched
/// most. Without distortion that is the larger focal length.
fn pixels_per_unit(camera: &Camera, x: f64, y: f64) -> f64 {
    if !camera.has_distortion() {
        return camera.fx.max(camera.fy);
    }
    let h = 1e-6;
    let at = |dx: f64, dy: f64| camera.distort_normalized(x + dx, y + dy);
    let (right, left, down, up) = (at(h, 0.0), at(-h, 0.0), at(0.0, h), at(0.0, -h));
    let jacobian = Matrix2::new(
        right.0 - left.0,
        down.0 - up.0,
        right.1 - left.1,
        down.1 - up.1,
    ) / (2.0 * h);
    jacobian.singular_values().max()
}

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

/// [`marker_scatter`] that places every marker or fails: a scene missing
/// some of the markers asked for would pass for a detector that lost them.
/// The error says how many did not fit and what would make room.
pub fn marker_scatter_all(
    camera: &Camera,
    markers: &[(Marker, u32)],
    distance: f64,
    max_tilt: f64,
    seed: u64,
) -> Result<Vec<LooseMarker>, ScatterOverflow> {
    let placed = marker_scatter(camera, markers, distance, max_tilt, seed);
    if placed.len() < markers.len() {
        return Err(ScatterOverflow {
            placed: placed.len(),
            asked: markers.len(),
            width: camera.width,
            height: camera.height,
        });
    }
    Ok(placed)
}

/// More markers asked of [`marker_scatter_all`] than fit into the view.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "only {placed} of {asked} markers fit into the {width}x{height} view without overlapping \
     ({} did not); scatter fewer, make them smaller (--diameter), move them further away \
     (--distance) or use --layout grid",
    asked - placed
)]
pub struct ScatterOverflow {
    /// How many markers fit.
    pub placed: usize,
    /// How many were asked for.
    pub asked: usize,
    /// The view's width, pixels.
    pub width: u32,
    /// The view's height, pixels.
    pub height: u32,
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
