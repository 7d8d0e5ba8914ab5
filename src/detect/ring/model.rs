//! Reading rings too small for sector sampling (paper section 5).
//!
//! At 12 px across an 8-bit marker's half-bit sector is about a pixel of
//! ring: the blur of the lens and the pixel's own area mix neighbouring
//! sectors, so no sample reads one sector. Instead every family member at
//! every rotation is rendered as the camera would see it (the fitted outer
//! ellipse, each pixel's footprint blurred by a Gaussian) and compared with
//! the pixels; the member that explains them best is the ID, unless another
//! member explains them almost as well (then unknown). The same comparison
//! against a ring without angular structure (any grey, any radial profile
//! of the marker's discs) tells a tiny marker from a round blob.
//!
//! A ring smeared by motion blur is read the same way: a blur of
//! length L smears sectors into their neighbours, so no sample reads one
//! sector, but the members rendered through a segment of the length and
//! direction the outline's edge spread shows
//! ([`crate::detect::ellipse::linear_blur`]) still tell them apart.
//!
//! Each pixel's model value is linear in the 2n half-sector colours, so the
//! pixel sums that the least-squares comparison needs are formed once per
//! blur and phase; each member rotation then costs a table lookup per bit
//! ([`PatternTables`]).

use std::f64::consts::PI;

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use crate::detect::ellipse::LinearBlur;
use crate::family::{necklace, Family};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::Ellipse as ImageEllipse;

/// Semi-major axis (pixels) up to which a steep view of the marker is
/// still close enough to an affine one for the model to be trusted.
pub const MAX_AFFINE_SEMI_MAJOR: f64 = 15.0;

/// Most member rotations compared per ring (bounds the cost on families of
/// long codes, whose sectors are too narrow at these sizes anyway).
const MAX_MODELS: usize = 4096;

/// Pixels up to this radius (relative to R) are compared: the centre disc,
/// the ring and the inner part of the black annulus, away from whatever
/// lies beyond the marker's white margin.
const COMPARED_RADIUS: f64 = 0.85;

/// Steps of the ring's phase per bit (two sectors).
const PHASE_STEPS: usize = 8;

/// Blur (Gaussian sigma, pixels, on top of the pixel's own area) tried.
const BLURS: [f64; 3] = [0.35, 0.7, 1.05];

/// The best member must leave at most this share of the residual of the
/// best ring without angular structure. Rings of 8-10 px seen at up to 45
/// degrees mostly stay under 0.35; small letters and blobs with an
/// off-centre hole reach 0.41-0.5, since the best of a thousand member
/// rotations fits some of any blob's asymmetry.
const MAX_STRUCTURE_RATIO: f64 = 0.4;

/// The runner-up member's residual must exceed the best one's by this
/// factor for the ID to be named.
const MIN_ID_MARGIN: f64 = 1.6;

/// Lengths tried, relative to the measured blur (the outline's ramp
/// reads about 0.85 of the true length: its ends are rounded by the focus
/// blur and the pixels).
const BLURRED_LENGTHS: [f64; 3] = [1.0, 1.15, 1.3];

/// Pixels compared on a blurred ring (a subset, evenly spread, on large ones).
const COMPARED_PIXELS: f64 = 1200.0;

/// [`MAX_STRUCTURE_RATIO`] and [`MIN_ID_MARGIN`] for blurred rings.
const MAX_BLURRED_STRUCTURE_RATIO: f64 = 0.4;
const MIN_BLURRED_ID_MARGIN: f64 = 1.6;

/// What the pixels of a small ring say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmallRing {
    /// The pixels show a code ring (a member explains them much better than
    /// any ring without angular structure).
    pub structured: bool,
    /// The member named, 0 when two members explain the pixels about as well.
    pub id: u32,
    /// The named member's code.
    pub code: u32,
    /// Image direction of the marker's +x axis, with an ID.
    pub yaw: Option<f64>,
    /// Residual of the runner-up member over the best one's (≥ 1).
    pub margin: f64,
    /// Residual of the best member over the best structureless ring's.
    pub structure_ratio: f64,
    /// Residual of the best member (sum of squared grey differences).
    pub residual: f64,
}

/// Compares the pixels inside `outer` with every member of `family` at
/// every rotation. `None` when the family is too large to compare or the
/// ring leaves the image.
pub fn read_small_ring<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
) -> Option<SmallRing> {
    compare(
        image,
        outer,
        family,
        &small_footprints(),
        1,
        Thresholds::SMALL,
    )
}

/// The pixel footprints a small ring is compared through: one per blur of
/// [`BLURS`].
fn small_footprints() -> Vec<Footprint> {
    BLURS.iter().map(|&blur| gaussian_footprint(blur)).collect()
}

/// [`read_small_ring`], with the member withdrawn (ID 0, no yaw) when a
/// ring of a neighbouring bit count explains the pixels better
/// ([`RingPixels::neighbour_count_fits_better`]).
pub fn read_small_ring_of_its_count<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
) -> Option<SmallRing> {
    RingPixels::read(image, outer, &small_footprints(), 1)?
        .read_of_its_count(family, Thresholds::SMALL)
}

/// [`read_defocused_ring`], with the member withdrawn when a ring of a
/// neighbouring bit count explains the pixels better.
pub fn read_defocused_ring_of_its_count<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
    sigma: f64,
) -> Option<SmallRing> {
    RingPixels::read(
        image,
        outer,
        &defocus_footprints(sigma, outer),
        compared_stride(outer),
    )?
    .read_of_its_count(family, Thresholds::BLURRED)
}

/// Reads a ring smeared by the motion blur `blur` (measured on the outline,
/// see [`crate::detect::ellipse::linear_blur`]): the same comparison with every member
/// rendered through segments of about the measured length. Large rings
/// are compared on a subset of their pixels (the smear, not the pixel,
/// sets the scale of what the model can tell apart).
pub fn read_blurred_ring<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
    blur: &LinearBlur,
) -> Option<SmallRing> {
    let footprints: Vec<Footprint> = BLURRED_LENGTHS
        .iter()
        .map(|&k| line_footprint(k * blur.length, blur.angle))
        .collect();
    compare(
        image,
        outer,
        family,
        &footprints,
        compared_stride(outer),
        Thresholds::BLURRED,
    )
}

/// Defocus tried, relative to the sigma read off the outline's edge: the
/// edge of a small or steep ring is short and noisy, and the ring's own
/// sectors blur a little more than the outline shows where the ring is
/// foreshortened.
const DEFOCUS_SCALES: [f64; 3] = [0.8, 1.0, 1.25];

/// Reads a ring out of focus by the Gaussian blur of `sigma` pixels the
/// outline's edge spread shows ([`crate::detect::ellipse::defocus`]): the
/// same comparison with every member rendered through Gaussians about
/// that wide, on about [`COMPARED_PIXELS`] pixels whatever the ring's size.
pub fn read_defocused_ring<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
    sigma: f64,
) -> Option<SmallRing> {
    compare(
        image,
        outer,
        family,
        &defocus_footprints(sigma, outer),
        compared_stride(outer),
        Thresholds::BLURRED,
    )
}

/// The Gaussians [`read_defocused_ring`] renders through.
fn defocus_footprints(sigma: f64, outer: &ImageEllipse) -> Vec<Footprint> {
    // The black annulus along the minor axis, pixels.
    let annulus = (1.0 - WHYCODE_WHITE_RATIO) * outer.semi_minor;
    let narrow = annulus < NARROW_ANNULUS_SIGMAS * sigma;
    DEFOCUS_SCALES
        .iter()
        .chain(if narrow {
            &NARROW_DEFOCUS_SCALES[..]
        } else {
            &[]
        })
        .map(|&k| Footprint::Gaussian(k * sigma))
        .collect()
}

