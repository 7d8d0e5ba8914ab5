//! Perspective-correct yaw. The ring reader works along the image ellipse,
//! which is exact for an affine view; under strong perspective the marker
//! angle is a projective function of the ellipse parameter and the yaw
//! drifts by degrees at 60° of tilt. Once the pose gives the marker plane,
//! the ring can be sampled at true marker angles: the measured positions
//! of the code's sector edges, compared with where the decoded code puts
//! them, give the in-plane rotation directly.

use nalgebra::Vector3;

use super::ellipse::sample;
use super::segment::Gray;
use crate::camera::Camera;
use crate::geometry::{sector_is_black, sector_width, RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::pose::Pose;

/// Samples per ring sector along the rectified circle.
const SAMPLES_PER_SECTOR: usize = 24;

/// The pose with its +x axis turned in the marker plane so that the sector
/// edges of `code` fall where the image shows them. None when the edges
/// cannot be measured (then keep the pose as it was).
pub fn refine_rotation(
    image: Gray<'_>,
    camera: &Camera,
    pose: &Pose,
    radius_m: f64,
    bits: u32,
    code: u32,
) -> Option<Pose> {
    let sectors = 2 * bits as usize;
    let w = sector_width(bits);
    let n = sectors * SAMPLES_PER_SECTOR;
    let x = pose.rotation.column(0).into_owned();
    let z = pose.rotation.column(2).into_owned();
    let y = z.cross(&x);
    let radii = [0.25, 0.5, 0.75]
        .map(|k| (RING_INNER_RATIO + (WHYCODE_WHITE_RATIO - RING_INNER_RATIO) * k) * radius_m);
    let mut profile = Vec::with_capacity(n);
    for j in 0..n {
        let theta = std::f64::consts::TAU * j as f64 / n as f64;
        let (s, c) = theta.sin_cos();
        let direction: Vector3<f64> = x * c + y * s;
        let mut sum = 0.0;
        for r in radii {
            let (u, v) = camera.project(&(pose.position + direction * r))?;
            sum += sample(image, u, v)?;
        }
        profile.push(sum / radii.len() as f64);
    }
    // Grey levels of the black and the white sectors as they are now.
    let (mut black, mut white, mut nb, mut nw) = (0.0, 0.0, 0, 0);
    for (j, &p) in profile.iter().enumerate() {
        let within = j % SAMPLES_PER_SECTOR;
        if !(SAMPLES_PER_SECTOR / 4..SAMPLES_PER_SECTOR * 3 / 4).contains(&within) {
            continue;
        }
        if sector_is_black(bits, code, (j / SAMPLES_PER_SECTOR) as u32) {
            black += p;
            nb += 1;
        } else {
            white += p;
            nw += 1;
        }
    }
    if nb == 0 || nw == 0 {
        return None;
    }
    let (black, white) = (black / f64::from(nb), white / f64::from(nw));
    if white - black < 8.0 {
        return None;
    }
    let mid = (black + white) / 2.0;
    let at = |j: isize| profile[j.rem_euclid(n as isize) as usize];
    let mut offsets = Vec::new();
    for k in 0..sectors {
        let before = sector_is_black(bits, code, ((k + sectors - 1) % sectors) as u32);
        let after = sector_is_black(bits, code, k as u32);
        if before == after {
            continue;
        }
        let rising = before; // black → white going counter-clockwise
        let centre = (k * SAMPLES_PER_SECTOR) as isize;
        let half = (SAMPLES_PER_SECTOR / 2) as isize;
        let mut best: Option<f64> = None;
        for j in centre - half..centre + half {
            let (p, q) = (at(j), at(j + 1));
            let crosses = if rising {
                p < mid && q >= mid
            } else {
                p >= mid && q < mid
            };
            if crosses {
                let position = j as f64 + (mid - p) / (q - p) - centre as f64;
                if best.map_or(true, |b: f64| position.abs() < b.abs()) {
                    best = Some(position);
                }
            }
        }
        offsets.push(best? * w / SAMPLES_PER_SECTOR as f64);
    }
    offsets.sort_by(f64::total_cmp);
    let phi = offsets[offsets.len() / 2];
    // The edges sit at angle φ in the current frame: +x turns by φ.
    let (s, c) = phi.sin_cos();
    let new_x = x * c + y * s;
    let new_y = z.cross(&new_x);
    Some(Pose::new(
        pose.position,
        nalgebra::Matrix3::from_columns(&[new_x, new_y, z]),
    ))
}
