//! Does a round candidate carry a WhyCode ring, and of how many bits?
//!
//! A dark disc with a light middle is common on a desk (washers, letters,
//! rings, stickers); what only a WhyCode marker has is the Manchester code
//! ring (spec section 2): 2n equal sectors where every bit is one black and
//! one white half-sector, so there is an edge in the middle of every bit and
//! nowhere but on sector boundaries. The test reads the ring's angular
//! profile for a bit count n:
//!
//! 1. the phase of the sector boundaries from the 2n-th harmonic of the
//!    profile's gradient magnitude, and the pairing of half-sectors into
//!    bits under which the bits are most clearly Manchester;
//! 2. the contrast between the bright and the dark half of every bit: the
//!    ring must show real contrast and every bit (all but a smudged one on
//!    long codes) must have its mid-bit edge;
//! 3. how much of the profile's variance the n-bit Manchester square wave,
//!    blurred as much as fits best, explains: a ring of another bit count
//!    puts edges inside the sectors, and a washer or a letter has no
//!    sector structure at all.
//!
//! A ring of n bits fails the test for 2n bits (the aligned pairing puts
//! both halves in one sector) and for n/2 bits (every sector holds a
//! mid-bit edge), so the bit count a ring passes for is the one printed.

use std::f64::consts::PI;
use std::ops::RangeInclusive;

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::profile::{
    bit_differences, boundary_phases, evened_light, gradient, half_sector_means, paper_profile,
    refined_centre, sample_profile, sample_radii, EllipseFrame,
};
use crate::family::necklace;
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::angle;
use crate::math::Ellipse as ImageEllipse;

/// Bit counts a ring may carry (the family generator's range).
pub const BITS: RangeInclusive<u32> = 4..=24;

/// Sector width (pixels, at the middle of the ring along the minor axis)
/// below which the sector structure is not tested: the ring blurs into a
/// grey band.
pub const MIN_TESTABLE_PIXELS: f64 = 1.3;

/// Least bright-minus-dark difference of the ring's half-sectors, relative
/// to the disc's black-white contrast.
const MIN_CONTRAST: f64 = 0.2;

/// A bit whose halves differ by less than this fraction of the ring's
/// contrast has no mid-bit edge.
const MIN_BIT_EDGE: f64 = 0.3;

/// Least share of the profile's variance the blurred Manchester model must
/// explain (squared correlation).
const MIN_FIT: f64 = 0.7;

/// A fit of the first count tried at least this good settles the count.
const SURE_FIT: f64 = 0.9;

/// Outer ellipses longer than this many times their width (a view of
/// about 50° and more) are steep enough for perspective to space the
/// sectors unevenly along the ellipse.
const STEEP_AXIS_RATIO: f64 = 1.5;

/// A plain reading of the expected count this good earns it a rectified
/// re-read of its own on a steep view (70° views read 0.66 before it).
const EXPECTED_RETRY_FIT: f64 = 0.6;

/// What the ring of one candidate shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RingEvidence {
    /// A Manchester ring of this many bits.
    Manchester(RingStructure),
    /// Sharp enough to show sectors, and it shows none of any bit count tried.
    Absent,
    /// Too small (or too blurred by its size) to test for the bit counts tried.
    TooSmall,
}

/// A Manchester ring as read by the structure test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RingStructure {
    /// The bit count the ring shows.
    pub bits: u32,
    /// The necklace read, as its smallest rotation (the form family tables
    /// list codes in).
    pub code: u32,
    /// Bright minus dark half-sector level, relative to the disc's contrast.
    pub contrast: f64,
    /// Squared correlation of the profile with the blurred model.
    pub fit: f64,
    /// The weakest bit's mid-edge relative to the ring's contrast.
    pub weakest_bit: f64,
    /// The ring passed only read as under even light (a cast shadow's edge
    /// crosses it): its bits are to be read so too
    /// ([`super::RingReader::read_in_shade`]).
    pub in_shade: bool,
}

/// True when the ring inside `outer` is large enough to show the sector
/// structure of `bits` bits.
pub fn testable(outer: &ImageEllipse, bits: u32) -> bool {
    sector_pixels(outer, bits) >= MIN_TESTABLE_PIXELS
}

/// Width in pixels of one half-bit sector of a `bits`-bit ring inside
/// `outer`, at the middle of the ring along the minor axis.
pub fn sector_pixels(outer: &ImageEllipse, bits: u32) -> f64 {
    let mid_ratio = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
    outer.semi_minor * mid_ratio * PI / f64::from(bits)
}