/// A black annulus narrower than this many sigmas of the blur read (along
/// the outline's minor axis: a small or steep ring) keeps the outline's
/// edge from reaching full contrast under the blur, so the edge reads a
/// blur short of the ring's (the sigmas read: docs/detection.md, "Defocus,
/// small and steep markers").
const NARROW_ANNULUS_SIGMAS: f64 = 3.0;

/// Further defocus tried on a ring of a narrow annulus, relative to the
/// sigma read.
const NARROW_DEFOCUS_SCALES: [f64; 2] = [1.6, 2.0];

/// Most elongation of a small ring's light along its outline's major axis
/// ([`light_elongation`]) for a ring the model vouches for without naming
/// it. The light of real small rings spreads either way, the code's second
/// harmonic turned any way, and stays under it; the hole of a bold
/// stroke-font letter is stretched along the major axis, most letters' to
/// near it or past it, and the 'O' once reported as a marker well past it
/// (the spreads, measured by `examples/small_ring_light`:
/// docs/detection.md, "The 11 px 'O', reproduced"). Rings the model names
/// are left alone: a member explaining them with a clear margin over every
/// other is what no letter earned.
pub const MAX_LIGHT_ELONGATION: f64 = 0.23;

/// How much more the light inside the ring's outer edge (radius 0.6 of
/// the outline) spreads along the outline's major axis than along its
/// minor one, in the outline's own frame: (Σ l·p² − Σ l·q²) / (Σ l·p² +
/// Σ l·q²), l a pixel's lightness between the disc's darkest tenth and
/// the white margin around it. A marker's light, its centre disc and the
/// white half of every bit, is as round as its outline up to the code's
/// second harmonic. A letter's hole is not: a pen of constant width
/// leaves a hole the narrower beside the outline the narrower the outline
/// is, so the hole is stretched along the major axis (an 'O' 10.7 × 8.4 px
/// outside, 2 × 5 px inside). `None` when the ring leaves the image.
pub fn light_elongation<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
) -> Option<f64> {
    let frame = MarkerFrame::of(outer);
    let (a, b) = (outer.semi_major, outer.semi_minor);
    let (width, height) = image.dimensions();
    let reach = a * MARGIN_RADII.1 + 1.0;
    let (x0, x1) = ((outer.u - reach).floor(), (outer.u + reach).ceil());
    let (y0, y1) = ((outer.v - reach).floor(), (outer.v + reach).ceil());
    if !(b > 0.0 && x0 >= 0.0 && y0 >= 0.0 && x1 < f64::from(width) && y1 < f64::from(height)) {
        return None;
    }
    let mut disc: Vec<(f64, f64, f64)> = Vec::new();
    let mut margin: Vec<f64> = Vec::new();
    for y in y0 as u32..=y1 as u32 {
        for x in x0 as u32..=x1 as u32 {
            let (p, q) = frame.marker_point(f64::from(x), f64::from(y));
            let rho = p.hypot(q);
            let grey = f64::from(image.get_pixel(x, y).0[0]);
            if rho <= COMPARED_RADIUS {
                disc.push((p, q, grey));
            } else if (MARGIN_RADII.0..MARGIN_RADII.1).contains(&rho) {
                margin.push(grey);
            }
        }
    }
    if disc.len() < 12 || margin.is_empty() {
        return None;
    }
    let mut greys: Vec<f64> = disc.iter().map(|d| d.2).collect();
    let (_, &mut black, _) = greys.select_nth_unstable_by(disc.len() / 10, f64::total_cmp);
    let middle = margin.len() / 2;
    let (_, &mut white, _) = margin.select_nth_unstable_by(middle, f64::total_cmp);
    let span = (white - black).max(1.0);
    let (mut along, mut across) = (0.0, 0.0);
    for &(p, q, grey) in &disc {
        if p.hypot(q) < WHYCODE_WHITE_RATIO {
            let light = ((grey - black) / span).clamp(0.0, 1.0);
            along += light * p * p;
            across += light * q * q;
        }
    }
    (along + across > 0.0).then(|| (along - across) / (along + across))
}

/// The white margin around a marker's disc, in radii of its outline: its
/// grey is the light that [`light_elongation`] measures against.
const MARGIN_RADII: (f64, f64) = (1.1, 1.3);

/// Pixel stride at which about [`COMPARED_PIXELS`] of the ring's are
/// compared (the blur, not the pixel, sets the scale of what the model can
/// tell apart).
fn compared_stride(outer: &ImageEllipse) -> u32 {
    let disc = PI * (outer.semi_major * COMPARED_RADIUS) * (outer.semi_minor * COMPARED_RADIUS);
    ((disc / COMPARED_PIXELS).sqrt().floor() as u32).max(1)
}

/// How one pixel's model value is formed from the marker's pattern.
enum Footprint {
    /// Averaged over these sub-pixel offsets and weights (summing to 1).
    Points(Vec<(f64, f64, f64)>),
    /// The pixel's area (4x4 samples) seen through a Gaussian of this
    /// sigma, pixels ([`rendered_through_gaussian`]).
    Gaussian(f64),
}

/// A pixel's area seen through a Gaussian blur of `blur` pixels: a 5x5
/// grid of sub-samples, Gaussian-weighted.
fn gaussian_footprint(blur: f64) -> Footprint {
    let sigma = (blur * blur + 1.0 / 12.0).sqrt();
    let offsets: Vec<(f64, f64, f64)> = (-2..=2)
        .flat_map(|i| (-2..=2).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (dx, dy) = (f64::from(i) * 0.8 * sigma, f64::from(j) * 0.8 * sigma);
            (dx, dy, (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp())
        })
        .collect();
    let total: f64 = offsets.iter().map(|o| o.2).sum();
    Footprint::Points(
        offsets
            .into_iter()
            .map(|(x, y, w)| (x, y, w / total))
            .collect(),
    )
}

/// A pixel smeared along a segment of `length` pixels in direction
/// `angle`: samples a pixel apart (the pixel's own width fills between them).
fn line_footprint(length: f64, angle: f64) -> Footprint {
    let taps = (length.ceil() as usize).max(1) + 1;
    let (s, c) = angle.sin_cos();
    Footprint::Points(
        (0..taps)
            .map(|k| {
                let t = (k as f64 / (taps - 1) as f64 - 0.5) * length;
                (t * c, t * s, 1.0 / taps as f64)
            })
            .collect(),
    )
}

/// When a comparison counts as a ring, and as an ID.
#[derive(Debug, Clone, Copy)]
struct Thresholds {
    max_structure_ratio: f64,
    min_id_margin: f64,
}

impl Thresholds {
    const SMALL: Thresholds = Thresholds {
        max_structure_ratio: MAX_STRUCTURE_RATIO,
        min_id_margin: MIN_ID_MARGIN,
    };
    const BLURRED: Thresholds = Thresholds {
        max_structure_ratio: MAX_BLURRED_STRUCTURE_RATIO,
        min_id_margin: MIN_BLURRED_ID_MARGIN,
    };
}

fn compare<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    outer: &ImageEllipse,
    family: &Family,
    footprints: &[Footprint],
    stride: u32,
    thresholds: Thresholds,
) -> Option<SmallRing> {
    RingPixels::read(image, outer, footprints, stride)?.compare(family, thresholds)
}

/// An image point in the marker's frame: p along the outline's major axis,
/// q along the minor one turned so that the parameter runs visually
/// counter-clockwise (as in the ring reader's frame), both in radii.
#[derive(Debug, Clone, Copy)]
struct MarkerFrame {
    u: f64,
    v: f64,
    sin: f64,
    cos: f64,
    a: f64,
    b: f64,
}

impl MarkerFrame {
    fn of(outer: &ImageEllipse) -> MarkerFrame {
        let (sin, cos) = outer.angle.sin_cos();
        MarkerFrame {
            u: outer.u,
            v: outer.v,
            sin,
            cos,
            a: outer.semi_major,
            b: outer.semi_minor,
        }
    }

