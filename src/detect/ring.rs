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
//! Perspective: the outer ellipse alone determines the marker-to-image map
//! only up to perspective, under which the ring is neither centred on the
//! ellipse nor evenly spaced in its parameter (degrees of yaw error for a
//! close, tilted marker in a wide-angle view). The reader locates the
//! projected marker centre from the ring's radial edges (a white sector
//! ends at 0.6 R, a black one starts at 0.343 R; perspective shifts
//! concentric circles by amounts growing as ρ²), then rectifies exactly:
//! the polar line of that centre is the image of the line at infinity. Yaw
//! is the image direction from the projected centre to the rim point on
//! the +x axis ([`RingReading::axis_point`], for the pose stage). The yaw
//! error this leaves on close, tilted markers in a wide-angle view is
//! bounded by `yaw_under_perspective_stays_within_stated_bounds`
//! (tests/integration/ring_perspective.rs).

use crate::family::{Decoded, Decoder, MatchStatus};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use image::{ImageBuffer, Luma};
use std::ops::Deref;

use crate::math::sample::{Border, Plane};
use crate::math::{angle, Ellipse};
use std::f64::consts::PI;

/// Rings whose sectors are narrower than this many pixels (at the sample
/// radius, along the ellipse's minor axis) are not read: below it the
/// sectors blur together and a read would be a guess.
pub const MIN_PIXELS_PER_SECTOR: f64 = 1.2;

/// Least difference between a bit's two halves, relative to the black-white
/// contrast, for the ring to count as visible at all.
const MIN_RING_CONTRAST: f64 = 0.10;

/// A bit whose two halves differ by less than this fraction of the ring's
/// typical bit contrast is an erasure (broken Manchester structure).
const ERASURE_RATIO: f64 = 0.45;

/// Below this confidence a decoded member is not reported as the ID.
pub const MIN_ID_CONFIDENCE: f64 = 0.1;

/// Least edge strength and sector width (pixels) at which erased bits are
/// filled from the family's distance.
const MIN_FILL_STRENGTH: f64 = 0.3;
const MIN_FILL_PIXELS: f64 = 2.0;

/// Least reading quality (edge strength, sector width, weakest kept bit)
/// at which a reading with filled erasures that still needed correcting is
/// named: 8-bit rings under 20-25 px of motion blur were read that way to
/// wrong IDs at quality 0.66-0.74 (and to no right one). Such rings are
/// now read by the blurred ring model (`ring_model::read_blurred_ring`),
/// which also overrules a corrected reading it cannot confirm; this guard
/// stays for smears the outline does not show as a linear blur.
const MIN_FILLED_QUALITY: f64 = 0.9;

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
    /// The member ID, 0 when unknown, not a member, or decoded with a
    /// confidence under [`MIN_ID_CONFIDENCE`] (then only `decoded` names
    /// the candidate, for the ID filter to weigh).
    pub id: u32,
    /// Image direction of the marker's +x axis, atan2(dv, du), radians;
    /// `None` unless the ID is known, and also when the error read lies
    /// equally close to two of the code's rotations.
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
    /// Projection of the marker centre as the ring shows it (under
    /// perspective it differs from the outer ellipse's centre); `None`
    /// when the ring was not sampled.
    pub projected_centre: Option<(f64, f64)>,
    /// Where the ring's radial edges meet (the image of the marker's
    /// centre), even when too close to the ellipse centre to rectify by:
    /// the pose stage tells its two candidate normals apart by it.
    pub centre_estimate: Option<(f64, f64)>,
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
            projected_centre: None,
            centre_estimate: None,
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
pub(super) fn sample_radii() -> [f64; 5] {
    let width = WHYCODE_WHITE_RATIO - RING_INNER_RATIO;
    [1.0, 2.0, 3.0, 4.0, 5.0].map(|k| RING_INNER_RATIO + width * k / 6.0)
}

impl RingReader {
    /// A reader that decodes rings with `decoder`, or only measures them without one.
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

    /// The decoder the reader uses, if any.
    pub fn decoder(&self) -> Option<&Decoder> {
        self.decoder.as_ref()
    }

