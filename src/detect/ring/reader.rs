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

use std::f64::consts::PI;
use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::profile::{
    bit_differences, boundary_phase, evened_light, half_sector_means, paper_profile,
    refined_centre, sample_profile, sample_radii, EllipseFrame,
};
use crate::family::{Decoded, Decoder, MatchStatus};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::Ellipse;

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
/// named: under heavy motion blur such readings named wrong IDs well below
/// it, and no right one (docs/detection.md, "Reporting rules"). Such rings
/// are now read by the blurred ring model (`model::read_blurred_ring`),
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
    /// is read as under even light (`profile::evened_light`).
    pub fn read_in_shade<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        black_level: f64,
        white_level: f64,
    ) -> RingReading {
        self.read_light(image, outer, black_level, white_level, true)
    }

    /// The reading's stages: the ring's scale, its profile (rectified under
    /// perspective, evened under a shadow's edge), the pairing of its
    /// half-sectors into bits, the bits, their decoding and what the
    /// decoded member earns.
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
        let scale = RingScale::of(outer, decoder.family().bits(), black_level, white_level);
        if scale.unreadable(self.min_pixels_per_sector) {
            return RingReading::unreadable(scale.pixels_per_sector.max(0.0));
        }
        let Some(mut ring) = RingProfile::sample(image, outer, scale.bits) else {
            return RingReading::unreadable(scale.pixels_per_sector);
        };
        let centre_estimate = ring.rectify(image, outer, 0.5 * (black_level + white_level));
        if in_shade {
            ring.even_light(image);
        }
        let pairing = Pairing::of(&ring.profile, scale.bits, ring.phase, scale.sector);
        let mut reading = RingReading {
            edge_strength: pairing.typical / scale.contrast,
            pixels_per_sector: scale.pixels_per_sector,
            projected_centre: Some(ring.frame.projected_centre),
            centre_estimate,
            ..RingReading::unreadable(scale.pixels_per_sector)
        };
        if reading.edge_strength < MIN_RING_CONTRAST {
            return reading;
        }
        if !pairing.clear() {
            return all_bits_equal(decoder, &pairing, reading);
        }
        let bits = BitsRead::of(&pairing, scale.bits);
        bits.record(&mut reading);
        let Some(decoded) = decode(decoder, &bits, &reading) else {
            return reading;
        };
        let Some(rotation) = weigh(&mut reading, decoded, &bits) else {
            return reading;
        };
        let x_axis_t = pairing.start + 2.0 * scale.sector * f64::from(rotation);
        let (yaw, axis_point) = x_axis(&ring.frame, x_axis_t);
        RingReading {
            yaw: Some(yaw),
            axis_point: Some(axis_point),
            ..reading
        }
    }
}

/// A ring's size against what the reader can read.
struct RingScale {
    bits: u32,
    /// A sector's span in the ellipse's parameter, radians.
    sector: f64,
    /// A sector's width in pixels at the sample radius, narrowest place.
    pixels_per_sector: f64,
    /// White level less black level.
    contrast: f64,
    /// The outline is a finite ellipse and the levels differ clearly.
    sound: bool,
}

impl RingScale {
    fn of(outer: &Ellipse, bits: u32, black_level: f64, white_level: f64) -> RingScale {
        let sector = PI / f64::from(bits);
        let mid_ratio = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
        let pixels_per_sector = outer.semi_minor * mid_ratio * sector;
        let contrast = white_level - black_level;
        let sound = [
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
        RingScale {
            bits,
            sector,
            pixels_per_sector,
            contrast,
            sound,
        }
    }

    /// Whether the ring is not to be read: unsound, or its sectors narrower
    /// than `min_pixels_per_sector`.
    fn unreadable(&self, min_pixels_per_sector: f64) -> bool {
        !self.sound || self.pixels_per_sector < min_pixels_per_sector
    }
}

/// The ring's profile along the ellipse's parameter, with the frame it
/// was sampled through and the phase of its sector boundaries.
struct RingProfile {
    bits: u32,
    /// Samples a sector.
    per_sector: usize,
    /// Samples round the ring.
    count: usize,
    /// Radii (of the outer ellipse) each sample averages over.
    radii: Vec<f64>,
    frame: EllipseFrame,
    profile: Vec<f64>,
    phase: f64,
}

impl RingProfile {
    /// Sampled through the outer ellipse's own frame; `None` when the ring
    /// leaves the image.
    fn sample<C: Deref<Target = [u8]>>(
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        bits: u32,
    ) -> Option<RingProfile> {
        let radii = sample_radii();
        // About one sample per pixel along the outermost sample radius
        // (bilinear interpolation keeps the profile smooth between them);
        // small rings average more radii against noise.
        let arc = 2.0 * PI * radii[4] * outer.semi_major;
        let per_sector = ((arc / f64::from(2 * bits)).ceil() as usize).clamp(8, 256);
        let radii = if outer.semi_minor < 20.0 {
            radii.to_vec()
        } else {
            vec![radii[0], radii[2], radii[4]]
        };
        let count = per_sector * 2 * bits as usize;
        let frame = EllipseFrame::new(outer);
        let profile = sample_profile(image, &frame, &radii, count)?;
        let phase = boundary_phase(&profile, bits, per_sector);
        Some(RingProfile {
            bits,
            per_sector,
            count,
            radii,
            frame,
            profile,
            phase,
        })
    }