/// Tests the ring inside `outer` for Manchester structure with each bit
/// count in `bits`; of the counts that pass, the one whose model fits best
/// wins (a ring of n bits can pass for n ± 1 when its profile is short).
/// When none passes, the ring is `Absent` only if every count could be
/// tested. With `expected` (a family's count first in `bits`), a ring
/// that a cast shadow's edge crosses is tried for that count as under
/// even light too.
pub fn examine<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    black_level: f64,
    white_level: f64,
    bits: impl IntoIterator<Item = u32>,
    expected: bool,
) -> RingEvidence {
    let contrast = white_level - black_level;
    let valid = [outer.u, outer.v, outer.semi_major, outer.semi_minor]
        .iter()
        .all(|x| x.is_finite())
        && outer.semi_minor > 0.0
        && contrast.is_finite()
        && contrast > 4.0;
    if !valid {
        return RingEvidence::Absent;
    }
    let mid_ratio = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
    let (counts, untestable): (Vec<u32>, Vec<u32>) =
        bits.into_iter().partition(|&n| testable(outer, n));
    let absent = if untestable.is_empty() {
        RingEvidence::Absent
    } else {
        RingEvidence::TooSmall
    };
    if counts.is_empty() {
        return RingEvidence::TooSmall;
    }
    let radii = sample_radii();
    let radii: &[f64] = if outer.semi_minor < 20.0 {
        &radii
    } else {
        &[radii[0], radii[2], radii[4]]
    };
    // Two samples per pixel along the outer sample radius, and at least
    // eight per sector of the longest code.
    let arc = 2.0 * PI * radii[radii.len() - 1] * outer.semi_major;
    let count = ((2.0 * arc).ceil() as usize).clamp(16 * 24, 2048);
    let pixels_per_sample =
        2.0 * PI * mid_ratio * (outer.semi_major * outer.semi_minor).sqrt() / count as f64;
    let mut model = Model::new(pixels_per_sample, count);
    let mut test_profile = |profile: &[f64], counts: &[u32]| -> Vec<Tested> {
        let ring = Profile::new(profile);
        boundary_phases(&ring.gradient, ring.gradient_total, counts)
            .into_iter()
            .zip(counts)
            .map(|(boundaries, &n)| test_bits(&ring, n, boundaries, contrast, &mut model))
            .collect()
    };
    let best = |tested: &[Tested]| {
        tested
            .iter()
            .filter_map(|t| t.ring)
            .filter(|r| r.fit >= MIN_FIT)
            .max_by(|a, b| a.fit.total_cmp(&b.fit))
    };
    let frame = EllipseFrame::new(outer);
    // The expected count first (a family's): a ring that fits it this
    // well fits no other count nearly as well (a neighbouring count drifts
    // half a sector around the ring), so the rest need no look.
    // Cut by the image border: nothing to test, nothing to refute.
    let Some(profile) = sample_profile(image, &frame, radii, count) else {
        return RingEvidence::TooSmall;
    };
    let first = test_profile(&profile, &counts[..1]);
    if let Some(ring) = best(&first).filter(|r| r.fit >= SURE_FIT) {
        return RingEvidence::Manchester(ring);
    }
    let steep = outer.semi_major > STEEP_AXIS_RATIO * outer.semi_minor;
    let mid_level = 0.5 * (black_level + white_level);
    // The ring's profile through the rectification that the sides of
    // `bits` bits at `phase` show (see `refined_centre`).
    let rectified_profile = |phase: f64, bits: u32| {
        let centre = refined_centre(image, &frame, phase, bits, mid_level)?;
        let frame = EllipseFrame::with_projected_centre(outer, centre)?;
        sample_profile(image, &frame, radii, count)
    };
    // Short of a steep view, perspective still bends the sectors enough
    // to cost a family's count its sure fit (a 30° view of a marker 80 px
    // across reads 0.88). Read through the rectification its own sides
    // show, a ring of that count fits surely again (0.99), and a ring of
    // another count does not: the count is settled, and the plain reading
    // stands, as it would have among the other counts.
    if expected && !steep {
        if let Some(plain) = best(&first) {
            let settled = rectified_profile(first[0].phase, counts[0])
                .and_then(|profile| test_profile(&profile, &counts[..1]).pop()?.ring)
                .is_some_and(|r| r.fit >= SURE_FIT && r.code == plain.code);
            if settled {
                return RingEvidence::Manchester(plain);
            }
        }
    }
    let tested: Vec<Tested> = first
        .into_iter()
        .chain(test_profile(&profile, &counts[1..]))
        .collect();
    let plain = best(&tested);
    // A steep view whose ring fits no count surely may fit a wrong count
    // best (an 8-bit ring at 60° passes for 7 bits): it is read again
    // rectified below, and the better fit of the two kept.
    match plain {
        Some(ring) if ring.fit >= SURE_FIT || !steep => return RingEvidence::Manchester(ring),
        _ => {}
    }
    // Perspective: the outer ellipse's parameter does not space the ring's
    // sectors evenly on a steep view, which spoils the model's fit. The
    // ring's own radial edges show where the marker's centre projects;
    // read again through that exact rectification.
    // The count whose boundaries the edges follow best sets the rays, and
    // the count expected first (a family's) too: on a view of 70° its
    // sides may look less regular than another count's before the
    // rectification that evens them out.
    let Some(nearest) =
        (0..counts.len()).max_by(|&a, &b| tested[a].coherence.total_cmp(&tested[b].coherence))
    else {
        return absent;
    };
    // The expected count only when its own plain reading came close: a
    // ring blurred past reading fits any count's rectified sides a little.
    let expected_close = tested[0].ring.is_some_and(|r| r.fit >= EXPECTED_RETRY_FIT);
    let again = [nearest, 0][..if nearest == 0 || !expected_close {
        1
    } else {
        2
    }]
        .iter()
        .filter_map(|&k| {
            best(&test_profile(
                &rectified_profile(tested[k].phase, counts[k])?,
                &counts,
            ))
        })
        .max_by(|a, b| a.fit.total_cmp(&b.fit));
    let found = [plain, again]
        .into_iter()
        .flatten()
        .max_by(|a, b| a.fit.total_cmp(&b.fit));
    if let Some(ring) = found {
        return RingEvidence::Manchester(ring);
    }
    // A cast shadow's edge across the ring (see [`evened_light`]): tried
    // for the expected count only.
    if !expected {
        return absent;
    }
    paper_profile(image, &frame, count)
        .and_then(|paper| evened_light(&profile, &paper, counts[0]))
        .and_then(|even| test_profile(&even, &counts[..1]).pop()?.ring)
        .filter(|r| r.fit >= MIN_FIT)
        .map_or(absent, |ring| {
            RingEvidence::Manchester(RingStructure {
                in_shade: true,
                ..ring
            })
        })
}

