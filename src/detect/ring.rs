//! Reading the Manchester code ring of a WhyCode marker: ID, yaw and a
//! confidence for the ID filter (paper section 5; spec sections 2-3).
//!
//! The ring is sampled along the outer ellipse's parametrisation, scaled to
//! radii inside the ring. A circle seen under an orientation-preserving
//! affine map becomes an ellipse whose visually counter-clockwise
//! parametrisation `t` equals the marker angle plus an unknown constant, so
//! the 2n sectors are equally spaced in `t`. Everything below works in `t`:
//!
//! 1. `K·2n` samples (a multiple of 2n, so no sector is favoured: the
//!    reference's fixed 360 samples bias yaw and break 16-bit codes), each
//!    the mean over several radii across the ring with bilinear
//!    interpolation, which averages noise and blur.
//! 2. Edge phase modulo one sector from the phase of the 2n-th harmonic of
//!    the gradient magnitude: every edge of a Manchester ring sits on a
//!    sector boundary, so this is the correlation with the 2n-periodic edge
//!    comb, continuous in the phase (sub-sample yaw).
//! 3. Which of the two boundary classes is the mandatory mid-bit edge: the
//!    pairing of half-sectors under which the bits are most clearly
//!    Manchester (both halves opposite).
//! 4. Bits by comparing the two halves of each bit; a bit whose halves are
//!    not clearly opposite is an erasure. Erasures are filled only when the
//!    family's distance guarantees a unique answer, otherwise ID 0.
//! 5. Decoding through [`Decoder`], yaw from the rotation and the phase.
//!
//! Under perspective the map from marker angle to `t` is projective rather
//! than affine; at 60° tilt and a marker spanning a tenth of the field of
//! view the resulting yaw error stays well below a degree, and
//! [`RingReading::axis_point`] lets the pose stage use the measured
//! direction of the +x axis rather than the ellipse-centred yaw.

use crate::family::{Decoded, Decoder, MatchStatus};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use image::GrayImage;
use std::f64::consts::PI;

/// An ellipse in the image, in pixels (centre origin at the top-left pixel's
/// centre; `angle` is the direction of the major axis, atan2(dv, du)).
/// Kept here until the pose module's identical type is available.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageEllipse {
    pub u: f64,
    pub v: f64,
    pub semi_major: f64,
    pub semi_minor: f64,
    pub angle: f64,
}

/// Rings whose sectors are narrower than this many pixels (at the sample
/// radius, along the ellipse's minor axis) are not read: below it the
/// sectors blur together and a read would be a guess.
pub const MIN_PIXELS_PER_SECTOR: f64 = 1.2;

/// Least difference between a bit's two halves, relative to the black-white
/// contrast, for the ring to count as visible at all.
const MIN_RING_CONTRAST: f64 = 0.10;

/// A bit whose two halves differ by less than this fraction of the ring's
/// typical bit contrast is an erasure (broken Manchester structure).
const ERASURE_RATIO: f64 = 0.4;

/// Most erasures the reader tries to fill from the family's distance.
const MAX_ERASURES: u32 = 4;

/// What one look at a code ring gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RingReading {
    /// The word read, bit 0 starting at the first bit boundary visually
    /// counter-clockwise of the ellipse's major axis (any start works: the
    /// decoder reports the rotation). `None` when nothing could be read.
    pub word: Option<u32>,
    /// The decoder's verdict. `None` when the ring could not be read
    /// reliably (too small, no contrast, broken Manchester structure):
    /// no evidence either way.
    pub decoded: Option<Decoded>,
    /// The member ID, 0 when unknown or not a member.
    pub id: u32,
    /// Image direction of the marker's +x axis, atan2(dv, du), radians;
    /// `None` unless the ID is known.
    pub yaw: Option<f64>,
    /// Probability that `id` is right. For ID 0 with `decoded` rejected, the
    /// probability that the ring really carries no member code.
    pub confidence: f64,
    /// Typical difference between the two halves of a bit, relative to the
    /// black-white contrast (1 for a sharp, well-resolved ring).
    pub edge_strength: f64,
    /// The weakest bit's half difference relative to the typical one.
    pub weakest_bit: f64,
    /// Number of bits read as erasures (halves not clearly opposite).
    pub erasures: u32,
    /// Ring sector width in pixels at the sample radius, narrowest place.
    pub pixels_per_sector: f64,
    /// Image point of the marker-frame point (R, 0) (on the outer ellipse
    /// in the direction of the +x axis), for the pose stage.
    pub axis_point: Option<(f64, f64)>,
}

