//! A printed square picture on its own card: another kind of fiducial (an
//! AprilTag, an ArUco marker) or any bitmap, at an exact physical size, so
//! other detectors can be measured on the same scenes as ours.

use super::Placement;
use crate::camera::Camera;
use image::GrayImage;
use serde::{Deserialize, Serialize};

/// A square bitmap printed at `side_mm` on a white card, one printed cell
/// per bitmap pixel (sharp edges, as a laser printer draws a tag).
#[derive(Debug, Clone, PartialEq)]
pub struct PrintedSquare {
    /// The picture as printed, top row first; a pixel darker than 128 is ink.
    pub bitmap: GrayImage,
    /// Side of the printed bitmap, mm (the bitmap is stretched to a square).
    pub side_mm: f64,
    /// Half the side of the white card around it, mm (at least `side_mm / 2`).
    pub card_half_mm: f64,
    /// Identity reported in the ground truth.
    pub id: u32,
    /// Pose of the square's centre: +x to the bitmap's right, +y to its top.
    pub placement: Placement,
}

impl PrintedSquare {
    /// `bitmap` printed `side_mm` wide on a card of the same side (its own
    /// border is the only margin).
    pub fn new(bitmap: GrayImage, side_mm: f64, id: u32, placement: Placement) -> PrintedSquare {
        PrintedSquare {
            bitmap,
            side_mm,
            card_half_mm: side_mm / 2.0,
            id,
            placement,
        }
    }

    /// True when the object-frame point (x, y) in mm is inked.
    pub fn is_black_at(&self, x: f64, y: f64) -> bool {
        let half = self.side_mm / 2.0;
        if x.abs() >= half || y.abs() >= half {
            return false;
        }
        let (w, h) = self.bitmap.dimensions();
        let col = (((x + half) / self.side_mm) * f64::from(w)) as u32;
        let row = (((half - y) / self.side_mm) * f64::from(h)) as u32;
        self.bitmap.get_pixel(col.min(w - 1), row.min(h - 1)).0[0] < 128
    }

    /// The corners of the printed bitmap in its own frame, mm: top-left,
    /// top-right, bottom-right, bottom-left as printed.
    pub fn corners_mm(&self) -> [(f64, f64); 4] {
        let h = self.side_mm / 2.0;
        [(-h, h), (h, h), (h, -h), (-h, -h)]
    }
}

/// Where a [`PrintedSquare`] lies in the image.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrueSquare {
    /// The square's identity.
    pub id: u32,
    /// Projected centre, pixels.
    pub u: f64,
    /// Row of the projected centre, pixels.
    pub v: f64,
    /// The bitmap's corners in pixels: top-left, top-right, bottom-right,
    /// bottom-left as printed.
    pub corners: [[f64; 2]; 4],
    /// Longest projected side, pixels.
    pub side_px: f64,
    /// Facing the camera and wholly inside the frame.
    pub visible: bool,
    /// Centre in the camera frame, metres.
    pub position: [f64; 3],
    /// Rotation square → camera, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Unit normal of the printed face in the camera frame.
    pub normal: [f64; 3],
}

pub(super) fn true_square(camera: &Camera, square: &PrintedSquare) -> TrueSquare {
    let p = &square.placement;
    let (u, v) = camera.project(&p.position).unwrap_or((f64::NAN, f64::NAN));
    let corners = square.corners_mm().map(|(x, y)| {
        camera
            .project(&p.to_camera_mm(x, y))
            .map_or([f64::NAN, f64::NAN], |(u, v)| [u, v])
    });
    let side_px = (0..4)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            (a[0] - b[0]).hypot(a[1] - b[1])
        })
        .fold(0.0, f64::max);
    let normal = p.normal();
    let facing = -normal.dot(&p.position) > 1e-9 * p.position.norm();
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let inside = corners
        .iter()
        .all(|c| c[0] >= -0.5 && c[1] >= -0.5 && c[0] <= w - 0.5 && c[1] <= h - 0.5);
    let r = p.rotation;
    TrueSquare {
        id: square.id,
        u,
        v,
        corners,
        side_px,
        visible: facing && inside && side_px >= 1.0,
        position: [p.position.x, p.position.y, p.position.z],
        rotation: [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        ],
        normal: [normal.x, normal.y, normal.z],
    }
}