/// One count tried: the ring read, if it passed the contrast and mid-bit
/// edge tests (its fit still to be judged), and where and how clearly the
/// profile's edges fall on that count's sector boundaries.
struct Tested {
    ring: Option<RingStructure>,
    phase: f64,
    coherence: f64,
}

/// A ring's angular profile and what every count's test reads of it alike.
struct Profile<'a> {
    samples: &'a [f64],
    /// Change between neighbouring samples, and its sum.
    gradient: Vec<f64>,
    gradient_total: f64,
    /// Mean, and sum of squared deviations from it (for [`correlation`]).
    mean: f64,
    spread: f64,
}

impl Profile<'_> {
    fn new(samples: &[f64]) -> Profile<'_> {
        let count = samples.len();
        let gradient: Vec<f64> = gradient(samples).collect();
        let gradient_total = gradient.iter().sum();
        let mean = samples.iter().sum::<f64>() / count as f64;
        let mut spread = 0.0;
        for x in samples {
            let dx = x - mean;
            spread += dx * dx;
        }
        Profile {
            samples,
            gradient,
            gradient_total,
            mean,
            spread,
        }
    }
}

/// The structure test for `bits` bits on a profile of the ring whose
/// sector boundaries for that count are `(phase, coherence)`
/// ([`boundary_phases`]).
fn test_bits(
    profile: &Profile,
    bits: u32,
    (phase, coherence): (f64, f64),
    disc_contrast: f64,
    model: &mut Model,
) -> Tested {
    let sector = PI / f64::from(bits);
    // Which boundaries are the mid-bit ones is clear from a varied code,
    // but a code with long runs of equal bits reads almost as well paired
    // the other way: both pairings are judged.
    let ring = [phase, phase + sector]
        .into_iter()
        .filter_map(|start| pairing(profile, bits, start, disc_contrast, model))
        .max_by(|a, b| a.fit.total_cmp(&b.fit));
    Tested {
        ring,
        phase,
        coherence,
    }
}