impl RingReading {
    fn unreadable(pixels_per_sector: f64) -> RingReading {
        RingReading {
            word: None,
            decoded: None,
            id: 0,
            yaw: None,
            confidence: 0.0,
            edge_strength: 0.0,
            weakest_bit: 0.0,
            erasures: 0,
            pixels_per_sector,
            axis_point: None,
        }
    }
}

/// Reads code rings for one family (or none: legacy WhyCon markers carry no
/// ring, and every reading is empty).
#[derive(Debug, Clone)]
pub struct RingReader {
    decoder: Option<Decoder>,
    min_pixels_per_sector: f64,
}

/// Radii (relative to R) averaged for each angular sample: the middle two
/// thirds of the ring 0.343..0.6, away from the white discs on both sides.
fn sample_radii() -> [f64; 5] {
    let width = WHYCODE_WHITE_RATIO - RING_INNER_RATIO;
    [1.0, 2.0, 3.0, 4.0, 5.0].map(|k| RING_INNER_RATIO + width * k / 6.0)
}

impl RingReader {
    pub fn new(decoder: Option<Decoder>) -> RingReader {
        RingReader {
            decoder,
            min_pixels_per_sector: MIN_PIXELS_PER_SECTOR,
        }
    }

    /// Changes the smallest sector width (pixels) the reader attempts.
    pub fn with_min_pixels_per_sector(mut self, pixels: f64) -> RingReader {
        self.min_pixels_per_sector = pixels;
        self
    }

    pub fn decoder(&self) -> Option<&Decoder> {
        self.decoder.as_ref()
    }

