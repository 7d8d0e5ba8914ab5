//! Perspective-correct yaw. The ring reader works along the image ellipse,
//! which is exact for an affine view; under strong perspective the marker
//! angle is a projective function of the ellipse parameter and the yaw
//! drifts by degrees at 60° of tilt. Once the pose gives the marker plane,
//! the ring can be sampled at true marker angles: the measured positions
//! of the code's sector edges, compared with where the decoded code puts
//! them, give the in-plane rotation directly.

use super::ellipse::sample;
use super::segment::Gray;
use std::sync::OnceLock;

use crate::camera::Camera;
use crate::family::MAX_BITS;
use crate::geometry::{sector_is_black, sector_width, RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::{angle, Ellipse};
use crate::pose::Pose;

/// Samples per ring sector along the rectified circle.
const SAMPLES_PER_SECTOR: usize = 12;

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
    if !(1..=MAX_BITS).contains(&bits) {
        return None;
    }
    let sectors = 2 * bits as usize;
    let per_sector = samples_per_sector(camera, pose, radius_m, sectors);
    let n = sectors * per_sector;
    let x = pose.rotation.column(0).into_owned();
    let z = pose.rotation.column(2).into_owned();
    let y = z.cross(&x);
    let radii = [0.25, 0.5, 0.75]
        .map(|k| (RING_INNER_RATIO + (WHYCODE_WHITE_RATIO - RING_INNER_RATIO) * k) * radius_m);
    let plane = camera.plane_projection(pose.position, x, y);
    // The three radii of an angle share its direction in the image and
    // are read independently of one another and of the angle before (its
    // cosine and sine come from a table, not from a rotation walked sample
    // by sample): this loop was a fifth of a tracked frame with pose.
    let mut profile = Vec::with_capacity(n);
    for &angle in unit_circle(n) {
        let mut sum = 0.0;
        for point in plane.project_radii(angle, &radii) {
            let (u, v) = point?;
            sum += sample(image, u, v)?;
        }
        profile.push(sum / radii.len() as f64);
    }
    let phi = code_edge_offset(&profile, bits, code, per_sector, 1.0)?;
    // The edges sit at angle φ in the current frame: +x turns by φ.
    let (s, c) = phi.sin_cos();
    let new_x = x * c + y * s;
    let new_y = z.cross(&new_x);
    Some(Pose::new(
        pose.position,
        nalgebra::Matrix3::from_columns(&[new_x, new_y, z]),
    ))
}

/// Samples per sector along the rectified ring: about [`SAMPLE_SPACING_PX`]
/// apart on the ring's middle circle, [`MIN_SAMPLES_PER_SECTOR`] to
/// [`SAMPLES_PER_SECTOR`]. Closer samples than that only interpolate the
/// same pixels again, and a 14-bit ring of a 90 px marker has sectors under
/// 5 px long.
fn samples_per_sector(camera: &Camera, pose: &Pose, radius_m: f64, sectors: usize) -> usize {
    let middle_m = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO) * radius_m;
    let middle_px = middle_m * 0.5 * (camera.fx + camera.fy) / pose.position.z;
    let arc_px = std::f64::consts::TAU * middle_px / sectors as f64;
    let wanted = (arc_px / SAMPLE_SPACING_PX).ceil();
    if wanted.is_nan() {
        return SAMPLES_PER_SECTOR;
    }
    (wanted as usize).clamp(MIN_SAMPLES_PER_SECTOR, SAMPLES_PER_SECTOR)
}

/// Spacing of the samples along the rectified ring, pixels: as close as
/// 12 samples a sector in yaw, for fewer samples on long codes; wider
/// spacing costs yaw (the detector bar's rows 1a/1b: docs/detection.md,
/// "Where the time goes").
const SAMPLE_SPACING_PX: f64 = 0.6;
const MIN_SAMPLES_PER_SECTOR: usize = 6;
const MAX_SAMPLES: usize = 2 * MAX_BITS as usize * SAMPLES_PER_SECTOR;

/// The cosines and sines of `n` angles evenly spread round the circle from
/// angle 0, worked out once per count by walking a fixed rotation.
fn unit_circle(n: usize) -> &'static [(f64, f64)] {
    static TABLES: [OnceLock<Vec<(f64, f64)>>; MAX_SAMPLES + 1] =
        [const { OnceLock::new() }; MAX_SAMPLES + 1];
    TABLES[n].get_or_init(|| {
        let (step_sin, step_cos) = (std::f64::consts::TAU / n as f64).sin_cos();
        let (mut s, mut c) = (0.0f64, 1.0f64);
        (0..n)
            .map(|_| {
                let angle = (c, s);
                (s, c) = (s * step_cos + c * step_sin, c * step_cos - s * step_sin);
                angle
            })
            .collect()
    })
}

