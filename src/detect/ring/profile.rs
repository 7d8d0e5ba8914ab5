//! What every reading of a code ring starts from: the ring's grey levels
//! along a parametrised ellipse ([`EllipseFrame`], [`sample_profile`]),
//! where its sector boundaries lie ([`boundary_phase`],
//! [`boundary_phases`]), the mean level of each half-sector and the
//! difference across each bit ([`half_sector_means`],
//! [`bit_differences`]), where the ring's radial edges put the marker's
//! projected centre ([`refined_centre`]), and the profile as under even
//! light when a cast shadow's edge crosses it ([`evened_light`]). The
//! sector reader ([`super::reader`]) and the structure test
//! ([`super::manchester`]) both read rings through these.

use std::f64::consts::PI;
use std::ops::Deref;

use image::{ImageBuffer, Luma};

use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::angle;
use crate::math::sample::{Border, Plane};
use crate::math::Ellipse;

/// Radii (relative to R) averaged for each angular sample: the middle two
/// thirds of the ring 0.343..0.6, away from the white discs on both sides.
pub(super) fn sample_radii() -> [f64; 5] {
    let width = WHYCODE_WHITE_RATIO - RING_INNER_RATIO;
    [1.0, 2.0, 3.0, 4.0, 5.0].map(|k| RING_INNER_RATIO + width * k / 6.0)
}

/// Where marker angle t (up to the unknown in-plane rotation) and radius
/// ρ·R land in the image. The outer ellipse alone fixes the map only up to
/// perspective; with the projection `p` of the marker centre it is exact:
/// the polar of `p` with respect to the ellipse is the image of the line at
/// infinity, and the homography sending it back to infinity leaves an
/// ellipse that is an affine image of the circle, centred on the image of
/// `p`. Without an estimate of `p` (p = ellipse centre) this is the plain
/// affine parametrisation. With image v pointing down, the minor-axis
/// direction is the major one turned by -90°, which makes t run visually
/// counter-clockwise.
#[derive(Debug, Clone, Copy)]
pub(super) struct EllipseFrame {
    /// Ellipse centre and scale (the semi-major axis) of the normalised
    /// coordinates the homography works in.
    centre: (f64, f64),
    scale: f64,
    /// The homography y -> y / (1 - m·y) back to normalised image coordinates.
    m: (f64, f64),
    /// The rectified ellipse: centre and (scaled) axis vectors.
    rectified_centre: (f64, f64),
    major: (f64, f64),
    minor: (f64, f64),
    /// Projection of the marker centre, pixels.
    pub(super) projected_centre: (f64, f64),
}

impl EllipseFrame {
    pub(super) fn new(e: &Ellipse) -> EllipseFrame {
        let (s, c) = e.angle.sin_cos();
        let k = e.semi_minor / e.semi_major;
        EllipseFrame {
            centre: (e.u, e.v),
            scale: e.semi_major,
            m: (0.0, 0.0),
            rectified_centre: (0.0, 0.0),
            major: (c, s),
            minor: (s * k, -c * k),
            projected_centre: (e.u, e.v),
        }
    }