    /// Reads the ring inside the outer ellipse `outer`. `black_level` and
    /// `white_level` are the grey levels of the marker's black disc and white
    /// disc as the detector measured them.
    pub fn read(
        &self,
        image: &GrayImage,
        outer: &ImageEllipse,
        black_level: f64,
        white_level: f64,
    ) -> RingReading {
        let Some(decoder) = &self.decoder else {
            return RingReading::unreadable(0.0);
        };
        let bits = decoder.family().bits();
        let sector = PI / f64::from(bits);
        let radii = sample_radii();
        let mid_ratio = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
        let pixels_per_sector = outer.semi_minor * mid_ratio * sector;
        let contrast = white_level - black_level;
        let valid = [
            outer.u,
            outer.v,
            outer.semi_major,
            outer.semi_minor,
            outer.angle,
        ]
        .iter()
        .all(|x| x.is_finite())
            && outer.semi_minor > 0.0
            && outer.semi_major >= outer.semi_minor
            && contrast.is_finite()
            && contrast > 4.0;
        if !valid || pixels_per_sector < self.min_pixels_per_sector {
            return RingReading::unreadable(pixels_per_sector.max(0.0));
        }

        // About two samples per pixel along the outermost sample radius.
        let arc = 2.0 * PI * radii[4] * outer.semi_major;
        let per_sector = ((arc * 2.0 / f64::from(2 * bits)).ceil() as usize).clamp(8, 256);
        let count = per_sector * 2 * bits as usize;
        let frame = EllipseFrame::new(outer);
        let Some(profile) = sample_profile(image, &frame, &radii, count) else {
            return RingReading::unreadable(pixels_per_sector);
        };

        let phase = edge_phase(&profile, bits, per_sector);
        let halves_a = half_sector_means(&profile, bits, phase);
        let halves_b = half_sector_means(&profile, bits, phase + sector);
        let diffs_a = bit_differences(&halves_a);
        let diffs_b = bit_differences(&halves_b);
        let score = |d: &[f64]| d.iter().map(|x| x.abs()).sum::<f64>();
        let (start, diffs, other_score) = if score(&diffs_a) >= score(&diffs_b) {
            (phase, diffs_a, score(&diffs_b))
        } else {
            (phase + sector, diffs_b, score(&diffs_a))
        };
        let best_score = score(&diffs);

        let mut magnitudes: Vec<f64> = diffs.iter().map(|d| d.abs()).collect();
        magnitudes.sort_by(f64::total_cmp);
        let typical = magnitudes[magnitudes.len() / 2];
        let edge_strength = typical / contrast;
        let weakest_bit = if typical > 0.0 {
            magnitudes[0] / typical
        } else {
            0.0
        };
        let mut reading = RingReading {
            edge_strength,
            weakest_bit,
            pixels_per_sector,
            ..RingReading::unreadable(pixels_per_sector)
        };
        // Only a word with all bits equal reads alike under both pairings,
        // and those are periodic; anything close to a tie is noise.
        let parity_clear = best_score - other_score > 0.5 * typical;
        if edge_strength < MIN_RING_CONTRAST || !parity_clear {
            return reading;
        }

        let mut word = 0u32;
        let mut erasures = Vec::new();
        for (j, d) in diffs.iter().enumerate() {
            // First half brighter than the second: white then black, a 1.
            if *d > 0.0 {
                word |= 1 << (bits as usize - 1 - j);
            }
            if d.abs() < ERASURE_RATIO * typical {
                erasures.push(j as u32);
            }
        }
        reading.word = Some(word);
        reading.erasures = erasures.len() as u32;

        let decoded = if erasures.is_empty() {
            decoder.decode(word)
        } else {
            match fill_erasures(decoder, word, &erasures) {
                Some(d) => d,
                None => return reading,
            }
        };
        reading.decoded = Some(decoded);

        let quality = logistic((edge_strength - 0.2) / 0.04)
            * logistic((pixels_per_sector - 1.6) / 0.2)
            * (weakest_bit / 0.7).min(1.0);
        match decoded.status {
            MatchStatus::Exact | MatchStatus::Corrected => {
                let status_factor = 0.5f64.powi(decoded.distance as i32);
                reading.id = decoded.id;
                reading.confidence = quality * status_factor;
                let x_axis_t = start + 2.0 * sector * f64::from(decoded.rotation);
                let (du, dv) = frame.offset(x_axis_t, 1.0);
                reading.yaw = Some(dv.atan2(du));
                reading.axis_point = Some((outer.u + du, outer.v + dv));
            }
            MatchStatus::Rejected => reading.confidence = quality,
            MatchStatus::Ambiguous => reading.confidence = 0.0,
        }
        reading
    }
}

/// Tries every filling of the erased bits; accepts the result only when
/// exactly one member rotation matches exactly and fewer bits were erased
/// than the family's distance (so no two members can fit the same reading).
fn fill_erasures(decoder: &Decoder, word: u32, erasures: &[u32]) -> Option<Decoded> {
    let family = decoder.family();
    let bits = family.bits();
    if erasures.len() as u32 >= family.distance() || erasures.len() as u32 > MAX_ERASURES {
        return None;
    }
    let mut found: Option<Decoded> = None;
    for fill in 0u32..(1 << erasures.len()) {
        let mut candidate = word;
        for (k, &j) in erasures.iter().enumerate() {
            let bit = 1 << (bits - 1 - j);
            if fill >> k & 1 == 1 {
                candidate ^= bit;
            }
        }
        let d = decoder.decode(candidate);
        if d.status != MatchStatus::Exact {
            continue;
        }
        let flipped = (candidate ^ word).count_ones();
        match found {
            None => {
                found = Some(Decoded {
                    status: if flipped == 0 {
                        MatchStatus::Exact
                    } else {
                        MatchStatus::Corrected
                    },
                    distance: flipped,
                    ..d
                })
            }
            Some(prev) if (prev.id, prev.rotation) != (d.id, d.rotation) => return None,
            Some(_) => {}
        }
    }
    found
}

fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The ellipse's visually counter-clockwise parametrisation: with image v
/// pointing down, the minor-axis direction is the major one turned by -90°.
struct EllipseFrame {
    centre: (f64, f64),
    major: (f64, f64),
    minor: (f64, f64),
}