/// Where the code's sector edges are in a ring profile sampled at equal
/// marker angles from the current +x axis, relative to where the code puts
/// them: the median offset (radians), or None when fewer than
/// `min_found` of the edges are found or the sectors show no contrast.
fn code_edge_offset(
    profile: &[f64],
    bits: u32,
    code: u32,
    per_sector: usize,
    min_found: f64,
) -> Option<f64> {
    let sectors = 2 * bits as usize;
    let n = profile.len();
    let w = sector_width(bits);
    // Grey levels of the black and the white sectors as they are now.
    let (mut black, mut white, mut nb, mut nw) = (0.0, 0.0, 0, 0);
    for (k, sector) in profile.chunks_exact(per_sector).enumerate() {
        let middle = &sector[per_sector / 4..per_sector * 3 / 4];
        let (sum, count) = if sector_is_black(bits, code, k as u32) {
            (&mut black, &mut nb)
        } else {
            (&mut white, &mut nw)
        };
        for &p in middle {
            *sum += p;
            *count += 1;
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
    let at = |j: isize| profile[angle::wrap_index(j as i64, n as i64)];
    let mut offsets = Vec::new();
    let mut edges = 0;
    for k in 0..sectors {
        let before = sector_is_black(bits, code, ((k + sectors - 1) % sectors) as u32);
        let after = sector_is_black(bits, code, k as u32);
        if before == after {
            continue;
        }
        edges += 1;
        let rising = before; // black → white going counter-clockwise
        let centre = (k * per_sector) as isize;
        let half = (per_sector / 2) as isize;
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
                if best.is_none_or(|b: f64| position.abs() < b.abs()) {
                    best = Some(position);
                }
            }
        }
        if let Some(b) = best {
            offsets.push(b * w / per_sector as f64);
        }
    }
    if offsets.is_empty() || (offsets.len() as f64) < min_found * f64::from(edges) {
        return None;
    }
    offsets.sort_by(f64::total_cmp);
    Some(offsets[offsets.len() / 2])
}

/// Yaw of a tracked marker whose code is known, from its ring sampled along
/// the image ellipse (exact for an affine view, as the ring reader
/// assumes): the sector edges the code predicts are looked for near where
/// last frame's yaw puts them. About 2n·16 samples instead of a full read.
/// Every edge must show up with the polarity the code gives it (two codes
/// of a family differ in at least one bit, whose mid-bit edge flips), so
/// this also confirms the code; None otherwise (then read the ring in full).
pub fn follow_ring(
    image: Gray<'_>,
    outer: &Ellipse,
    bits: u32,
    code: u32,
    previous_yaw: f64,
) -> Option<f64> {
    let sectors = 2 * bits as usize;
    let w = sector_width(bits);
    let n = sectors * FOLLOW_SAMPLES_PER_SECTOR;
    // The ellipse parameter t grows visually clockwise (image v points
    // down), marker angles visually counter-clockwise: t = t0 - θ.
    let (sa, ca) = outer.angle.sin_cos();
    let (dy, dx) = previous_yaw.sin_cos();
    let (ex, ey) = (dx * ca + dy * sa, -dx * sa + dy * ca);
    let t0 = (ey / outer.semi_minor).atan2(ex / outer.semi_major);
    let scales = [0.42, 0.52];
    // Walk t by a fixed rotation instead of evaluating sines per sample.
    let (step_sin, step_cos) = (-std::f64::consts::TAU / n as f64).sin_cos();
    let (mut st, mut ct) = t0.sin_cos();
    let mut profile = Vec::with_capacity(n);
    for _ in 0..n {
        let mut sum = 0.0;
        for k in scales {
            let (x, y) = (k * outer.semi_major * ct, k * outer.semi_minor * st);
            sum += sample(image, outer.u + x * ca - y * sa, outer.v + x * sa + y * ca)?;
        }
        profile.push(sum / scales.len() as f64);
        (st, ct) = (st * step_cos + ct * step_sin, ct * step_cos - st * step_sin);
    }
    let phi = code_edge_offset(&profile, bits, code, FOLLOW_SAMPLES_PER_SECTOR, 1.0)?;
    if phi.abs() > w / 2.0 {
        return None;
    }
    let (x, y) = outer.point_at(t0 - phi);
    Some((y - outer.v).atan2(x - outer.u))
}

const FOLLOW_SAMPLES_PER_SECTOR: usize = 8;