    #[inline]
    fn marker_point(&self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.u, y - self.v);
        (
            (dx * self.cos + dy * self.sin) / self.a,
            (dx * self.sin - dy * self.cos) / self.b,
        )
    }
}

/// The pixels of one ring that the model is compared with, and what each
/// footprint samples of the marker at them: read once, then compared with
/// the family and with rings of the neighbouring bit counts
/// ([`RingPixels::neighbour_count_fits_better`]), whose sectors differ but whose
/// samples do not.
struct RingPixels {
    frame: MarkerFrame,
    /// (x, y, grey) of each pixel compared.
    pixels: Vec<(f64, f64, f64)>,
    sum_y: f64,
    /// Σ (y − ȳ)².
    syy: f64,
    footprints: Vec<Sampled>,
    /// What every pixel's area covers of the marker, for the Gaussians.
    subsamples: Option<SubSamples>,
}

/// A footprint's samples of the marker at the compared pixels.
enum Sampled {
    /// Per pixel: the weight on white outside the code ring, and the
    /// (angle, weight) of each sample inside the ring.
    Points(Vec<f64>, PerPixel<(f64, f64)>),
    /// The pixel's area seen through a Gaussian of this sigma, pixels.
    Gaussian(f64),
}

impl RingPixels {
    /// `None` when the ring leaves the image or shows too few pixels (or
    /// none but one grey) to compare.
    fn read<C: Deref<Target = [u8]>>(
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &ImageEllipse,
        footprints: &[Footprint],
        stride: u32,
    ) -> Option<RingPixels> {
        let (a, b) = (outer.semi_major, outer.semi_minor);
        if !(a.is_finite() && b > 1.0 && outer.u.is_finite() && outer.v.is_finite()) {
            return None;
        }
        let frame = MarkerFrame::of(outer);
        let (width, height) = image.dimensions();
        let reach = a * COMPARED_RADIUS + 1.0;
        let (x0, x1) = ((outer.u - reach).floor(), (outer.u + reach).ceil());
        let (y0, y1) = ((outer.v - reach).floor(), (outer.v + reach).ceil());
        if x0 < 0.0 || y0 < 0.0 || x1 >= f64::from(width) || y1 >= f64::from(height) {
            return None;
        }
        let mut pixels: Vec<(f64, f64, f64)> = Vec::new();
        for y in (y0 as u32..=y1 as u32).step_by(stride as usize) {
            for x in (x0 as u32..=x1 as u32).step_by(stride as usize) {
                let (p, q) = frame.marker_point(f64::from(x), f64::from(y));
                if radius(p, q) <= COMPARED_RADIUS {
                    pixels.push((
                        f64::from(x),
                        f64::from(y),
                        f64::from(image.get_pixel(x, y).0[0]),
                    ));
                }
            }
        }
        let count = pixels.len() as f64;
        if count < 12.0 {
            return None;
        }
        let sum_y: f64 = pixels.iter().map(|p| p.2).sum();
        let syy = pixels.iter().map(|p| p.2 * p.2).sum::<f64>() - sum_y * sum_y / count;
        if syy <= 0.0 {
            return None;
        }
        // The pixels' coverage of the marker is formed once for every
        // Gaussian tried, out to the widest one's reach.
        let widest = footprints
            .iter()
            .filter_map(|f| match f {
                Footprint::Gaussian(sigma) => Some(gaussian_kernel(*sigma).1),
                Footprint::Points(_) => None,
            })
            .max();
        let subsamples = widest.map(|reach| SubSamples::of(&pixels, reach, &frame));
        let footprints = footprints
            .iter()
            .map(|f| match f {
                Footprint::Gaussian(sigma) => Sampled::Gaussian(*sigma),
                Footprint::Points(offsets) => {
                    let (fixed, ring) = sampled_through(&pixels, offsets, &frame);
                    Sampled::Points(fixed, ring)
                }
            })
            .collect();
        Some(RingPixels {
            frame,
            pixels,
            sum_y,
            syy,
            footprints,
            subsamples,
        })
    }

    /// [`RingPixels::compare`], with the member withdrawn (ID 0, no yaw)
    /// when a ring of a neighbouring count fits better.
    fn read_of_its_count(&self, family: &Family, thresholds: Thresholds) -> Option<SmallRing> {
        let read = self.compare(family, thresholds)?;
        let refuted = read.id != 0 && self.neighbour_count_fits_better(family, &read);
        Some(SmallRing {
            id: if refuted { 0 } else { read.id },
            yaw: read.yaw.filter(|_| !refuted),
            ..read
        })
    }

    /// Whether the pixels look more like a ring of a neighbouring bit count
    /// (up to two more or fewer than the family's: any aperiodic code of
    /// that count) than like `read`, the family's best member. A ring too
    /// small to count its sectors otherwise matches a member of the family
    /// one count off (a 9-bit marker 16 px across read as ID 10 of the
    /// 8-bit family). Counts whose codes are too many to compare refute
    /// nothing.
    fn neighbour_count_fits_better(&self, family: &Family, read: &SmallRing) -> bool {
        let bits = family.bits();
        [
            bits.saturating_sub(2),
            bits.saturating_sub(1),
            bits + 1,
            bits + 2,
        ]
        .into_iter()
        .filter(|n| super::manchester::BITS.contains(n))
        .filter_map(|n| Family::generate(n, 1).ok())
        .filter_map(|every| self.compare_beating(&every, Thresholds::SMALL, Some(read.residual)))
        .any(|other| other.residual < read.residual)
    }

    /// Compares the pixels with every member of `family` at every rotation.
    /// `None` when the family is too large to compare.
    fn compare(&self, family: &Family, thresholds: Thresholds) -> Option<SmallRing> {
        self.compare_beating(family, thresholds, None)
    }