    /// The frame in which `p` is the projection of the marker centre;
    /// `None` when that is inconsistent with the ellipse (p outside it, or
    /// a degenerate rectification).
    pub(super) fn with_projected_centre(e: &Ellipse, p: (f64, f64)) -> Option<EllipseFrame> {
        let a = e.semi_major;
        let (s, c) = e.angle.sin_cos();
        let q = 1.0 / (e.semi_minor / a).powi(2);
        // Normalised conic x^T M x = 1, M = R diag(1, q) R^T.
        let mm = [
            [c * c + q * s * s, c * s * (1.0 - q)],
            [c * s * (1.0 - q), s * s + q * c * c],
        ];
        let pn = ((p.0 - e.u) / a, (p.1 - e.v) / a);
        if pn.0 * (mm[0][0] * pn.0 + mm[0][1] * pn.1) + pn.1 * (mm[1][0] * pn.0 + mm[1][1] * pn.1)
            >= 0.25
        {
            return None;
        }
        // Polar line of p: (M p, -1) ~ (-M p, 1) =: (m, 1).
        let m = (
            -(mm[0][0] * pn.0 + mm[0][1] * pn.1),
            -(mm[1][0] * pn.0 + mm[1][1] * pn.1),
        );
        // Conic in rectified coordinates: C' = H^-T C H^-1 with
        // H^-1 = [[1,0,0],[0,1,0],[-m1,-m2,1]], C = [[M,0],[0,-1]].
        let c3 = [
            [mm[0][0], mm[0][1], 0.0],
            [mm[1][0], mm[1][1], 0.0],
            [0.0, 0.0, -1.0],
        ];
        let hinv = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-m.0, -m.1, 1.0]];
        let mut tmp = [[0.0; 3]; 3];
        let mut cr = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                tmp[i][j] = (0..3).map(|k| c3[i][k] * hinv[k][j]).sum();
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                cr[i][j] = (0..3).map(|k| hinv[k][i] * tmp[k][j]).sum();
            }
        }
        let (a11, a12, a22) = (cr[0][0], cr[0][1], cr[1][1]);
        let det = a11 * a22 - a12 * a12;
        if det.is_nan() || det <= 1e-12 || a11 <= 0.0 {
            return None;
        }
        let g = (cr[0][2], cr[1][2]);
        let centre = (
            -(a22 * g.0 - a12 * g.1) / det,
            -(-a12 * g.0 + a11 * g.1) / det,
        );
        let level = -(cr[2][2] + g.0 * centre.0 + g.1 * centre.1);
        if level.is_nan() || level <= 0.0 {
            return None;
        }
        // Axes of (x-c)^T A (x-c) = level.
        let mean = 0.5 * (a11 + a22);
        let root = (0.25 * (a11 - a22).powi(2) + a12 * a12).sqrt();
        let (small, large) = (mean - root, mean + root);
        if small <= 0.0 {
            return None;
        }
        let angle = 0.5 * (-2.0 * a12).atan2(a22 - a11);
        let (major_len, minor_len) = ((level / small).sqrt(), (level / large).sqrt());
        let (s2, c2) = angle.sin_cos();
        let frame = EllipseFrame {
            centre: (e.u, e.v),
            scale: a,
            m,
            rectified_centre: centre,
            major: (c2 * major_len, s2 * major_len),
            minor: (s2 * minor_len, -c2 * minor_len),
            projected_centre: p,
        };
        // The rectified centre must map back onto p, and the marker must
        // stay on the near side of the vanishing line.
        let back = frame.point(0.0, 0.0);
        let near = (0..16).all(|k| {
            let (sn, cs) = (f64::from(k) * PI / 8.0).sin_cos();
            let y = (
                centre.0 + cs * frame.major.0 + sn * frame.minor.0,
                centre.1 + cs * frame.major.1 + sn * frame.minor.1,
            );
            1.0 - m.0 * y.0 - m.1 * y.1 > 0.2
        });
        ((back.0 - p.0).hypot(back.1 - p.1) < 0.01 * a && near).then_some(frame)
    }

    /// Image point of the rectified unit-circle coordinates `d`.
    fn unit_point(&self, d: (f64, f64)) -> (f64, f64) {
        let y0 = self.rectified_centre.0 + d.0 * self.major.0 + d.1 * self.minor.0;
        let y1 = self.rectified_centre.1 + d.0 * self.major.1 + d.1 * self.minor.1;
        let w = 1.0 - self.m.0 * y0 - self.m.1 * y1;
        (
            self.centre.0 + self.scale * y0 / w,
            self.centre.1 + self.scale * y1 / w,
        )
    }

    /// Direction of parameter `t` in rectified coordinates (for [`Self::at`]).
    fn direction(&self, t: f64) -> (f64, f64) {
        let (s, c) = t.sin_cos();
        self.direction_of(s, c)
    }

    /// [`Self::direction`] of the parameter whose sine and cosine are given.
    fn direction_of(&self, s: f64, c: f64) -> (f64, f64) {
        (
            c * self.major.0 + s * self.minor.0,
            c * self.major.1 + s * self.minor.1,
        )
    }

    /// Image point at radius `rho`·R along a rectified `direction`.
    #[inline]
    fn at(&self, direction: (f64, f64), rho: f64) -> (f64, f64) {
        // Without a perspective term the divisor below is exactly 1: the
        // same point without two divisions (the ring tests' samples).
        if self.m == (0.0, 0.0) {
            return self.at_affine(direction, rho);
        }
        let y0 = self.rectified_centre.0 + rho * direction.0;
        let y1 = self.rectified_centre.1 + rho * direction.1;
        let w = 1.0 - self.m.0 * y0 - self.m.1 * y1;
        (
            self.centre.0 + self.scale * y0 / w,
            self.centre.1 + self.scale * y1 / w,
        )
    }

    /// [`Self::at`] of a frame without perspective (`m` zero).
    #[inline]
    fn at_affine(&self, direction: (f64, f64), rho: f64) -> (f64, f64) {
        let y0 = self.rectified_centre.0 + rho * direction.0;
        let y1 = self.rectified_centre.1 + rho * direction.1;
        (
            self.centre.0 + self.scale * y0,
            self.centre.1 + self.scale * y1,
        )
    }

    /// Image point of parameter `t` on the concentric circle of radius `rho`·R.
    pub(super) fn point(&self, t: f64, rho: f64) -> (f64, f64) {
        let (s, c) = t.sin_cos();
        let y0 = self.rectified_centre.0 + rho * (c * self.major.0 + s * self.minor.0);
        let y1 = self.rectified_centre.1 + rho * (c * self.major.1 + s * self.minor.1);
        let w = 1.0 - self.m.0 * y0 - self.m.1 * y1;
        (
            self.centre.0 + self.scale * y0 / w,
            self.centre.1 + self.scale * y1 / w,
        )
    }
}