impl EllipseFrame {
    fn new(e: &ImageEllipse) -> EllipseFrame {
        let (s, c) = e.angle.sin_cos();
        EllipseFrame {
            centre: (e.u, e.v),
            major: (c * e.semi_major, s * e.semi_major),
            minor: (s * e.semi_minor, -c * e.semi_minor),
        }
    }

    /// Offset from the centre of the point at parameter `t`, radius ratio `rho`.
    fn offset(&self, t: f64, rho: f64) -> (f64, f64) {
        let (s, c) = t.sin_cos();
        (
            rho * (c * self.major.0 + s * self.minor.0),
            rho * (c * self.major.1 + s * self.minor.1),
        )
    }
}

/// Mean grey level over the given radii at `count` equally spaced
/// parameters; `None` when the ring leaves the image.
fn sample_profile(
    image: &GrayImage,
    frame: &EllipseFrame,
    radii: &[f64],
    count: usize,
) -> Option<Vec<f64>> {
    let (w, h) = image.dimensions();
    let (max_x, max_y) = (f64::from(w) - 1.0, f64::from(h) - 1.0);
    let mut profile = Vec::with_capacity(count);
    for j in 0..count {
        let (dx, dy) = frame.offset(2.0 * PI * j as f64 / count as f64, 1.0);
        let mut sum = 0.0;
        for &rho in radii {
            let x = frame.centre.0 + rho * dx;
            let y = frame.centre.1 + rho * dy;
            if !(0.0..=max_x).contains(&x) || !(0.0..=max_y).contains(&y) {
                return None;
            }
            sum += bilinear(image, x, y);
        }
        profile.push(sum / radii.len() as f64);
    }
    Some(profile)
}

/// Bilinear interpolation with pixel centres at integer coordinates; the
/// caller keeps (x, y) inside [0, w-1] x [0, h-1].
fn bilinear(image: &GrayImage, x: f64, y: f64) -> f64 {
    let (w, h) = image.dimensions();
    let raw = image.as_raw();
    let x0 = (x.floor() as u32).min(w - 1);
    let y0 = (y.floor() as u32).min(h - 1);
    let x1 = (x0 + 1).min(w - 1);
    let y1 = (y0 + 1).min(h - 1);
    let fx = x - f64::from(x0);
    let fy = y - f64::from(y0);
    let at = |xx: u32, yy: u32| f64::from(raw[yy as usize * w as usize + xx as usize]);
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Parameter (radians, in [0, one sector)) of the ring's sector boundaries:
/// the phase of the 2n-th harmonic of the gradient magnitude. Each edge
/// contributes a phasor at its own position, so the estimate moves
/// continuously with the marker and is not tied to the sample grid.
fn edge_phase(profile: &[f64], bits: u32, per_sector: usize) -> f64 {
    let count = profile.len();
    let (mut re, mut im) = (0.0, 0.0);
    for j in 0..count {
        let g = (profile[(j + 1) % count] - profile[j]).abs();
        // 2n·t at the midpoint between samples j and j+1.
        let arg = 2.0 * PI * (j as f64 + 0.5) / per_sector as f64;
        re += g * arg.cos();
        im -= g * arg.sin();
    }
    let sector = PI / f64::from(bits);
    let phase = -im.atan2(re) / f64::from(2 * bits);
    phase.rem_euclid(sector)
}

/// Mean grey level of the central part of each of the 2n half-bit sectors,
/// the first one starting at parameter `start`.
fn half_sector_means(profile: &[f64], bits: u32, start: f64) -> Vec<f64> {
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
                    let x = (t / (2.0 * PI) * count).rem_euclid(count);
                    let j = x.floor();
                    let frac = x - j;
                    let j = j as usize % profile.len();
                    profile[j] * (1.0 - frac) + profile[(j + 1) % profile.len()] * frac
                })
                .sum();
            sum / POINTS.len() as f64
        })
        .collect()
}

/// First half minus second half of every bit: positive means white then
/// black, a 1 bit.
fn bit_differences(halves: &[f64]) -> Vec<f64> {
    halves.chunks_exact(2).map(|h| h[0] - h[1]).collect()
}