    /// [`RingPixels::compare`]; given `beat`, phases where no rotation can
    /// leave a residual under it are skipped (see [`unconstrained_residual`]).
    fn compare_beating(
        &self,
        family: &Family,
        thresholds: Thresholds,
        beat: Option<f64>,
    ) -> Option<SmallRing> {
        let bits = family.bits();
        let members = family.len();
        if members == 0 || members * bits as usize > MAX_MODELS {
            return None;
        }
        let sectors = 2 * bits as usize;
        let sector = PI / f64::from(bits);
        let (pixels, sum_y, syy) = (&self.pixels, self.sum_y, self.syy);
        let count = pixels.len() as f64;
        let codes: Vec<u32> = (1..=members as u32)
            .filter_map(|id| family.code(id))
            .collect();
        // Every member rotation as the word seen, bit i (least significant
        // first) owning sectors 2i, 2i+1; a 1 is white then black.
        let patterns: Vec<(u32, u32, u64)> = codes
            .iter()
            .enumerate()
            .flat_map(|(k, &code)| {
                (0..bits).map(move |r| {
                    let word = necklace::rotl(code, bits, r);
                    let seen = (0..bits).fold(0u64, |seen, i| {
                        seen | u64::from(word >> (bits - 1 - i) & 1) << i
                    });
                    (k as u32 + 1, r, seen)
                })
            })
            .collect();
        let mut tables = PatternTables::new(bits as usize);
        struct Best {
            sse: f64,
            id: u32,
            rotation: u32,
            phase: f64,
        }
        let mut best: Option<Best> = None;
        // Best residual of every member (any rotation, phase and blur).
        let mut per_member = vec![f64::INFINITY; codes.len() + 1];
        let mut best_null = f64::INFINITY;
        // The Gaussians' coverage of the ring's wedges, binned once for all.
        let coverage = self
            .subsamples
            .as_ref()
            .map(|subsamples| subsamples.binned(sectors));
        for footprint in &self.footprints {
            // Per pixel: white weight outside the ring, and (wedge, weight) of
            // its footprint inside it.
            let (fixed_through, wedge_samples);
            let (fixed, ring_samples) = match footprint {
                Sampled::Gaussian(sigma) => {
                    let coverage = coverage.as_ref()?;
                    (fixed_through, wedge_samples) =
                        rendered_through_gaussian(pixels, *sigma, coverage);
                    (&fixed_through, &wedge_samples)
                }
                Sampled::Points(fixed, angles) => {
                    wedge_samples = in_wedges(angles, sectors);
                    (fixed, &wedge_samples)
                }
            };
            // Structureless ring: y ≈ α + β·fixed + γ·ring coverage.
            let coverage: Vec<f64> = ring_samples
                .runs()
                .map(|run| run.iter().map(|s| s.1).sum())
                .collect();
            best_null = best_null.min(residual_of_two(pixels, fixed, &coverage));
            let sum_fixed: f64 = fixed.iter().sum();
            let ff: f64 = fixed.iter().map(|f| f * f).sum();
            let yf: f64 = pixels.iter().zip(fixed).map(|(p, f)| p.2 * f).sum();
            // A phase a whole sector on reads every pixel's sectors one index
            // down: only the phases within the first sector are summed.
            let within: Vec<PhaseSums> = (0..WEDGES_PER_SECTOR)
                .map(|step| PhaseSums::of(pixels, fixed, ring_samples, sectors, step))
                .collect();
            // Phases where no rotation can leave a residual under `beat`.
            let ruled_out: Vec<bool> = within
                .iter()
                .map(|sums| {
                    beat.is_some_and(|beat| {
                        unconstrained_residual(sums, sum_fixed, ff, yf, count, sum_y, syy)
                            .is_some_and(|free| free > beat * (1.0 + BOUND_MARGIN))
                    })
                })
                .collect();
            for step in 0..PHASE_STEPS {
                // A sector on, the same sectors under other indices: the
                // same bound.
                if ruled_out[step % WEDGES_PER_SECTOR] {
                    continue;
                }
                let phase = 2.0 * sector * step as f64 / PHASE_STEPS as f64;
                let shifted;
                let sums = if step < WEDGES_PER_SECTOR {
                    &within[step]
                } else {
                    shifted = within[step - WEDGES_PER_SECTOR].next_sector();
                    &shifted
                };
                let PhaseSums {
                    gram,
                    w_sum,
                    w_fixed,
                    w_y,
                } = sums;
                tables.fill(gram, w_sum, w_fixed, w_y);
                for &(id, rotation, seen) in &patterns {
                    let (sm, smm, sym) = tables.sums(seen);
                    let (sm, smm, sym) = (sum_fixed + sm, ff + smm, yf + sym);
                    let sym_c = sym - sum_y * sm / count;
                    let smm_c = smm - sm * sm / count;
                    if sym_c <= 0.0 || smm_c <= 0.0 {
                        continue;
                    }
                    // The residual syy − sym_c²/smm_c beats the member's best
                    // so far only if sym_c² exceeds (syy − best)·smm_c: most
                    // rotations are refused without a division.
                    let slot = &mut per_member[id as usize];
                    if sym_c * sym_c <= (syy - *slot) * smm_c {
                        continue;
                    }
                    let sse = syy - sym_c * sym_c / smm_c;
                    *slot = slot.min(sse);
                    if best.as_ref().is_none_or(|b| sse < b.sse) {
                        best = Some(Best {
                            sse,
                            id,
                            rotation,
                            phase,
                        });
                    }
                }
            }
        }
        let best = best?;
        let runner_up = per_member
            .iter()
            .enumerate()
            .filter(|&(id, _)| id as u32 != best.id)
            .map(|(_, &sse)| sse)
            .fold(f64::INFINITY, f64::min);
        let floor = 1e-6 * syy;
        let margin = runner_up.max(floor) / best.sse.max(floor);
        let structure_ratio = best.sse / best_null.max(floor);
        let structured = structure_ratio <= thresholds.max_structure_ratio;
        let named = structured && margin >= thresholds.min_id_margin;
        let code = codes[best.id as usize - 1];
        // Sector 0 of the word seen sits at `phase`; the word is the code
        // rotated left by `rotation`, so the code's own bit 0 (the +x axis)
        // lies `rotation` bits earlier.
        let x_axis_t = best.phase - 2.0 * sector * f64::from(best.rotation);
        let (st, ct) = x_axis_t.sin_cos();
        let MarkerFrame {
            sin: s,
            cos: c,
            a,
            b,
            ..
        } = self.frame;
        let (ax, ay) = (a * ct * c + b * st * s, a * ct * s - b * st * c);
        Some(SmallRing {
            structured,
            id: if named { best.id } else { 0 },
            code,
            yaw: named.then(|| ay.atan2(ax)),
            margin,
            structure_ratio,
            residual: best.sse,
        })
    }
}

/// The sums a member rotation's least-squares fit needs at one phase,
/// read from tables instead of summed sector by sector. A rotation is the
/// word seen, bit i white in sector 2i when set, else in 2i + 1. Its sums
/// over the sectors it whitens are linear per bit, except the model's
/// squared norm, a sum over pairs of bits of the Gram matrix. A pixel's
/// footprint covers a few neighbouring sectors, so bits further apart than
/// the Gram matrix's band never pair; the pairs of bit b with the next
/// `reach` bits are one entry of a table indexed by those reach + 1 bits.
/// A rotation then costs a lookup per bit, not one per pair of bits (the
/// neighbouring bit counts' thousand rotations made the pairs most of a
/// small ring's cost).
struct PatternTables {
    bits: usize,
    reach: usize,
    /// Per bit, 2^(reach + 1) entries: its pairs with the next `reach`
    /// bits (and its own square and linear norm term).
    pairs: Vec<f64>,
    /// Per group of [`LINEAR_GROUP`] bits, per value of the group: the sum
    /// of the whitened sectors' weights and of their weighted greys.
    linear: Vec<[f64; 2]>,
}

/// Bits per entry of [`PatternTables::linear`].
const LINEAR_GROUP: usize = 4;

impl PatternTables {
    fn new(bits: usize) -> PatternTables {
        PatternTables {
            bits,
            reach: 0,
            pairs: Vec::new(),
            linear: vec![[0.0; 2]; bits.div_ceil(LINEAR_GROUP) << LINEAR_GROUP],
        }
    }

    /// Tables of the sums over pixels of the sector weights `w_sum`, their
    /// products with the white outside the ring `w_fixed` and with the
    /// grey `w_y`, and of products of sector weights `gram` (2n × 2n).
    fn fill(&mut self, gram: &[f64], w_sum: &[f64], w_fixed: &[f64], w_y: &[f64]) {
        let n = self.bits;
        let sectors = 2 * n;
        let sector = |bit: usize, set: usize| 2 * (bit % n) + 1 - set;
        // Widest cyclic distance between two sectors one pixel covers; bits
        // b and b + d own sectors at least 2d - 1 apart.
        let mut band = 0;
        for i in 0..sectors {
            for j in i + 1..sectors {
                if gram[i * sectors + j] != 0.0 {
                    band = band.max((j - i).min(sectors - (j - i)));
                }
            }
        }
        self.reach = (band.div_ceil(2)).min(n / 2);
        let size = 1usize << (self.reach + 1);
        self.pairs.clear();
        self.pairs.resize(n * size, 0.0);
        // Each unordered pair once: twice its entry, except the pair of
        // opposite bits of an even count, which both of its bits reach.
        let factor = |d: usize| if 2 * d == n { 1.0 } else { 2.0 };
        for b in 0..n {
            let table = &mut self.pairs[b * size..(b + 1) * size];
            for own in 0..2 {
                let s = sector(b, own);
                let row = &gram[s * sectors..(s + 1) * sectors];
                // Every further bit clear, then each one set in turn.
                let mut clear = row[s] + 2.0 * w_fixed[s];
                let mut step = [0.0; 32];
                for d in 1..=self.reach {
                    let f = factor(d);
                    clear += f * row[sector(b + d, 0)];
                    step[d] = f * (row[sector(b + d, 1)] - row[sector(b + d, 0)]);
                }
                table[own] = clear;
                for further in 1..size >> 1 {
                    let lowest = further & further.wrapping_neg();
                    let d = lowest.trailing_zeros() as usize + 1;
                    table[own | further << 1] = table[own | (further ^ lowest) << 1] + step[d];
                }
            }
        }
        for (group, table) in self.linear.chunks_mut(1 << LINEAR_GROUP).enumerate() {
            let first = group * LINEAR_GROUP;
            for (value, entry) in table.iter_mut().enumerate() {
                *entry = [0.0; 2];
                for bit in first..(first + LINEAR_GROUP).min(n) {
                    let s = sector(bit, value >> (bit - first) & 1);
                    entry[0] += w_sum[s];
                    entry[1] += w_y[s];
                }
            }
        }
    }