/// Mean grey level over the given radii at `count` equally spaced
/// parameters; `None` when the ring leaves the image.
pub(super) fn sample_profile<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    frame: &EllipseFrame,
    radii: &[f64],
    count: usize,
) -> Option<Vec<f64>> {
    let plane = Plane::new(
        image.as_raw(),
        image.width() as usize,
        image.height() as usize,
    );
    // The ring's radii (three or five) and the paper's two as arrays: the
    // loop over them unrolls, and the sums stay in registers. Not in the
    // browser, whose first load has a size budget the copies would spend.
    if !cfg!(target_arch = "wasm32") {
        match *radii {
            [a, b] => return profile_at(&plane, frame, [a, b], count),
            [a, b, c] => return profile_at(&plane, frame, [a, b, c], count),
            [a, b, c, d, e] => return profile_at(&plane, frame, [a, b, c, d, e], count),
            _ => {}
        }
    }
    profile_at(&plane, frame, radii, count)
}

/// [`sample_profile`] over `radii`.
#[inline(always)]
fn profile_at<R: AsRef<[f64]>>(
    plane: &Plane<'_, u8>,
    frame: &EllipseFrame,
    radii: R,
    count: usize,
) -> Option<Vec<f64>> {
    let radii = radii.as_ref();
    let mut profile = Vec::with_capacity(count);
    // Walk the parameter by a fixed rotation instead of a sine per sample.
    let (step_sin, step_cos) = (2.0 * PI / count as f64).sin_cos();
    let (mut s, mut c) = (0.0f64, 1.0f64);
    for _ in 0..count {
        let direction = frame.direction_of(s, c);
        (s, c) = (s * step_cos + c * step_sin, c * step_cos - s * step_sin);
        let mut sum = 0.0;
        for &rho in radii {
            let (x, y) = frame.at(direction, rho);
            sum += plane.at(x, y, Border::Interior)?;
        }
        profile.push(sum / radii.len() as f64);
    }
    Some(profile)
}