    /// Under perspective the ring is neither centred on the outer ellipse
    /// nor evenly spaced in its parameter. Locates the projected marker
    /// centre from the ring's own radial edges (where the grey crosses
    /// `mid_level`) and reads again through the exact rectification when it
    /// moves by more than a tenth of a pixel. Returns where the radial
    /// edges meet, `None` when they could not be located.
    fn rectify<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &Ellipse,
        mid_level: f64,
    ) -> Option<(f64, f64)> {
        // Starting needs a clear offset (noise and blur move the estimate
        // by a tenth of a pixel on a face-on ring); once rectifying, refine
        // until it settles.
        let mut threshold = 0.25;
        let mut centre_estimate = None;
        for _ in 0..3 {
            let Some(p) = refined_centre(image, &self.frame, self.phase, self.bits, mid_level)
            else {
                break;
            };
            centre_estimate = Some(p);
            let projected = self.frame.projected_centre;
            let moved = (p.0 - projected.0).hypot(p.1 - projected.1);
            let offset = (p.0 - outer.u).hypot(p.1 - outer.v);
            if moved < threshold || offset > 0.3 * outer.semi_minor {
                break;
            }
            let Some(rectified) = EllipseFrame::with_projected_centre(outer, p) else {
                break;
            };
            let Some(resampled) = sample_profile(image, &rectified, &self.radii, self.count) else {
                break;
            };
            self.profile = resampled;
            self.phase = boundary_phase(&self.profile, self.bits, self.per_sector);
            self.frame = rectified;
            threshold = 0.1;
        }
        centre_estimate
    }

    /// The profile as under even light, judged from the paper round the
    /// marker (unchanged when that cannot be read).
    fn even_light<C: Deref<Target = [u8]>>(&mut self, image: &ImageBuffer<Luma<u8>, C>) {
        let even = paper_profile(image, &self.frame, self.count)
            .and_then(|paper| evened_light(&self.profile, &paper, self.bits));
        if let Some(even) = even {
            self.profile = even;
        }
    }
}

/// The half-sectors paired into bits: of the two classes of sector
/// boundary, the one taken for the mandatory mid-bit edge is the pairing
/// under which the bits are most clearly Manchester.
struct Pairing {
    /// Where the first bit starts, in the ellipse's parameter.
    start: f64,
    /// Each bit's first half less its second, under this pairing.
    diffs: Vec<f64>,
    /// The same under the other pairing.
    other_diffs: Vec<f64>,
    /// The median bit's difference, in grey levels.
    typical: f64,
}

impl Pairing {
    fn of(profile: &[f64], bits: u32, phase: f64, sector: f64) -> Pairing {
        let halves_a = half_sector_means(profile, bits, phase);
        let halves_b = half_sector_means(profile, bits, phase + sector);
        let diffs_a = bit_differences(&halves_a);
        let diffs_b = bit_differences(&halves_b);
        let (start, diffs, other_diffs) = if pairing_score(&diffs_a) >= pairing_score(&diffs_b) {
            (phase, diffs_a, diffs_b)
        } else {
            (phase + sector, diffs_b, diffs_a)
        };
        let typical = median(diffs.iter().map(|d| d.abs()).collect());
        Pairing {
            start,
            diffs,
            other_diffs,
            typical,
        }
    }