    /// The ring's part of the rotation `seen`'s sums over the pixels: of
    /// its model, of its model squared, and of its model times the grey
    /// (the white outside the ring adds its own terms to each).
    fn sums(&self, seen: u64) -> (f64, f64, f64) {
        let n = self.bits;
        let size = 1usize << (self.reach + 1);
        let mask = (size - 1) as u64;
        let twice = seen | seen << n;
        let mut norm = 0.0;
        for (b, table) in self.pairs.chunks_exact(size).enumerate() {
            norm += table[(twice >> b & mask) as usize];
        }
        let (mut sum, mut grey) = (0.0, 0.0);
        for (group, table) in self.linear.chunks_exact(1 << LINEAR_GROUP).enumerate() {
            let entry =
                table[(seen >> (group * LINEAR_GROUP)) as usize & ((1 << LINEAR_GROUP) - 1)];
            sum += entry[0];
            grey += entry[1];
        }
        (sum, norm, grey)
    }
}

/// Per pixel of `pixels`: the weight of its footprint `offsets` on white
/// outside the code ring, and the (angle, weight) of the footprint's
/// samples inside the ring.
fn sampled_through(
    pixels: &[(f64, f64, f64)],
    offsets: &[(f64, f64, f64)],
    frame: &MarkerFrame,
) -> (Vec<f64>, PerPixel<(f64, f64)>) {
    let mut fixed = Vec::with_capacity(pixels.len());
    let mut ring_samples = PerPixel::with_capacity(pixels.len(), pixels.len() * offsets.len());
    for &(x, y, _) in pixels {
        let mut white = 0.0;
        for &(dx, dy, w) in offsets {
            let (p, q) = frame.marker_point(x + dx, y + dy);
            let rho = radius(p, q);
            if !(RING_INNER_RATIO..1.0).contains(&rho) {
                white += w;
            } else if rho < WHYCODE_WHITE_RATIO {
                ring_samples.push((q.atan2(p).rem_euclid(2.0 * PI), w));
            }
        }
        fixed.push(white);
        ring_samples.end_pixel();
    }
    (fixed, ring_samples)
}

/// Entries per compared pixel, every pixel's run in one buffer: a ring's
/// pixels are sampled for every blur and bit count compared, and one
/// allocation a pixel cost more than the sampling.
struct PerPixel<T> {
    /// Where each pixel's run ends in `entries`.
    ends: Vec<usize>,
    entries: Vec<T>,
}

impl<T> PerPixel<T> {
    fn with_capacity(pixels: usize, entries: usize) -> PerPixel<T> {
        PerPixel {
            ends: Vec::with_capacity(pixels),
            entries: Vec::with_capacity(entries),
        }
    }

    /// Adds an entry to the current pixel's run.
    fn push(&mut self, entry: T) {
        self.entries.push(entry);
    }

    /// Closes the current pixel's run; the next entry is the next pixel's.
    fn end_pixel(&mut self) {
        self.ends.push(self.entries.len());
    }

    /// The entries of the current pixel's run so far.
    fn current_mut(&mut self) -> &mut [T] {
        let start = self.ends.last().copied().unwrap_or(0);
        &mut self.entries[start..]
    }

    /// Every pixel's run, in the pixels' order.
    fn runs(&self) -> impl Iterator<Item = &[T]> {
        self.ends.iter().scan(0, |start, &end| {
            let run = &self.entries[*start..end];
            *start = end;
            Some(run)
        })
    }
}

/// The wedge of `wedges` (equal, the first from angle 0) holding the
/// angle `t` in [0, 2π).
fn wedge_of(t: f64, wedges: usize) -> usize {
    let wedge_angle = 2.0 * PI / wedges as f64;
    ((t / wedge_angle) as usize).min(wedges - 1)
}

/// Samples at angles binned into the wedges of a ring of `sectors`
/// ([`WEDGES_PER_SECTOR`] a sector), one entry a wedge.
fn in_wedges(samples: &PerPixel<(f64, f64)>, sectors: usize) -> PerPixel<(usize, f64)> {
    let wedges = sectors * WEDGES_PER_SECTOR;
    let mut binned = PerPixel::with_capacity(samples.ends.len(), samples.entries.len());
    for inside in samples.runs() {
        for &(t, w) in inside {
            let wedge = wedge_of(t, wedges);
            // Neighbouring samples mostly share a wedge.
            match binned.current_mut().iter_mut().find(|(j, _)| *j == wedge) {
                Some((_, sum)) => *sum += w,
                None => binned.push((wedge, w)),
            }
        }
        binned.end_pixel();
    }
    binned
}

/// Relative margin by which [`unconstrained_residual`] must exceed a
/// residual to rule a phase out (the solve's rounding stays far below).
const BOUND_MARGIN: f64 = 0.01;

/// The least residual of any model whose sectors each take their own
/// grey at this phase (with its own weight for the white outside the ring
/// and an offset): a lower bound on every member rotation's residual,
/// each being such a model with sector greys 0 or 1. `None` when the
/// sums leave that fit undetermined.
fn unconstrained_residual(
    sums: &PhaseSums,
    sum_fixed: f64,
    ff: f64,
    yf: f64,
    count: f64,
    sum_y: f64,
    syy: f64,
) -> Option<f64> {
    let sectors = sums.w_sum.len();
    // Columns: the white outside the ring, then every sector that any
    // pixel sees (the others are all zero), centred.
    let columns: Vec<Option<usize>> = std::iter::once(None)
        .chain(
            (0..sectors)
                .filter(|&i| sums.gram[i * sectors + i] > 0.0)
                .map(Some),
        )
        .collect();
    let total = |c: Option<usize>| c.map_or(sum_fixed, |i| sums.w_sum[i]);
    let product = |a: Option<usize>, b: Option<usize>| match (a, b) {
        (None, None) => ff,
        (None, Some(i)) | (Some(i), None) => sums.w_fixed[i],
        (Some(i), Some(j)) => sums.gram[i * sectors + j],
    };
    let with_grey = |c: Option<usize>| c.map_or(yf, |i| sums.w_y[i]);
    let k = columns.len();
    let normal = nalgebra::DMatrix::from_fn(k, k, |r, c| {
        product(columns[r], columns[c]) - total(columns[r]) * total(columns[c]) / count
    });
    let right = nalgebra::DVector::from_fn(k, |r, _| {
        with_grey(columns[r]) - total(columns[r]) * sum_y / count
    });
    let solved = normal.cholesky()?.solve(&right);
    Some(syy - right.dot(&solved))
}

/// The sums over pixels a phase's comparison needs, sector by sector: of
/// each sector's weight in a pixel's model, of that weight times the
/// pixel's white outside the ring and times its grey, and of products of
/// two sectors' weights (the Gram matrix, `sectors` × `sectors`).
struct PhaseSums {
    gram: Vec<f64>,
    w_sum: Vec<f64>,
    w_fixed: Vec<f64>,
    w_y: Vec<f64>,
}