/// A better estimate of the projected marker centre (pixels), from where
/// rays through the middle of each half-sector cross from white to black:
/// at 0.343 R in black sectors, at 0.6 R in white ones. In the frame's
/// rectified unit-circle coordinates, if the true centre sits at D, the
/// circle of radius ρ appears shifted by (1 - ρ²)·D (to first order, the
/// way perspective shifts concentric circles), so it is crossed at
/// ρ + (1 - ρ²)·D·u(t); a scale and a constant term absorb ellipse size
/// errors and blur. `None` when the rays do not show the ring's structure.
pub(super) fn refined_centre<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    frame: &EllipseFrame,
    phase: f64,
    bits: u32,
    mid_level: f64,
) -> Option<(f64, f64)> {
    let plane = Plane::new(
        image.as_raw(),
        image.width() as usize,
        image.height() as usize,
    );
    let sector = PI / f64::from(bits);
    let major = frame.scale * frame.major.0.hypot(frame.major.1);
    let step = 0.5 / major.max(1.0);
    let (start, end) = (0.3, 0.75);
    // Normal equations of e = (1-ρ²)(Dx cos t + Dy sin t) + s·ρ + b.
    let mut ata = [[0.0f64; 4]; 4];
    let mut atb = [0.0f64; 4];
    let mut used = [0usize; 2];
    for k in 0..2 * bits {
        {
            let offset = 0.5;
            let t = phase + (f64::from(k) + offset) * sector;
            let direction = frame.direction(t);
            let at = |rho: f64| {
                let (x, y) = frame.at(direction, rho);
                plane.at(x, y, Border::Interior)
            };
            let mut previous = at(start)?;
            if previous <= mid_level {
                continue;
            }
            let mut rho = start;
            let mut crossing = None;
            while rho < end {
                let next_rho = rho + step;
                let next = at(next_rho)?;
                if next < mid_level {
                    let f = (previous - mid_level) / (previous - next);
                    crossing = Some(rho + f * step);
                    break;
                }
                previous = next;
                rho = next_rho;
            }
            let Some(rho_c) = crossing else { continue };
            let middle = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
            let (expected, class) = if rho_c < middle {
                (RING_INNER_RATIO, 0)
            } else {
                (WHYCODE_WHITE_RATIO, 1)
            };
            used[class] += 1;
            let k1 = 1.0 - expected * expected;
            let row = [k1 * t.cos(), k1 * t.sin(), expected, 1.0];
            let e = rho_c - expected;
            for i in 0..4 {
                for j in 0..4 {
                    ata[i][j] += row[i] * row[j];
                }
                atb[i] += row[i] * e;
            }
        }
    }
    if used[0] < 2 || used[1] < 2 {
        return None;
    }
    let solution = solve4(ata, atb)?;
    let (ux, uy) = (solution[0], solution[1]);
    let centre = frame.unit_point((ux, uy));
    (centre.0.is_finite() && centre.1.is_finite()).then_some(centre)
}

/// Solves a 4x4 linear system by Gaussian elimination with pivoting.
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    for col in 0..4 {
        let pivot = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for row in col + 1..4 {
            let f = a[row][col] / pivot_row[col];
            for (x, p) in a[row].iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let sum: f64 = (row + 1..4).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - sum) / a[row][row];
    }
    Some(x)
}

/// How much the profile changes from each sample to the next (the last
/// sample's next is the first: the profile goes round the ring); its peaks
/// are the ring's edges.
pub(super) fn gradient(samples: &[f64]) -> impl Iterator<Item = f64> + '_ {
    // Each sample beside the next, the first after the last: no division
    // per sample to wrap the index.
    let next = samples.iter().skip(1).chain(samples.first());
    samples.iter().zip(next).map(|(a, b)| (b - a).abs())
}