/// The structure test for one pairing of half-sectors into bits, the first
/// bit starting at `start`.
fn pairing(
    profile: &Profile,
    bits: u32,
    start: f64,
    disc_contrast: f64,
    model: &mut Model,
) -> Option<RingStructure> {
    let halves = half_sector_means(profile.samples, bits, start);
    let diffs = bit_differences(&halves);
    let (mut bright, mut dark) = (0.0, 0.0);
    for pair in halves.chunks_exact(2) {
        bright += pair[0].max(pair[1]);
        dark += pair[0].min(pair[1]);
    }
    let ring_contrast = (bright - dark) / f64::from(bits);
    if ring_contrast < MIN_CONTRAST * disc_contrast {
        return None;
    }
    let edge = |d: &f64| d.abs() / ring_contrast;
    let weak = diffs.iter().filter(|d| edge(d) < MIN_BIT_EDGE).count() as u32;
    // A smudge or a glint may hide one bit's edge of a long code; a ring
    // of the wrong bit count loses many.
    if weak > bits / 16 {
        return None;
    }
    let weakest_bit = diffs.iter().map(edge).fold(f64::INFINITY, f64::min);
    let mut word = 0u32;
    for (j, d) in diffs.iter().enumerate() {
        if *d > 0.0 {
            word |= 1 << (bits as usize - 1 - j);
        }
    }
    // No family holds a word equal to one of its rotations, but printed
    // sets do (the reference prints every word; tags_35.pdf has five, read
    // as unknown), so long ones are kept. A short code's periodic word is
    // a pattern of two or four lobes, what a letter or a squashed blob
    // shows around its hole.
    if bits < 8 && necklace::is_periodic(word, bits) {
        return None;
    }
    let fit = model.fit(profile, bits, start, word);
    Some(RingStructure {
        bits,
        code: necklace::min_rotation(word, bits).0,
        contrast: ring_contrast / disc_contrast,
        fit,
        weakest_bit,
        in_shade: false,
    })
}

/// Gaussian widths (pixels) the Manchester model is blurred by.
const MODEL_BLURS: [f64; 3] = [0.4, 0.8, 1.4];

/// The blurred Manchester models of one ring's profiles: the kernels,
/// which depend on the sample spacing only, made once per ring, and the
/// buffers every count's model is built in.
struct Model {
    kernels: [Kernel; 3],
    /// Parameter of every sample.
    angles: Vec<f64>,
    square: Vec<f64>,
    padded: Vec<f64>,
    blurred: [Vec<f64>; 3],
}

/// Gaussian taps from the centre out (`reach` + 1 of them), and their
/// sum over both sides.
struct Kernel {
    weights: Vec<f64>,
    norm: f64,
}

impl Model {
    fn new(pixels_per_sample: f64, count: usize) -> Model {
        Model {
            kernels: MODEL_BLURS.map(|sigma_px| Kernel::new(sigma_px / pixels_per_sample, count)),
            angles: (0..count)
                .map(|j| 2.0 * PI * j as f64 / count as f64)
                .collect(),
            square: Vec::with_capacity(count),
            padded: Vec::with_capacity(2 * count),
            blurred: std::array::from_fn(|_| Vec::with_capacity(count)),
        }
    }

    /// Best squared correlation of the profile with the Manchester square
    /// wave of `word` (bit 0 from `start`), blurred by one of
    /// [`MODEL_BLURS`].
    fn fit(&mut self, profile: &Profile, bits: u32, start: f64, word: u32) -> f64 {
        let sector = PI / f64::from(bits);
        let sectors = i64::from(2 * bits);
        self.square.clear();
        self.square.extend(self.angles.iter().map(|&t| {
            // floor_to_int: `floor` is a library call on targets without
            // SSE4.1, and this runs for every sample of every model.
            let k = angle::wrap_index(angle::floor_to_int((t - start) / sector), sectors) as u32;
            let bit = word >> (bits - 1 - k / 2) & 1;
            // A 1 is white then black.
            let white = (bit == 1) == k.is_multiple_of(2);
            f64::from(u8::from(white))
        }));
        for (kernel, blurred) in self.kernels.iter().zip(&mut self.blurred) {
            kernel.blur(&self.square, &mut self.padded, blurred);
        }
        correlations(profile, &self.blurred)
            .into_iter()
            .fold(0.0, |best, r| f64::max(best, r.powi(2)))
    }
}