impl PhaseSums {
    /// At the phase `step` wedges on: wedge j lies in sector
    /// (j − step) / [`WEDGES_PER_SECTOR`], cyclically.
    fn of(
        pixels: &[(f64, f64, f64)],
        fixed: &[f64],
        ring_samples: &PerPixel<(usize, f64)>,
        sectors: usize,
        step: usize,
    ) -> PhaseSums {
        let wedges = sectors * WEDGES_PER_SECTOR;
        let sector_of: Vec<usize> = (0..wedges)
            .map(|j| (j + wedges - step) % wedges / WEDGES_PER_SECTOR)
            .collect();
        let mut sums = PhaseSums {
            gram: vec![0.0; sectors * sectors],
            w_sum: vec![0.0; sectors],
            w_fixed: vec![0.0; sectors],
            w_y: vec![0.0; sectors],
        };
        // The sectors a pixel's footprint covers, a few, with their weights.
        let mut touched: Vec<(usize, f64)> = Vec::with_capacity(sectors);
        for ((samples, &(_, _, y)), &white) in ring_samples.runs().zip(pixels).zip(fixed) {
            for &(wedge, w) in samples {
                let index = sector_of[wedge];
                // Wedges mostly come in order, a sector's together.
                match touched.last_mut() {
                    Some((last, sum)) if *last == index => *sum += w,
                    _ => match touched.iter_mut().find(|(i, _)| *i == index) {
                        Some((_, sum)) => *sum += w,
                        None => touched.push((index, w)),
                    },
                }
            }
            for &(i, wi) in &touched {
                sums.w_sum[i] += wi;
                sums.w_fixed[i] += wi * white;
                sums.w_y[i] += wi * y;
                let row = &mut sums.gram[i * sectors..(i + 1) * sectors];
                for &(j, wj) in &touched {
                    row[j] += wi * wj;
                }
            }
            touched.clear();
        }
        sums
    }

    /// The sums a whole sector further on: every sector index one down.
    fn next_sector(&self) -> PhaseSums {
        let sectors = self.w_sum.len();
        let up = |i: usize| (i + 1) % sectors;
        PhaseSums {
            gram: (0..sectors * sectors)
                .map(|k| self.gram[up(k / sectors) * sectors + up(k % sectors)])
                .collect(),
            w_sum: (0..sectors).map(|i| self.w_sum[up(i)]).collect(),
            w_fixed: (0..sectors).map(|i| self.w_fixed[up(i)]).collect(),
            w_y: (0..sectors).map(|i| self.w_y[up(i)]).collect(),
        }
    }
}

/// Wedges a half-sector is cut into: the phase steps within it, so every
/// phase the comparison tries is a whole number of wedges.
const WEDGES_PER_SECTOR: usize = PHASE_STEPS / 2;

/// Weights under the blur below this are left out.
const NEGLIGIBLE_WEIGHT: f64 = 1e-5;

/// What each pixel's area covers of the marker, for [`rendered_through_gaussian`]:
/// white (the centre disc and the paper), and each of the ring's thin
/// wedges (4x4 samples a pixel, as a camera's pixel integrates).
struct Coverage<'a> {
    white: &'a Patch,
    /// Per wedge: the pixels it covers and by how much.
    wedges: Vec<Vec<(i64, i64, f64)>>,
}

/// The 4x4 samples of every pixel's area around a ring, for [`Coverage`]:
/// which fall on white, and the angle of each that falls in the code ring
/// (binned into wedges once per bit count).
struct SubSamples {
    white: Patch,
    /// (x, y, angle) of each sample in the ring, a pixel's together.
    ring: Vec<(i64, i64, f64)>,
}

/// The smallest box (x0, y0, x1, y1, inclusive) holding the pixels.
fn pixel_box(pixels: &[(f64, f64, f64)]) -> (i64, i64, i64, i64) {
    pixels.iter().fold(
        (i64::MAX, i64::MAX, i64::MIN, i64::MIN),
        |(x0, y0, x1, y1), &(x, y, _)| {
            let (x, y) = (x as i64, y as i64);
            (x0.min(x), y0.min(y), x1.max(x), y1.max(y))
        },
    )
}

/// Samples a side of a pixel's area in [`SubSamples`].
const SUBSAMPLES_SIDE: usize = 4;

impl SubSamples {
    /// Over the box of `pixels` grown by `reach`.
    fn of(pixels: &[(f64, f64, f64)], reach: i64, frame: &MarkerFrame) -> SubSamples {
        let (x0, y0, x1, y1) = pixel_box(pixels);
        let (gx, gy) = (x0 - reach, y0 - reach);
        let (gw, gh) = (x1 - x0 + 1 + 2 * reach, y1 - y0 + 1 + 2 * reach);
        let mut white = Patch::zeros(gx, gy, gw, gh);
        let mut ring = Vec::new();
        let share = 1.0 / (SUBSAMPLES_SIDE * SUBSAMPLES_SIDE) as f64;
        for py in gy..gy + gh {
            for px in gx..gx + gw {
                let mut light = 0u32;
                for k in 0..SUBSAMPLES_SIDE * SUBSAMPLES_SIDE {
                    let du = ((k % SUBSAMPLES_SIDE) as f64 + 0.5) / SUBSAMPLES_SIDE as f64 - 0.5;
                    let dv = ((k / SUBSAMPLES_SIDE) as f64 + 0.5) / SUBSAMPLES_SIDE as f64 - 0.5;
                    let (p, q) = frame.marker_point(px as f64 + du, py as f64 + dv);
                    let rho = radius(p, q);
                    if !(RING_INNER_RATIO..1.0).contains(&rho) {
                        light += 1;
                    } else if rho < WHYCODE_WHITE_RATIO {
                        ring.push((px, py, q.atan2(p).rem_euclid(2.0 * PI)));
                    }
                }
                if light > 0 {
                    white.set(px, py, f64::from(light) * share);
                }
            }
        }
        SubSamples { white, ring }
    }

    /// The coverage of the wedges of a ring of `sectors`.
    fn binned(&self, sectors: usize) -> Coverage<'_> {
        let count = sectors * WEDGES_PER_SECTOR;
        let share = 1.0 / (SUBSAMPLES_SIDE * SUBSAMPLES_SIDE) as f64;
        let mut wedges: Vec<Vec<(i64, i64, f64)>> = vec![Vec::new(); count];
        for &(px, py, t) in &self.ring {
            let cells = &mut wedges[wedge_of(t, count)];
            // A pixel's samples come together: its cell is the last one.
            match cells.last_mut() {
                Some((x, y, w)) if (*x, *y) == (px, py) => *w += share,
                _ => cells.push((px, py, share)),
            }
        }
        Coverage {
            white: &self.white,
            wedges,
        }
    }
}

/// The sampled Gaussian of `sigma` pixels out to three sigma, normalised,
/// and its reach.
fn gaussian_kernel(sigma: f64) -> (Vec<f64>, i64) {
    let reach = (3.0 * sigma).ceil().max(1.0) as i64;
    let kernel: Vec<f64> = (-reach..=reach)
        .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f64 = kernel.iter().sum();
    (kernel.into_iter().map(|w| w / total).collect(), reach)
}