/// Parameter (radians, in [0, one sector)) of the sector boundaries of a
/// `bits`-bit ring: the phase of the 2n-th harmonic of the profile's
/// [`gradient`], where every edge of a Manchester ring sits. Each edge
/// contributes a phasor at its own position, so the estimate moves
/// continuously with the marker and is not tied to the sample grid.
///
/// For a profile of `per_sector` samples to each sector (the sector
/// reader's), whose phasors repeat every sector: one sector's, each
/// computed exactly, serve the whole ring. [`boundary_phases`] sums the
/// same harmonic for profiles of any length; the two sums round
/// differently in the last bits.
pub(super) fn boundary_phase(profile: &[f64], bits: u32, per_sector: usize) -> f64 {
    // 2n·t at the midpoint between samples j and j+1 repeats every sector.
    let phasors: Vec<(f64, f64)> = (0..per_sector)
        .map(|j| (2.0 * PI * (j as f64 + 0.5) / per_sector as f64).sin_cos())
        .collect();
    let (mut re, mut im) = (0.0, 0.0);
    for (g, &(sin, cos)) in gradient(profile).zip(phasors.iter().cycle()) {
        re += g * cos;
        im -= g * sin;
    }
    phase_in_sector(re, im, f64::from(2 * bits), bits)
}

/// [`boundary_phase`] for every count in `counts`, on the [`gradient`] of
/// a profile of any length (the structure test samples one profile for
/// every count it tries), with how much of the gradient (`total`, its sum)
/// each harmonic holds: 1 when every edge sits on a boundary of that count.
pub(super) fn boundary_phases(gradient: &[f64], total: f64, counts: &[u32]) -> Vec<(f64, f64)> {
    // Each count's sum is a chain of dependent steps a sample long; four
    // counts walked side by side keep the processor busy between the
    // steps of one (each lane's arithmetic as it would be alone).
    const LANES: usize = 4;
    let count = gradient.len() as f64;
    let mut out = Vec::with_capacity(counts.len());
    for group in counts.chunks(LANES) {
        // Short groups fill up with their last count, read and dropped.
        let harmonic: [f64; LANES] =
            std::array::from_fn(|i| f64::from(2 * group[i.min(group.len() - 1)]));
        let (mut re, mut im) = ([0.0; LANES], [0.0; LANES]);
        // exp(i·h·t) at t = 2π(j + 0.5)/count (the gradient between
        // samples j and j+1), advanced by one rotation per sample instead
        // of a sine and a cosine each.
        let step = harmonic.map(|h| (h * 2.0 * PI / count).sin_cos());
        let (mut s, mut c): ([f64; LANES], [f64; LANES]) = {
            let first = harmonic.map(|h| (h * PI / count).sin_cos());
            (first.map(|x| x.0), first.map(|x| x.1))
        };
        for g in gradient {
            for i in 0..LANES {
                re[i] += g * c[i];
                im[i] -= g * s[i];
                let (step_sin, step_cos) = step[i];
                (s[i], c[i]) = (
                    s[i] * step_cos + c[i] * step_sin,
                    c[i] * step_cos - s[i] * step_sin,
                );
            }
        }
        for (i, &bits) in group.iter().enumerate() {
            let coherence = if total > 0.0 {
                re[i].hypot(im[i]) / total
            } else {
                0.0
            };
            out.push((phase_in_sector(re[i], im[i], harmonic[i], bits), coherence));
        }
    }
    out
}

/// The boundary phase a harmonic's sum (re, im) puts within one sector.
fn phase_in_sector(re: f64, im: f64, harmonic: f64, bits: u32) -> f64 {
    (-im.atan2(re) / harmonic).rem_euclid(PI / f64::from(bits))
}

