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
//! (`solver::PatternTables`).
//!
//! This file holds the readers and the thresholds they name a ring by; the
//! parts they share are a file each: `footprint.rs` renders the marker at
//! the compared pixels (a footprint of points, or a pixel's area through a
//! Gaussian), `solver.rs` fits every member rotation to the pixels by
//! least squares, `neighbour_count.rs` withdraws a member that a ring of a
//! neighbouring bit count explains better, and `light.rs` tells a small
//! marker's round light from a letter's stretched hole.

mod footprint;
mod light;
mod neighbour_count;
mod solver;

pub use light::{light_elongation, MAX_LIGHT_ELONGATION};

use std::f64::consts::PI;
use std::ops::Deref;

use image::{ImageBuffer, Luma};

use crate::detect::ellipse::LinearBlur;
use crate::family::Family;
use crate::geometry::WHYCODE_WHITE_RATIO;
use crate::math::Ellipse as ImageEllipse;
use footprint::{gaussian_footprint, line_footprint, Footprint, RingPixels};

/// Semi-major axis (pixels) up to which a steep view of the marker is
/// still close enough to an affine one for the model to be trusted.
pub const MAX_AFFINE_SEMI_MAJOR: f64 = 15.0;

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
/// (`RingPixels::neighbour_count_fits_better`).
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
/// that wide, on about `COMPARED_PIXELS` pixels whatever the ring's size.
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

/// Pixel stride at which about [`COMPARED_PIXELS`] of the ring's are
/// compared (the blur, not the pixel, sets the scale of what the model can
/// tell apart).
fn compared_stride(outer: &ImageEllipse) -> u32 {
    let disc = PI * (outer.semi_major * COMPARED_RADIUS) * (outer.semi_minor * COMPARED_RADIUS);
    ((disc / COMPARED_PIXELS).sqrt().floor() as u32).max(1)
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
}