/// [`sampled_through`] for a Gaussian focus blur of `sigma` pixels,
/// formed as a camera forms it: the `coverage` of each pixel's area (by
/// white, black and each of the ring's thin wedges) blurred by the sampled
/// Gaussian. A footprint of a few points samples sharp sector edges too
/// coarsely under a blur of a pixel or two (a step of a fifth of the
/// contrast as an edge crosses a point: residuals several times the
/// noise's on a ring out of focus); this does not. Each wedge's weight
/// carries the wedge's middle angle, so the phases the comparison tries
/// (whole wedges) split the wedges exactly at the sector edges.
fn rendered_through_gaussian(
    pixels: &[(f64, f64, f64)],
    sigma: f64,
    coverage: &Coverage,
) -> (Vec<f64>, PerPixel<(usize, f64)>) {
    let (kernel, reach) = gaussian_kernel(sigma);
    let white = coverage.white.blurred(&kernel, reach);
    let fixed: Vec<f64> = pixels
        .iter()
        .map(|&(x, y, _)| white.get(x as i64, y as i64))
        .collect();
    // Each wedge's blurred coverage is handed to the compared pixels it
    // reaches (a pixel's wedges in order), through the pixels' index on
    // the grid of their box.
    let index = PixelIndex::of(pixels);
    let blurred: Vec<(usize, Patch)> = coverage
        .wedges
        .iter()
        .enumerate()
        .filter_map(|(j, cells)| {
            let (a, b, c, d) = cells.iter().fold(None, |span, &(x, y, _)| {
                let (a, b, c, d) = span.unwrap_or((x, y, x, y));
                Some((a.min(x), b.min(y), c.max(x), d.max(y)))
            })?;
            let mut patch = Patch::zeros(a, b, c - a + 1, d - b + 1);
            for &(x, y, w) in cells {
                patch.set(x, y, w);
            }
            Some((j, patch.blurred(&kernel, reach)))
        })
        .collect();
    // Two passes: how many wedges reach each pixel, then the wedges in
    // order into each pixel's run.
    let mut ends = vec![0usize; pixels.len()];
    for (_, patch) in &blurred {
        index.for_each_within(patch, |k, w| {
            if w > NEGLIGIBLE_WEIGHT {
                ends[k] += 1;
            }
        });
    }
    let mut total = 0;
    for end in &mut ends {
        total += *end;
        *end = total;
    }
    let mut next: Vec<usize> = std::iter::once(0)
        .chain(ends.iter().copied())
        .take(pixels.len())
        .collect();
    let mut entries = vec![(0usize, 0.0f64); total];
    for (j, patch) in &blurred {
        index.for_each_within(patch, |k, w| {
            if w > NEGLIGIBLE_WEIGHT {
                entries[next[k]] = (*j, w);
                next[k] += 1;
            }
        });
    }
    (fixed, PerPixel { ends, entries })
}

/// Where each compared pixel lies on the grid of the pixels' box.
struct PixelIndex {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    /// Per grid cell, the pixel there ([`usize::MAX`] for none).
    cells: Vec<usize>,
}

impl PixelIndex {
    fn of(pixels: &[(f64, f64, f64)]) -> PixelIndex {
        let (x0, y0, x1, y1) = pixel_box(pixels);
        let (width, height) = ((x1 - x0 + 1).max(0), (y1 - y0 + 1).max(0));
        let mut cells = vec![usize::MAX; (width * height) as usize];
        for (k, &(x, y, _)) in pixels.iter().enumerate() {
            cells[((y as i64 - y0) * width + (x as i64 - x0)) as usize] = k;
        }
        PixelIndex {
            x0,
            y0,
            width,
            height,
            cells,
        }
    }

    /// Calls `visit` with (pixel, value) of every compared pixel inside
    /// `patch`.
    fn for_each_within(&self, patch: &Patch, mut visit: impl FnMut(usize, f64)) {
        let (xa, xb) = (
            patch.x0.max(self.x0),
            (patch.x0 + patch.width).min(self.x0 + self.width),
        );
        let (ya, yb) = (
            patch.y0.max(self.y0),
            (patch.y0 + patch.height).min(self.y0 + self.height),
        );
        if xa >= xb {
            return;
        }
        for y in ya..yb {
            let cells = &self.cells[((y - self.y0) * self.width + (xa - self.x0)) as usize..]
                [..(xb - xa) as usize];
            let values = &patch.values[((y - patch.y0) * patch.width + (xa - patch.x0)) as usize..]
                [..(xb - xa) as usize];
            for (&k, &value) in cells.iter().zip(values) {
                if k != usize::MAX {
                    visit(k, value);
                }
            }
        }
    }
}

/// A dense box of values on the pixel grid, zero outside.
#[derive(Clone)]
struct Patch {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    values: Vec<f64>,
}

impl Patch {
    fn zeros(x0: i64, y0: i64, width: i64, height: i64) -> Patch {
        Patch {
            x0,
            y0,
            width,
            height,
            values: vec![0.0; (width.max(0) * height.max(0)) as usize],
        }
    }

    fn index(&self, x: i64, y: i64) -> Option<usize> {
        let (i, j) = (x - self.x0, y - self.y0);
        ((0..self.width).contains(&i) && (0..self.height).contains(&j))
            .then(|| (j * self.width + i) as usize)
    }

    fn get(&self, x: i64, y: i64) -> f64 {
        self.index(x, y).map_or(0.0, |k| self.values[k])
    }

    fn set(&mut self, x: i64, y: i64, value: f64) {
        if let Some(k) = self.index(x, y) {
            self.values[k] = value;
        }
    }

    /// Blurred by the separable `kernel` (2 `reach` + 1 taps), grown by
    /// `reach` on every side so nothing is cut.
    fn blurred(&self, kernel: &[f64], reach: i64) -> Patch {
        let mut rows = Patch::zeros(
            self.x0 - reach,
            self.y0,
            self.width + 2 * reach,
            self.height,
        );
        for y in 0..self.height {
            for x in 0..self.width {
                let v = self.values[(y * self.width + x) as usize];
                if v == 0.0 {
                    continue;
                }
                let base = (y * rows.width + x) as usize;
                for (k, w) in kernel.iter().enumerate() {
                    rows.values[base + k] += w * v;
                }
            }
        }
        let mut out = Patch::zeros(
            rows.x0,
            self.y0 - reach,
            rows.width,
            self.height + 2 * reach,
        );
        for y in 0..rows.height {
            for x in 0..rows.width {
                let v = rows.values[(y * rows.width + x) as usize];
                if v == 0.0 {
                    continue;
                }
                for (k, w) in kernel.iter().enumerate() {
                    out.values[((y + k as i64) * out.width + x) as usize] += w * v;
                }
            }
        }
        out
    }
}

/// The radii the model's pixels are sorted by.
const RADIUS_BOUNDS: [f64; 4] = [RING_INNER_RATIO, WHYCODE_WHITE_RATIO, COMPARED_RADIUS, 1.0];

/// hypot(p, q) as far as the comparisons with [`RADIUS_BOUNDS`] can tell:
/// the plain square root is a few times cheaper than `hypot` (a library
/// call), and differs from it by an ulp or so, which matters only within
/// a hair of a bound, where `hypot` decides as before. The model is
/// compared at 75 sub-samples per pixel, on every small round candidate
/// of a cluttered frame.
#[inline]
fn radius(p: f64, q: f64) -> f64 {
    let r = (p * p + q * q).sqrt();
    if RADIUS_BOUNDS.iter().any(|&b| (r - b).abs() <= 1e-9) {
        p.hypot(q)
    } else {
        r
    }
}