/// Mean grey level of the central part of each of the 2n half-bit sectors,
/// the first one starting at parameter `start`.
pub(super) fn half_sector_means(profile: &[f64], bits: u32, start: f64) -> Vec<f64> {
    let count = profile.len() as f64;
    let sector = PI / f64::from(bits);
    // The central 60 % of each sector, away from blurred edges.
    const POINTS: [f64; 7] = [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8];
    (0..2 * bits)
        .map(|k| {
            let sum: f64 = POINTS
                .iter()
                .map(|f| {
                    let t = start + (f64::from(k) + f) * sector;
                    let x = wrap_samples(t / (2.0 * PI) * count, count);
                    // x ≥ 0 (or NaN, which reads as sample 0 and stays NaN).
                    let j = angle::floor_to_int(x);
                    let frac = x - j as f64;
                    let len = profile.len();
                    let j = if (j as usize) < len {
                        j as usize
                    } else {
                        j as usize % len
                    };
                    let next = if j + 1 == len { 0 } else { j + 1 };
                    profile[j] * (1.0 - frac) + profile[next] * frac
                })
                .sum();
            sum / POINTS.len() as f64
        })
        .collect()
}

/// `x.rem_euclid(count)` (bit for bit) without the library's `fmod` for
/// the parameters within the profile's turn or the next, where the ring
/// tests ask for all but a few: a turn off is an exact subtraction there.
#[inline]
fn wrap_samples(x: f64, count: f64) -> f64 {
    if (0.0..count).contains(&x) {
        x
    } else if (count..2.0 * count).contains(&x) {
        x - count
    } else {
        x.rem_euclid(count)
    }
}

/// First half minus second half of every bit: positive means white then
/// black, a 1 bit.
pub(super) fn bit_differences(halves: &[f64]) -> Vec<f64> {
    halves.chunks_exact(2).map(|h| h[0] - h[1]).collect()
}

/// Least ratio of the brightest to the dimmest light along the ring at
/// which a cast shadow's edge is taken to cross it.
const SHADED_LIGHT_RATIO: f64 = 1.5;

/// Most the dimmest paper round a shaded ring may keep of the brightest:
/// a light gradient across one marker stays well above it.
const SHADED_PAPER_RATIO: f64 = 0.6;

/// Where the paper round the marker is sampled for its light, in outer
/// radii: clear of the black disc's blurred edge.
const PAPER_RADII: [f64; 2] = [1.2, 1.3];

/// The light on the paper just outside the marker, at the same `count`
/// parameters as [`sample_profile`]'s; `None` where it leaves the image.
pub(super) fn paper_profile<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    frame: &EllipseFrame,
    count: usize,
) -> Option<Vec<f64>> {
    sample_profile(image, frame, &PAPER_RADII, count)
}