    /// Reads the ring inside the outer ellipse `outer`. `black_level` and
    /// `white_level` are the grey levels of the marker's black disc and white
    /// disc as the detector measured them.
    pub fn read<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        black_level: f64,
        white_level: f64,
    ) -> RingReading {
        self.read_light(image, outer, black_level, white_level, false)
    }

    /// As [`RingReader::read`], for a ring that a cast shadow's edge
    /// crosses (the structure test found it so,
    /// [`super::manchester::RingStructure::in_shade`]): the ring's profile
    /// is read as under even light ([`evened_light`]).
    pub fn read_in_shade<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        black_level: f64,
        white_level: f64,
    ) -> RingReading {
        self.read_light(image, outer, black_level, white_level, true)
    }

    fn read_light<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        black_level: f64,
        white_level: f64,
        in_shade: bool,
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

        // About one sample per pixel along the outermost sample radius
        // (bilinear interpolation keeps the profile smooth between them);
        // small rings average more radii against noise.
        let arc = 2.0 * PI * radii[4] * outer.semi_major;
        let per_sector = ((arc / f64::from(2 * bits)).ceil() as usize).clamp(8, 256);
        let radii: &[f64] = if outer.semi_minor < 20.0 {
            &radii
        } else {
            &[radii[0], radii[2], radii[4]]
        };
        let count = per_sector * 2 * bits as usize;
        let mut frame = EllipseFrame::new(outer);
        let Some(mut profile) = sample_profile(image, &frame, radii, count) else {
            return RingReading::unreadable(pixels_per_sector);
        };
        let mut phase = edge_phase(&profile, bits, per_sector);

        // Under perspective the ring is neither centred on the outer ellipse
        // nor evenly spaced in its parameter. Locate the projected marker
        // centre from the ring's own radial edges and read again through the
        // exact rectification when it moves by more than a tenth of a pixel.
        let mid_level = 0.5 * (black_level + white_level);
        // Starting needs a clear offset (noise and blur move the estimate
        // by a tenth of a pixel on a face-on ring); once rectifying, refine
        // until it settles.
        let mut threshold = 0.25;
        let mut centre_estimate = None;
        for _ in 0..3 {
            let Some(p) = refined_centre(image, &frame, phase, bits, mid_level) else {
                break;
            };
            centre_estimate = Some(p);
            let moved = (p.0 - frame.projected_centre.0).hypot(p.1 - frame.projected_centre.1);
            let offset = (p.0 - outer.u).hypot(p.1 - outer.v);
            if moved < threshold || offset > 0.3 * outer.semi_minor {
                break;
            }
            let Some(rectified) = EllipseFrame::with_projected_centre(outer, p) else {
                break;
            };
            let Some(resampled) = sample_profile(image, &rectified, radii, count) else {
                break;
            };
            profile = resampled;
            phase = edge_phase(&profile, bits, per_sector);
            frame = rectified;
            threshold = 0.1;
        }

        let even = in_shade
            .then(|| paper_profile(image, &frame, count))
            .flatten()
            .and_then(|paper| evened_light(&profile, &paper, bits));
        if let Some(even) = even {
            profile = even;
        }
        let halves_a = half_sector_means(&profile, bits, phase);
        let halves_b = half_sector_means(&profile, bits, phase + sector);
        let diffs_a = bit_differences(&halves_a);
        let diffs_b = bit_differences(&halves_b);
        let score = |d: &[f64]| d.iter().map(|x| x.abs()).sum::<f64>();
        let (start, diffs, other_diffs) = if score(&diffs_a) >= score(&diffs_b) {
            (phase, diffs_a, diffs_b)
        } else {
            (phase + sector, diffs_b, diffs_a)
        };
        let (best_score, other_score) = (score(&diffs), score(&other_diffs));

        let typical = median(diffs.iter().map(|d| d.abs()).collect());
        let edge_strength = typical / contrast;
        let mut reading = RingReading {
            edge_strength,
            pixels_per_sector,
            projected_centre: Some(frame.projected_centre),
            centre_estimate,
            ..RingReading::unreadable(pixels_per_sector)
        };
        // Only a word with all bits equal reads alike under both pairings,
        // and those are periodic; anything close to a tie is noise.
        let parity_clear = best_score - other_score > 0.5 * typical;
        if edge_strength < MIN_RING_CONTRAST {
            return reading;
        }
        if !parity_clear {
            // Clean Manchester bits under both pairings: a ring alternating
            // every sector, i.e. all bits equal. Either reading is periodic,
            // so it is no member whichever way it is paired.
            let all_clear = diffs
                .iter()
                .chain(&other_diffs)
                .all(|d| d.abs() > (1.0 - ERASURE_RATIO) * typical);
            if all_clear {
                let decoded = decoder.decode(0);
                reading.word = Some(0);
                reading.decoded = Some(decoded);
                reading.confidence = logistic((edge_strength - 0.15) / 0.03);
            }
            return reading;
        }

        let mut word = 0u32;
        for (j, d) in diffs.iter().enumerate() {
            // First half brighter than the second: white then black, a 1.
            if *d > 0.0 {
                word |= 1 << (bits as usize - 1 - j);
            }
        }
        let references = bit_references(&diffs, typical);
        let mut erasures = Vec::new();
        let mut weakest_bit = f64::INFINITY;
        // Erased bits are paid for by the decoded distance instead.
        let mut weakest_kept = 1.0f64;
        for (j, (d, reference)) in diffs.iter().zip(&references).enumerate() {
            let relative = d.abs() / reference;
            weakest_bit = weakest_bit.min(relative);
            if relative < ERASURE_RATIO {
                erasures.push(j as u32);
            } else {
                weakest_kept = weakest_kept.min(relative);
            }
        }
        reading.weakest_bit = weakest_bit.min(1.0);
        reading.word = Some(word);
        reading.erasures = erasures.len() as u32;

        // Filling erasures assumes every other bit is right, which only a
        // sharp, well-resolved ring (a local smudge or glare) warrants.
        let fillable = edge_strength >= MIN_FILL_STRENGTH && pixels_per_sector >= MIN_FILL_PIXELS;
        let decoded = if erasures.is_empty() {
            decoder.decode(word)
        } else if !fillable {
            return reading;
        } else {
            match fill_erasures(decoder, word, &erasures) {
                Some(d) => d,
                None => return reading,
            }
        };
        reading.decoded = Some(decoded);

        let quality = logistic((edge_strength - 0.15) / 0.03)
            * logistic((pixels_per_sector - 1.1) / 0.1)
            * (weakest_kept / 0.7).min(1.0);
        match decoded.status {
            MatchStatus::Exact | MatchStatus::Corrected => {
                if !erasures.is_empty() && decoded.distance > 0 && quality < MIN_FILLED_QUALITY {
                    // Filling erasures and then correcting bits besides
                    // trusts a ring with weak bits left (motion blur smears
                    // sectors into their neighbours), which is as likely
                    // another member's.
                    reading.decoded = Some(decoded);
                    reading.confidence = quality * 0.5f64.powi(decoded.distance as i32);
                    return reading;
                }
                let status_factor = 0.5f64.powi(decoded.distance as i32);
                reading.confidence = quality * status_factor;
                if reading.confidence < MIN_ID_CONFIDENCE {
                    // Kept in `decoded` as (weak) evidence for the ID
                    // filter, but not named: a guess is not an answer.
                    return reading;
                }
                reading.id = decoded.id;
                if decoded.rotation_ambiguous {
                    // The ID is certain, but the error sits between two of
                    // the code's own rotations: no yaw rather than a guess.
                    return reading;
                }
                let x_axis_t = start + 2.0 * sector * f64::from(decoded.rotation);
                // The rim point on the outer ellipse, seen from the
                // estimated projection of the marker centre.
                let (ax, ay) = frame.point(x_axis_t, 1.0);
                let (cx, cy) = frame.projected_centre;
                reading.yaw = Some((ay - cy).atan2(ax - cx));
                reading.axis_point = Some((ax, ay));
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

/// The contrast each bit should show if the ring were read cleanly. Blur
/// attenuates a half-sector flanked by the opposite colour (a bit next to
/// an equal bit) more than one that joins a run of two, so bits are
/// compared within their class (how many of their halves are isolated);
/// within a class the clearer bits set the reference, since motion blur
/// fades (or even inverts) a whole arc of the ring and the median can fall
/// inside it.
fn bit_references(diffs: &[f64], typical: f64) -> Vec<f64> {
    let n = diffs.len();
    let bit = |j: usize| diffs[j % n] > 0.0;
    let class =
        |j: usize| usize::from(bit(j + n - 1) == bit(j)) + usize::from(bit(j + 1) == bit(j));
    let mut per_class: [Vec<f64>; 3] = Default::default();
    for (j, d) in diffs.iter().enumerate() {
        per_class[class(j)].push(d.abs());
    }
    let class_reference: Vec<f64> = per_class
        .into_iter()
        .map(|mut m| {
            if m.len() < 3 {
                return typical;
            }
            m.sort_by(f64::total_cmp);
            m[m.len() * 3 / 4]
        })
        .collect();
    (0..n)
        .map(|j| class_reference[class(j)].max(f64::MIN_POSITIVE))
        .collect()
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
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
    projected_centre: (f64, f64),
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
    fn point(&self, t: f64, rho: f64) -> (f64, f64) {
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

/// Parameter (radians, in [0, one sector)) of the ring's sector boundaries:
/// the phase of the 2n-th harmonic of the gradient magnitude. Each edge
/// contributes a phasor at its own position, so the estimate moves
/// continuously with the marker and is not tied to the sample grid.
fn edge_phase(profile: &[f64], bits: u32, per_sector: usize) -> f64 {
    let count = profile.len();
    // 2n·t at the midpoint between samples j and j+1 repeats every sector.
    let phasors: Vec<(f64, f64)> = (0..per_sector)
        .map(|j| (2.0 * PI * (j as f64 + 0.5) / per_sector as f64).sin_cos())
        .collect();
    let (mut re, mut im) = (0.0, 0.0);
    for j in 0..count {
        let g = (profile[(j + 1) % count] - profile[j]).abs();
        let (sin, cos) = phasors[j % per_sector];
        re += g * cos;
        im -= g * sin;
    }
    let sector = PI / f64::from(bits);
    let phase = -im.atan2(re) / f64::from(2 * bits);
    phase.rem_euclid(sector)
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
pub(crate) fn evened_light(profile: &[f64], paper: &[f64], bits: u32) -> Option<Vec<f64>> {
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