/// Least-squares residual of y ≈ α + β·u + γ·v over the pixels.
fn residual_of_two(pixels: &[(f64, f64, f64)], u: &[f64], v: &[f64]) -> f64 {
    let n = pixels.len() as f64;
    let mean = |f: &dyn Fn(usize) -> f64| (0..pixels.len()).map(f).sum::<f64>() / n;
    let (my, mu, mv) = (mean(&|k| pixels[k].2), mean(&|k| u[k]), mean(&|k| v[k]));
    let (mut suu, mut svv, mut suv, mut syu, mut syv, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..pixels.len() {
        let (y, a, b) = (pixels[k].2 - my, u[k] - mu, v[k] - mv);
        suu += a * a;
        svv += b * b;
        suv += a * b;
        syu += y * a;
        syv += y * b;
        syy += y * y;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-12 {
        // Degenerate: fit the better single regressor.
        let one = |sxx: f64, syx: f64| if sxx > 0.0 { syx * syx / sxx } else { 0.0 };
        return syy - one(suu, syu).max(one(svv, syv));
    }
    let beta = (syu * svv - syv * suv) / det;
    let gamma = (syv * suu - syu * suv) / det;
    syy - beta * syu - gamma * syv
}

#[cfg(test)]
mod tests {
    use super::super::test_images::{angle_between, draw};
    use super::*;
    use crate::geometry::Marker;

    #[test]
    fn a_ring_too_small_to_sample_is_named_by_the_members_rendered() {
        let family = Family::generate(8, 2).unwrap();
        for (id, turn) in [(2, 0.3), (7, 2.0)] {
            let code = family.code(id).unwrap();
            let (image, outline) = draw(
                &Marker::whycode(8, code, 50.0),
                14.0,
                24,
                (12.3, 11.8),
                turn,
            );
            let ring = read_small_ring(&image, &outline, &family).unwrap();
            assert!(ring.structured, "{ring:?}");
            assert_eq!((ring.id, ring.code), (id, code), "{ring:?}");
            let yaw = ring.yaw.unwrap();
            assert!(
                angle_between(yaw, -turn) < 10f64.to_radians(),
                "{yaw} {turn}"
            );
        }
    }

    /// `image` through the simulator's focus blur of `sigma` pixels.
    fn defocused(image: &image::GrayImage, sigma: f64) -> image::GrayImage {
        let (w, h) = image.dimensions();
        let grey: Vec<f32> = image.pixels().map(|p| f32::from(p.0[0])).collect();
        let blurred = crate::simulate::effects::gaussian_blur(&grey, w as usize, h as usize, sigma);
        image::GrayImage::from_fn(w, h, |x, y| {
            Luma([blurred[(y * w + x) as usize].round().clamp(0.0, 255.0) as u8])
        })
    }

    #[test]
    fn a_ring_out_of_focus_is_explained_to_the_grey_level_by_its_member() {
        // 20 px across under a blur of 2 px: a half-sector's 2.6 px of
        // ring keep a tenth of their contrast. The member rendered as the
        // camera forms it (pixel areas, then the Gaussian) explains the
        // pixels to within the rounding to grey levels; the same member
        // through a few footprint points left a residual as large as the
        // code's own signal, and named none (docs/detection.md, "The
        // members rendered as the camera forms them").
        let family = Family::generate(8, 2).unwrap();
        for (id, turn) in [(3, 0.4), (11, 2.2)] {
            let code = family.code(id).unwrap();
            let (sharp, outline) = draw(
                &Marker::whycode(8, code, 50.0),
                20.0,
                40,
                (20.3, 19.6),
                turn,
            );
            let image = defocused(&sharp, 2.0);
            let ring = read_defocused_ring(&image, &outline, &family, 2.0).unwrap();
            assert!(ring.structured, "{ring:?}");
            assert_eq!((ring.id, ring.code), (id, code), "{ring:?}");
            let compared = PI * (COMPARED_RADIUS * 10.0).powi(2);
            assert!(ring.residual / compared < 2.0, "{ring:?}");
            assert!(ring.margin > 10.0, "{ring:?}");
        }
    }

    #[test]
    fn a_markers_light_is_round_and_a_pen_drawn_hole_is_not() {
        let family = Family::generate(8, 2).unwrap();
        for id in 1..=family.len() as u32 {
            for turn in [0.0, 0.7, 1.9] {
                let marker = Marker::whycode(8, family.code(id).unwrap(), 50.0);
                let (image, outline) = draw(&marker, 10.0, 24, (12.3, 11.6), turn);
                let e = light_elongation(&image, &outline).unwrap();
                assert!(e.abs() <= MAX_LIGHT_ELONGATION, "ID {id}, turn {turn}: {e}");
            }
        }
        // An 'O' drawn with a pen 3 px wide, 10.7 x 8.4 px outside (the
        // stroke-font 'O' of docs/detection.md: a hole 2 x 5 px).
        let outline = ImageEllipse {
            u: 12.2,
            v: 11.7,
            semi_major: 5.35,
            semi_minor: 4.2,
            angle: 0.0,
        };
        let inside = |x: f64, y: f64, a: f64, b: f64| {
            let (dx, dy) = (x - outline.u, y - outline.v);
            (dx / a).powi(2) + (dy / b).powi(2) <= 1.0
        };
        let letter = image::GrayImage::from_fn(24, 24, |x, y| {
            let ink = (0..16)
                .filter(|k| {
                    let (sx, sy) = (
                        f64::from(x) + (f64::from(k % 4) - 1.5) / 4.0,
                        f64::from(y) + (f64::from(k / 4) - 1.5) / 4.0,
                    );
                    inside(sx, sy, 5.35, 4.2) && !inside(sx, sy, 2.35, 1.2)
                })
                .count();
            Luma([(200 - 10 * ink) as u8])
        });
        let e = light_elongation(&letter, &outline).unwrap();
        assert!(e > MAX_LIGHT_ELONGATION, "{e}");
    }

    #[test]
    fn a_disc_without_a_code_ring_is_no_small_ring() {
        let family = Family::generate(8, 2).unwrap();
        let (image, outline) = draw(&Marker::whycon(50.0), 14.0, 24, (12.0, 12.0), 0.0);
        let ring = read_small_ring(&image, &outline, &family).unwrap();
        assert!(
            !ring.structured && ring.structure_ratio > MAX_STRUCTURE_RATIO,
            "{ring:?}"
        );
        // The comparison needs the whole disc inside the image.
        let cut = ImageEllipse { u: 3.0, ..outline };
        assert_eq!(read_small_ring(&image, &cut, &family), None);
    }

    /// The tables give every word the sums a sector-by-sector pass over
    /// its bits and pairs of bits gives, whatever the count and however
    /// many sectors a pixel's footprint spans (narrow bands read few
    /// pairs; a band past half the ring reads them all, opposite bits of
    /// an even count once).
    #[test]
    fn pattern_tables_sum_as_the_sectors_do() {
        let mut rng = crate::math::Pcg32::new(25, 3);
        for case in 0..400 {
            let n = 2 + case % 13;
            let sectors = 2 * n;
            let span = 1 + rng.next_u32() as usize % sectors;
            let mut gram = vec![0.0; sectors * sectors];
            let mut w_sum = vec![0.0; sectors];
            let mut w_fixed = vec![0.0; sectors];
            let mut w_y = vec![0.0; sectors];
            for _ in 0..20 {
                let first = rng.next_u32() as usize % sectors;
                let width = 1 + rng.next_u32() as usize % span;
                let touched: Vec<(usize, f64)> = (0..width)
                    .map(|k| ((first + k) % sectors, rng.range(0.01, 1.0)))
                    .collect();
                let (white, grey) = (rng.next_f64(), rng.range(0.0, 255.0));
                for &(i, wi) in &touched {
                    w_sum[i] += wi;
                    w_fixed[i] += wi * white;
                    w_y[i] += wi * grey;
                    for &(j, wj) in &touched {
                        gram[i * sectors + j] += wi * wj;
                    }
                }
            }
            let mut tables = PatternTables::new(n);
            tables.fill(&gram, &w_sum, &w_fixed, &w_y);
            for _ in 0..20 {
                let seen = u64::from(rng.next_u32()) & ((1 << n) - 1);
                let white: Vec<usize> = (0..n)
                    .map(|b| 2 * b + 1 - (seen >> b & 1) as usize)
                    .collect();
                let sum: f64 = white.iter().map(|&s| w_sum[s]).sum();
                let grey: f64 = white.iter().map(|&s| w_y[s]).sum();
                let norm: f64 = white.iter().map(|&s| 2.0 * w_fixed[s]).sum::<f64>()
                    + white
                        .iter()
                        .flat_map(|&s| white.iter().map(move |&t| (s, t)))
                        .map(|(s, t)| gram[s * sectors + t])
                        .sum::<f64>();
                let got = tables.sums(seen);
                for (a, b) in [(got.0, sum), (got.1, norm), (got.2, grey)] {
                    assert!(
                        (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                        "n {n} span {span} word {seen:b}: {got:?} against {sum}, {norm}, {grey}"
                    );
                }
            }
        }
    }
}