/// The ring's profile (`bits` bits, samples evenly spaced round it) as
/// under even light, when a cast shadow's edge crosses the ring: the
/// profile steps down with the light, which hides the bits' edges in the
/// shade. Every window of three half-sectors of a Manchester ring holds a
/// white one, so the profile's running maximum over that window follows
/// the light; divided by it (and scaled back to the brightest), the ring
/// reads as under even light. None where the light varies less than
/// [`SHADED_LIGHT_RATIO`] round the ring (a gentle gradient, or a washer or
/// a letter, whose light middle is no ring of sectors), and where `paper`
/// (the light just outside the marker, [`paper_profile`]) is not shaded.
pub(super) fn evened_light(profile: &[f64], paper: &[f64], bits: u32) -> Option<Vec<f64>> {
    // Shade falls on the paper round the marker too; an ink blot over
    // the ring (a run of three or more dark half-sectors, whose "light"
    // is the ink itself) leaves it lit, and evening the blot would read
    // noise as the bits beneath it.
    let (paper_dim, paper_bright) = paper
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &l| (lo.min(l), hi.max(l)));
    if paper_dim > SHADED_PAPER_RATIO * paper_bright {
        return None;
    }
    let count = profile.len();
    let half = ((0.75 * count as f64 / f64::from(2 * bits)).ceil() as usize).min(count / 2);
    let light: Vec<f64> = (0..count)
        .map(|j| {
            (0..=2 * half)
                .map(|k| profile[(j + count + k - half) % count])
                .fold(f64::MIN, f64::max)
        })
        .collect();
    let (dimmest, brightest) = light
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &l| (lo.min(l), hi.max(l)));
    if dimmest <= 0.0 || brightest < SHADED_LIGHT_RATIO * dimmest {
        return None;
    }
    Some(
        profile
            .iter()
            .zip(&light)
            .map(|(p, l)| p * brightest / l)
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile of 2n·`per_sector` samples: `levels[k]` over sector k.
    fn stepped(levels: &[f64], per_sector: usize) -> Vec<f64> {
        levels
            .iter()
            .flat_map(|&level| std::iter::repeat_n(level, per_sector))
            .collect()
    }

    #[test]
    fn the_gradient_goes_round_the_ring() {
        let gradient: Vec<f64> = gradient(&[0.0, 0.0, 10.0, 10.0, 4.0]).collect();
        assert_eq!(gradient, [0.0, 10.0, 0.0, 6.0, 4.0]);
    }

    #[test]
    fn both_sums_put_the_boundaries_between_the_samples_they_fall_between() {
        // Two bits, four samples a sector: edges between samples 3 and 4, 7
        // and 8, ... that is at 3.5/16 of a turn, 7π/16 within a sector.
        let profile = stepped(&[0.0, 1.0, 0.0, 1.0], 4);
        let phase = boundary_phase(&profile, 2, 4);
        assert!((phase - 7.0 * PI / 16.0).abs() < 1e-12, "{phase}");
        let gradient: Vec<f64> = gradient(&profile).collect();
        let total = gradient.iter().sum();
        let [(walked, coherence)] = boundary_phases(&gradient, total, &[2])[..] else {
            panic!("one count, one phase");
        };
        assert!((walked - phase).abs() < 1e-12, "{walked} {phase}");
        assert!((coherence - 1.0).abs() < 1e-12, "{coherence}");
        // Three bits' boundaries fall a third of a sector off every other
        // edge: their phasors cancel.
        let [_, (_, three)] = boundary_phases(&gradient, total, &[2, 3])[..] else {
            panic!("two counts, two phases");
        };
        assert!(three < 1e-9, "{three}");
    }

    #[test]
    fn half_sectors_are_read_in_their_middles_and_bits_from_their_halves() {
        // Ten samples a sector: the middle 60 % lies within each sector.
        let profile = stepped(&[200.0, 50.0, 60.0, 190.0], 10);
        assert_eq!(
            half_sector_means(&profile, 2, 0.0),
            [200.0, 50.0, 60.0, 190.0]
        );
        // Started a sector on, the first half-sector is the second.
        assert_eq!(
            half_sector_means(&profile, 2, PI / 2.0),
            [50.0, 60.0, 190.0, 200.0]
        );
        assert_eq!(
            bit_differences(&[200.0, 50.0, 60.0, 190.0]),
            [150.0, -130.0]
        );
    }

    #[test]
    fn a_profile_samples_the_image_bilinearly_along_the_ellipse() {
        let image = gray_image!(
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200;
            0, 0, 0, 0, 200, 200, 200, 200);
        let circle = Ellipse {
            u: 3.5,
            v: 3.5,
            semi_major: 2.0,
            semi_minor: 2.0,
            angle: 0.0,
        };
        let frame = EllipseFrame::new(&circle);
        // Right, up (image v down), left, down: on the white side, on the
        // edge between the columns 3 and 4, on the black side, the edge.
        let profile = sample_profile(&image, &frame, &[1.0], 4).unwrap();
        let expected = [200.0, 100.0, 0.0, 100.0];
        for (got, want) in profile.iter().zip(expected) {
            assert!((got - want).abs() < 1e-9, "{profile:?}");
        }
        // A ring reaching past the image is not sampled.
        assert_eq!(sample_profile(&image, &frame, &[2.0], 4), None);
    }

    #[test]
    fn a_frame_runs_visually_counter_clockwise_and_keeps_its_centre() {
        let tilted = Ellipse {
            u: 40.0,
            v: 30.0,
            semi_major: 20.0,
            semi_minor: 10.0,
            angle: 0.0,
        };
        let frame = EllipseFrame::new(&tilted);
        let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1) < 1e-9;
        assert!(close(frame.point(0.0, 1.0), (60.0, 30.0)));
        // A quarter turn on: up the image, along the minor axis.
        assert!(close(frame.point(PI / 2.0, 1.0), (40.0, 20.0)));
        assert!(close(frame.point(PI / 2.0, 0.5), (40.0, 25.0)));
        // With the marker's centre seen off the ellipse's (perspective),
        // the rectified centre maps back onto it.
        let seen = (43.0, 29.0);
        let rectified = EllipseFrame::with_projected_centre(&tilted, seen).unwrap();
        assert!(close(rectified.point(0.0, 0.0), seen));
        // Outside the ellipse's middle no rectification fits.
        assert!(EllipseFrame::with_projected_centre(&tilted, (55.0, 30.0)).is_none());
    }

    #[test]
    fn the_radial_edges_of_a_face_on_ring_meet_at_its_centre() {
        use super::super::test_images::{draw, INK, PAPER};
        use crate::geometry::Marker;
        let marker = Marker::whycode(8, 0b0110_1011, 50.0);
        let (image, outline) = draw(&marker, 60.0, 80, (40.3, 39.6), 0.4);
        let frame = EllipseFrame::new(&outline);
        let mid = 0.5 * f64::from(u16::from(INK) + u16::from(PAPER));
        let profile = sample_profile(&image, &frame, &sample_radii(), 16 * 16).unwrap();
        let phase = boundary_phase(&profile, 8, 16);
        let centre = refined_centre(&image, &frame, phase, 8, mid).unwrap();
        assert!((centre.0 - 40.3).hypot(centre.1 - 39.6) < 0.1, "{centre:?}");
    }

    #[test]
    fn a_shaded_ring_reads_as_under_even_light_only_when_its_paper_is_shaded() {
        // Four bits, eight samples a half-sector, white and black in turn;
        // the middle half of the ring lies in a shadow of half the light.
        let lit = stepped(&[200.0, 40.0, 200.0, 40.0, 200.0, 40.0, 200.0, 40.0], 8);
        let light = |j: usize| if (16..48).contains(&j) { 0.5 } else { 1.0 };
        let shaded: Vec<f64> = lit.iter().enumerate().map(|(j, p)| p * light(j)).collect();
        let paper: Vec<f64> = (0..64).map(|j| 220.0 * light(j)).collect();
        let even = evened_light(&shaded, &paper, 4).unwrap();
        // Every white sample back to the brightest white; the black ones
        // stay well below the middle grey (next to a shadow's edge a black
        // sample's light is the white across it, and it reads darker or
        // lighter than the rest).
        for (j, (got, was)) in even.iter().zip(&lit).enumerate() {
            if *was == 200.0 {
                assert!((got - 200.0).abs() < 1e-9, "{j}: {even:?}");
            } else {
                assert!(*got <= 80.0 + 1e-9, "{j}: {even:?}");
            }
        }
        // Paper lit all round: a dark blot on the ring, not a shadow.
        assert_eq!(evened_light(&shaded, &[220.0; 64], 4), None);
        // Even light: nothing to even.
        assert_eq!(evened_light(&lit, &paper, 4), None);
    }
}