    /// Only a word with all bits equal reads alike under both pairings,
    /// and those are periodic; anything close to a tie is noise.
    fn clear(&self) -> bool {
        pairing_score(&self.diffs) - pairing_score(&self.other_diffs) > 0.5 * self.typical
    }
}

/// How clearly Manchester the bits' differences are.
fn pairing_score(diffs: &[f64]) -> f64 {
    diffs.iter().map(|x| x.abs()).sum::<f64>()
}

/// A ring whose two pairings read about alike. Clean Manchester bits under
/// both pairings are a ring alternating every sector, i.e. all bits equal.
/// Either reading is periodic, so it is no member whichever way it is
/// paired.
fn all_bits_equal(decoder: &Decoder, pairing: &Pairing, mut reading: RingReading) -> RingReading {
    let all_clear = pairing
        .diffs
        .iter()
        .chain(&pairing.other_diffs)
        .all(|d| d.abs() > (1.0 - ERASURE_RATIO) * pairing.typical);
    if all_clear {
        let decoded = decoder.decode(0);
        reading.word = Some(0);
        reading.decoded = Some(decoded);
        reading.confidence = logistic((reading.edge_strength - 0.15) / 0.03);
    }
    reading
}

/// The bits a pairing reads, and how clearly.
struct BitsRead {
    /// The bits read, the first in the most significant place.
    word: u32,
    /// The bits whose halves are not clearly opposite.
    erasures: Vec<u32>,
    /// The weakest bit's difference relative to its reference.
    weakest_bit: f64,
    /// The same over the bits kept (at most 1): erased bits are paid for
    /// by the decoded distance instead.
    weakest_kept: f64,
}

impl BitsRead {
    fn of(pairing: &Pairing, bits: u32) -> BitsRead {
        let diffs = &pairing.diffs;
        let mut word = 0u32;
        for (j, d) in diffs.iter().enumerate() {
            // First half brighter than the second: white then black, a 1.
            if *d > 0.0 {
                word |= 1 << (bits as usize - 1 - j);
            }
        }
        let references = bit_references(diffs, pairing.typical);
        let mut erasures = Vec::new();
        let mut weakest_bit = f64::INFINITY;
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
        BitsRead {
            word,
            erasures,
            weakest_bit,
            weakest_kept,
        }
    }

    /// What the reading reports of the bits.
    fn record(&self, reading: &mut RingReading) {
        reading.weakest_bit = self.weakest_bit.min(1.0);
        reading.word = Some(self.word);
        reading.erasures = self.erasures.len() as u32;
    }
}

/// The decoder's verdict on the bits read, erasures filled from the
/// family's distance; `None` when erasures are left that cannot be filled.
fn decode(decoder: &Decoder, bits: &BitsRead, reading: &RingReading) -> Option<Decoded> {
    // Filling erasures assumes every other bit is right, which only a
    // sharp, well-resolved ring (a local smudge or glare) warrants.
    let fillable =
        reading.edge_strength >= MIN_FILL_STRENGTH && reading.pixels_per_sector >= MIN_FILL_PIXELS;
    if bits.erasures.is_empty() {
        Some(decoder.decode(bits.word))
    } else if !fillable {
        None
    } else {
        fill_erasures(decoder, bits.word, &bits.erasures)
    }
}

/// Records `decoded` in `reading` with the confidence it earns, and the
/// member's ID when that is enough to name it. Returns the code's rotation
/// when the yaw follows from it too.
fn weigh(reading: &mut RingReading, decoded: Decoded, bits: &BitsRead) -> Option<u32> {
    reading.decoded = Some(decoded);
    let quality = logistic((reading.edge_strength - 0.15) / 0.03)
        * logistic((reading.pixels_per_sector - 1.1) / 0.1)
        * (bits.weakest_kept / 0.7).min(1.0);
    match decoded.status {
        MatchStatus::Exact | MatchStatus::Corrected => {
            if !bits.erasures.is_empty() && decoded.distance > 0 && quality < MIN_FILLED_QUALITY {
                // Filling erasures and then correcting bits besides
                // trusts a ring with weak bits left (motion blur smears
                // sectors into their neighbours), which is as likely
                // another member's.
                reading.confidence = quality * 0.5f64.powi(decoded.distance as i32);
                return None;
            }
            let status_factor = 0.5f64.powi(decoded.distance as i32);
            reading.confidence = quality * status_factor;
            if reading.confidence < MIN_ID_CONFIDENCE {
                // Kept in `decoded` as (weak) evidence for the ID
                // filter, but not named: a guess is not an answer.
                return None;
            }
            reading.id = decoded.id;
            if decoded.rotation_ambiguous {
                // The ID is certain, but the error sits between two of
                // the code's own rotations: no yaw rather than a guess.
                return None;
            }
            Some(decoded.rotation)
        }
        MatchStatus::Rejected => {
            reading.confidence = quality;
            None
        }
        MatchStatus::Ambiguous => {
            reading.confidence = 0.0;
            None
        }
    }
}