impl Kernel {
    /// A Gaussian of `sigma` samples for a circular signal of `count`.
    fn new(sigma: f64, count: usize) -> Kernel {
        let reach = ((3.0 * sigma).ceil() as usize).min(count / 2);
        let weights: Vec<f64> = (0..=reach)
            .map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp())
            .collect();
        let norm = weights[0] + 2.0 * weights[1..].iter().sum::<f64>();
        Kernel { weights, norm }
    }

    /// The circular `signal` blurred into `out`.
    fn blur(&self, signal: &[f64], padded: &mut Vec<f64>, out: &mut Vec<f64>) {
        let count = signal.len();
        let reach = self.weights.len() - 1;
        out.clear();
        if reach == 0 {
            out.extend_from_slice(signal);
            return;
        }
        // The signal with `reach` samples wrapped round on either side, so
        // the taps index without a division.
        padded.clear();
        padded.extend_from_slice(&signal[count - reach..]);
        padded.extend_from_slice(signal);
        padded.extend_from_slice(&signal[..reach]);
        // Tap by tap over the whole signal (each sample's sum still taken
        // from the centre out): the inner loop runs over neighbouring
        // samples, which vectorises.
        out.extend(
            padded[reach..reach + count]
                .iter()
                .map(|x| self.weights[0] * x),
        );
        for (k, &w) in self.weights.iter().enumerate().skip(1) {
            let ahead = &padded[reach + k..reach + k + count];
            let behind = &padded[reach - k..reach - k + count];
            for ((sum, a), b) in out.iter_mut().zip(ahead).zip(behind) {
                *sum += w * (a + b);
            }
        }
        for sum in out.iter_mut() {
            *sum /= self.norm;
        }
    }
}

/// Correlation of the profile with each of three models of it, side by
/// side for the same reason as [`boundary_phases`]' lanes.
fn correlations(profile: &Profile, models: &[Vec<f64>; 3]) -> [f64; 3] {
    let [m0, m1, m2] = models;
    let n = m0.len() as f64;
    let mut sums = [0.0; 3];
    for ((a, b), c) in m0.iter().zip(m1).zip(m2) {
        sums[0] += a;
        sums[1] += b;
        sums[2] += c;
    }
    let ma = profile.mean;
    let mb = sums.map(|sum| sum / n);
    let (mut ab, mut bb) = ([0.0; 3], [0.0; 3]);
    for (((x, a), b), c) in profile.samples.iter().zip(m0).zip(m1).zip(m2) {
        let dx = x - ma;
        for (i, y) in [a, b, c].into_iter().enumerate() {
            let dy = y - mb[i];
            ab[i] += dx * dy;
            bb[i] += dy * dy;
        }
    }
    let aa = profile.spread;
    std::array::from_fn(|i| {
        if aa <= 0.0 || bb[i] <= 0.0 {
            0.0
        } else {
            ab[i] / (aa * bb[i]).sqrt()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_images::{draw, INK, PAPER};
    use super::*;
    use crate::geometry::Marker;

    const BLACK: f64 = INK as f64;
    const WHITE: f64 = PAPER as f64;

    #[test]
    fn a_drawn_ring_shows_its_own_count_and_code_among_all() {
        for (bits, code) in [(6, 0b001011), (8, 0b0110_1011), (12, 0b0000_1101_0111)] {
            let marker = Marker::whycode(bits, code, 50.0);
            let (image, outline) = draw(&marker, 60.0, 72, (36.2, 35.9), 0.7);
            let expected = std::iter::once(bits).chain(BITS.filter(|&n| n != bits));
            let RingEvidence::Manchester(ring) =
                examine(&image, &outline, BLACK, WHITE, expected, true)
            else {
                panic!("{bits} bits: no Manchester ring");
            };
            assert_eq!(
                (ring.bits, ring.code),
                (bits, necklace::min_rotation(code, bits).0)
            );
            assert!(ring.fit >= SURE_FIT && !ring.in_shade, "{ring:?}");
            // Tested for twice its count, or without its own, it is no ring.
            let others = BITS.filter(|&n| n != bits);
            match examine(&image, &outline, BLACK, WHITE, others, false) {
                RingEvidence::Manchester(other) => assert!(other.bits != bits, "{other:?}"),
                RingEvidence::Absent | RingEvidence::TooSmall => {}
            }
            assert!(!matches!(
                examine(&image, &outline, BLACK, WHITE, [2 * bits], false),
                RingEvidence::Manchester(_)
            ));
        }
    }

    #[test]
    fn a_washer_shows_no_ring_unless_a_count_tried_was_too_fine_to_test() {
        let (image, outline) = draw(&Marker::whycon(50.0), 32.0, 40, (20.0, 20.0), 0.0);
        assert!(testable(&outline, 8) && !testable(&outline, 24));
        assert_eq!(
            examine(&image, &outline, BLACK, WHITE, [8, 12], false),
            RingEvidence::Absent
        );
        // Sectors of 24 bits would be under MIN_TESTABLE_PIXELS here: no
        // evidence either way for that count.
        assert_eq!(
            examine(&image, &outline, BLACK, WHITE, [8, 24], false),
            RingEvidence::TooSmall
        );
        assert_eq!(
            examine(&image, &outline, BLACK, WHITE, [24], false),
            RingEvidence::TooSmall
        );
    }
}