/// The yaw of the marker's +x axis, at `x_axis_t` in the ellipse's
/// parameter, and its rim point on the outer ellipse: the yaw is the
/// direction to the rim point as seen from the estimated projection of
/// the marker centre.
fn x_axis(frame: &EllipseFrame, x_axis_t: f64) -> (f64, (f64, f64)) {
    let (ax, ay) = frame.point(x_axis_t, 1.0);
    let (cx, cy) = frame.projected_centre;
    ((ay - cy).atan2(ax - cx), (ax, ay))
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

#[cfg(test)]
mod tests {
    use super::super::test_images::{angle_between, draw, INK, PAPER};
    use super::*;
    use crate::family::Family;
    use crate::geometry::Marker;

    const BLACK: f64 = INK as f64;
    const WHITE: f64 = PAPER as f64;

    #[test]
    fn a_drawn_ring_reads_as_its_member_with_its_turn() {
        let family = Family::generate(8, 2).unwrap();
        let reader = RingReader::new(Some(Decoder::new(&family)));
        for (id, turn) in [(1, 0.0), (5, 1.0), (9, -2.5)] {
            let code = family.code(id).unwrap();
            let marker = Marker::whycode(8, code, 50.0);
            let (image, outline) = draw(&marker, 48.0, 64, (31.7, 32.2), turn);
            let reading = reader.read(&image, &outline, BLACK, WHITE);
            assert_eq!(reading.id, id, "{reading:?}");
            assert_eq!(reading.erasures, 0);
            assert_eq!(reading.decoded.map(|d| d.status), Some(MatchStatus::Exact));
            // The +x axis points along image angle -turn.
            let yaw = reading.yaw.unwrap();
            assert!(
                angle_between(yaw, -turn) < 0.5f64.to_radians(),
                "{id}: {yaw} {turn}"
            );
            // Read as under even light, an evenly lit ring reads the same.
            assert_eq!(
                reader.read_in_shade(&image, &outline, BLACK, WHITE),
                reading
            );
        }
    }

    #[test]
    fn a_ring_without_sectors_or_too_fine_to_sample_names_nothing() {
        let family = Family::generate(8, 2).unwrap();
        let reader = RingReader::new(Some(Decoder::new(&family)));
        // A WhyCon disc: the ring's band is black all round.
        let (image, outline) = draw(&Marker::whycon(50.0), 48.0, 64, (32.0, 32.0), 0.0);
        let reading = reader.read(&image, &outline, BLACK, WHITE);
        assert_eq!((reading.id, reading.decoded), (0, None), "{reading:?}");
        // Sectors under MIN_PIXELS_PER_SECTOR wide are not read at all.
        let code = family.code(3).unwrap();
        let (image, outline) = draw(&Marker::whycode(8, code, 50.0), 9.0, 16, (8.0, 8.0), 0.0);
        let reading = reader.read(&image, &outline, BLACK, WHITE);
        assert!(reading.pixels_per_sector < MIN_PIXELS_PER_SECTOR);
        assert_eq!((reading.word, reading.projected_centre), (None, None));
        // Without a decoder (legacy markers) nothing is read.
        let (image, outline) = draw(&Marker::whycode(8, code, 50.0), 48.0, 64, (32.0, 32.0), 0.0);
        assert_eq!(
            RingReader::new(None).read(&image, &outline, BLACK, WHITE),
            RingReading::unreadable(0.0)
        );
    }
}
