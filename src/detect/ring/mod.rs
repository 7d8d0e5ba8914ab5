//! Reading a candidate's code ring: is there a WhyCode ring, of how many
//! bits, and which member does it carry? `Rings::identify` answers with a
//! `RingVerdict`: a member, a ring of another bit count, a marker whose ID
//! cannot be told, or no marker.
//!
//! One file per way of looking at a ring, all reading through the shared
//! profile primitives of `profile.rs` (the ellipse's parametrisation, the
//! ring's sampled profile, its sector boundaries and half-sectors):
//! [`manchester`] tests for the Manchester structure of each bit count,
//! [`RingReader`] (`reader.rs`) reads the bits of rings wide enough to
//! sample sector by sector, and [`model`] compares rings too small or too
//! smeared for that with every member rendered as the camera would see it.

#[cfg(test)]
#[macro_use]
mod test_images;

pub mod manchester;
pub mod model;
mod profile;
mod reader;

pub use reader::{RingReader, RingReading, MIN_ID_CONFIDENCE, MIN_PIXELS_PER_SECTOR};

use std::ops::Deref;
use std::sync::OnceLock;

use image::{ImageBuffer, Luma};

use super::segment::Gray;
use super::{ellipse, Candidate, Target};
use crate::family::{Decoder, Family, MatchStatus};
use crate::math::Ellipse;
use manchester::{RingEvidence, RingStructure};
use model::SmallRing;

/// What a candidate's ring says it is, with what the detection reports of
/// the ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum RingVerdict {
    /// A member named: of the family, or in auto mode of the family of the
    /// ring's own bit count.
    Member(RingRead),
    /// A code ring of a count other than the family's: no marker of this
    /// family (ID 0); the code is what the ring shows.
    OtherBits(RingRead),
    /// A marker whose ID cannot be told: too small or too smeared to name,
    /// no member, two members alike, or no family to name it in.
    Unknown(RingRead),
    /// No code ring where a marker's would show. What little was read is
    /// reported only for a marker its track has settled on, or with
    /// [`super::DetectorConfig::report_unreadable`].
    NotAMarker(RingRead),
}

impl RingVerdict {
    /// What was read, whatever the verdict.
    pub(super) fn read(&self) -> &RingRead {
        match self {
            RingVerdict::Member(read)
            | RingVerdict::OtherBits(read)
            | RingVerdict::Unknown(read)
            | RingVerdict::NotAMarker(read) => read,
        }
    }
}

/// What the looks at a ring read, as a detection reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RingRead {
    /// Family ID, 0 when none is named.
    pub id: u32,
    pub code: Option<u32>,
    pub status: Option<MatchStatus>,
    /// Image direction of the marker's +x axis.
    pub yaw: Option<f64>,
    pub confidence: f64,
    /// The bit count the ring shows, when it could be counted.
    pub bits: Option<u32>,
    /// For the pose stage: the rim point on the +x axis, and where the
    /// ring's radial edges put the image of the marker's centre (see
    /// [`RingReading`]).
    pub axis_point: Option<(f64, f64)>,
    pub centre_estimate: Option<(f64, f64)>,
}

impl RingRead {
    /// Nothing read yet, with the confidence the candidate's outline earned.
    pub(super) fn nothing(confidence: f64) -> RingRead {
        RingRead {
            id: 0,
            code: None,
            status: None,
            yaw: None,
            confidence,
            bits: None,
            axis_point: None,
            centre_estimate: None,
        }
    }

    /// The sector reader's reading; a code read before it (a ring of
    /// another count's) stays unless the reader names a member.
    fn take(&mut self, reading: &RingReading) {
        self.id = reading.id;
        self.code = reading
            .decoded
            .filter(|x| x.is_member())
            .map(|x| x.code)
            .or(self.code);
        self.status = reading.decoded.map(|x| x.status);
        self.yaw = reading.yaw;
        self.confidence = reading.confidence;
        self.axis_point = reading.axis_point;
        self.centre_estimate = reading.centre_estimate;
    }

    /// The member the ring model named.
    fn named_by_model(self, ring: &SmallRing) -> RingRead {
        RingRead {
            id: ring.id,
            code: Some(ring.code),
            status: Some(MatchStatus::Exact),
            yaw: ring.yaw,
            confidence: (1.0 - 1.0 / ring.margin).clamp(0.0, 1.0),
            ..self
        }
    }
}

/// The ring readers of one detector: the family's, and in auto mode with
/// a distance one per bit count met (families are generated on first use).
#[derive(Debug, Clone)]
pub(super) struct Rings {
    family: Option<RingReader>,
    auto: AutoReaders,
}

#[derive(Debug, Clone)]
struct AutoReaders {
    distance: Option<u32>,
    /// Indexed by bit count; each made once, by whichever thread describing
    /// a candidate first needs it.
    readers: Vec<OnceLock<Option<RingReader>>>,
}

impl AutoReaders {
    /// The reader for rings of `bits` bits; None without a distance.
    fn reader(&self, bits: u32) -> Option<&RingReader> {
        let distance = self.distance?;
        let reader = self.readers.get(bits as usize)?.get_or_init(|| {
            Family::generate(bits, distance)
                .ok()
                .map(|family| RingReader::new(Some(Decoder::new(&family))))
        });
        reader.as_ref()
    }
}

impl Rings {
    /// The readers for what `target` looks for.
    pub(super) fn new(target: &Target) -> Rings {
        let distance = match target {
            Target::AnyBits { distance } => *distance,
            Target::WhyCon | Target::WhyCode(_) => None,
        };
        Rings {
            family: target
                .family()
                .map(|family| RingReader::new(Some(Decoder::new(family)))),
            auto: AutoReaders {
                distance,
                readers: (0..=*manchester::BITS.end())
                    .map(|_| OnceLock::new())
                    .collect(),
            },
        }
    }

    fn family(&self) -> Option<&Family> {
        self.family
            .as_ref()
            .and_then(RingReader::decoder)
            .map(Decoder::family)
    }

    /// What the ring of candidate `c` says it is. `confidence` is what the
    /// candidate's outline earned, `remembered` the bit count its track's
    /// ring showed last. In steps: the structure test's evidence; the bits
    /// read sector by sector, or on a ring too small to count its sectors,
    /// by the ring model; a coarser count such a ring still shows; and for
    /// a ring the outline shows smeared by motion, the members rendered
    /// through that smear.
    pub(super) fn identify<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
        confidence: f64,
        remembered: Option<u32>,
    ) -> RingVerdict {
        let family_bits = self.family().map(Family::bits);
        let evidence = evidence(image, c, family_bits, remembered);
        let mut read = RingRead::nothing(confidence);
        let mut marker = true;
        match (evidence, &self.family) {
            (RingEvidence::Manchester(ring), Some(reader)) if Some(ring.bits) == family_bits => {
                read.bits = Some(ring.bits);
                read.take(&read_sectors(reader, image, c, ring.in_shade));
            }
            (RingEvidence::Manchester(ring), _) => {
                // Not this family's ring (or no family given): the code is
                // what the ring says, the ID only from a family of the
                // ring's own bit count.
                read.bits = Some(ring.bits);
                read.code = Some(ring.code);
                read.confidence *= ring.fit;
                if let Some(reader) = self.auto.reader(ring.bits) {
                    read.take(&read_sectors(reader, image, c, ring.in_shade));
                }
            }
            // Auto mode cannot name the bit count of a ring too small to
            // count its sectors: no evidence it is a marker.
            (RingEvidence::Absent, _) | (RingEvidence::TooSmall, None) => marker = false,
            (RingEvidence::TooSmall, Some(reader)) => {
                let family = reader.decoder().map(Decoder::family);
                match family
                    .and_then(|family| model::read_small_ring_of_its_count(image, &c.outer, family))
                {
                    Some(ring) if !ring.structured => {
                        // The rendered model ignores perspective, which a
                        // steep view of a large marker cannot: there it
                        // names no ID but refutes nothing either.
                        let outer = &c.outer;
                        marker = outer.semi_major > 2.0 * outer.semi_minor
                            && outer.semi_major > model::MAX_AFFINE_SEMI_MAJOR;
                    }
                    Some(ring) if ring.id != 0 => read = read.named_by_model(&ring),
                    // Vouched for without a member to name, the ring's
                    // light must be as round as a marker's: the lopsided
                    // hole of a bold letter 'O' passes the structure ratio
                    // (the best of a thousand member rotations fits some of
                    // any hole's asymmetry) but not this.
                    Some(_) => {
                        marker = model::light_elongation(image, &c.outer)
                            .is_none_or(|e| e <= model::MAX_LIGHT_ELONGATION);
                    }
                    None => {
                        let reading = read_sectors(reader, image, c, false);
                        // A ring the structure test could not look at (cut
                        // by the image border, say) that reads as no code
                        // at all is no evidence of a marker either.
                        marker = reading.decoded.is_some();
                        read.take(&reading);
                    }
                }
                // Out of focus by more than the small-ring model's own
                // blurs, the ring may still be named by the members
                // rendered through the blur its outline shows.
                if read.id == 0 {
                    if let Some(ring) = family.and_then(|f| defocused_small_ring(image, gray, c, f))
                    {
                        marker = true;
                        read = RingRead {
                            axis_point: None,
                            centre_estimate: None,
                            ..read.named_by_model(&ring)
                        };
                    }
                }
            }
        }
        if let (Some(bits), RingEvidence::TooSmall, true) = (family_bits, evidence, read.id != 0) {
            // Too fine to test for the family's count, the ring may still
            // show a coarser count's structure: then the member read is not
            // what was printed (a 16-bit ring 43 px across matched a member
            // of an 18-bit family, dense as long families are). Only the ID
            // goes: the candidate was judged a marker or not as before.
            if let Some(ring) = coarser_ring(image, c, bits) {
                read = RingRead {
                    bits: Some(ring.bits),
                    code: Some(ring.code),
                    confidence: read.confidence * ring.fit,
                    // The yaw, rim point and centre were the member's.
                    ..RingRead::nothing(0.0)
                };
            }
        }
        let family_ring = match evidence {
            RingEvidence::Manchester(ring) => Some(ring.bits) == family_bits,
            RingEvidence::Absent => true,
            RingEvidence::TooSmall => false,
        };
        // A clean exact reading needs no second opinion; any other ring the
        // outline shows smeared by motion is compared with the members
        // rendered through that smear.
        let clean =
            read.id != 0 && read.status == Some(MatchStatus::Exact) && read.confidence >= 0.5;
        if family_ring && !clean {
            if let Some(blurred) = self.read_blurred(image, gray, &c.outer) {
                if let Some(judged) = with_blurred_model(read, &blurred) {
                    // The model vouches for the ring.
                    marker = true;
                    read = judged;
                }
            }
        }
        if !marker {
            RingVerdict::NotAMarker(read)
        } else if read.id != 0 {
            RingVerdict::Member(read)
        } else if family_bits.is_some() && read.bits.is_some() && read.bits != family_bits {
            RingVerdict::OtherBits(read)
        } else {
            RingVerdict::Unknown(read)
        }
    }

    /// The ring read through the blur its outline shows: a motion blur
    /// long enough to smear the sectors the reader samples, else a focus
    /// blur wide enough to.
    fn read_blurred<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        outer: &Ellipse,
    ) -> Option<SmallRing> {
        let family = self.family()?;
        // Below this length the sector reader's central samples stay clear
        // of the neighbouring sectors.
        let motion = ellipse::linear_blur(gray, outer)
            .filter(|blur| blur.length >= ellipse::MIN_MOTION_BLUR_PX);
        if let Some(blur) = motion {
            return model::read_blurred_ring(image, outer, family, &blur);
        }
        // A blur narrow beside the half-sectors leaves their edges to the
        // structure test and the reader: a ring they refute then is no
        // marker's (desk clutter's washers and letters, whose edges read
        // as a little blur, would otherwise all be compared with the
        // family; the cost: docs/detection.md, "Defocus, small and steep
        // markers").
        let sectors = manchester::sector_pixels(outer, family.bits());
        let sigma = ellipse::defocus(gray, outer)
            .filter(|&s| s >= MIN_DEFOCUS_PX && s >= MIN_DEFOCUS_PER_SECTOR * sectors)?;
        model::read_defocused_ring(image, outer, family, sigma)
    }
}

/// The sector reader's reading of the ring: read as under even light when
/// the structure test found a cast shadow's edge across it.
fn read_sectors<C: Deref<Target = [u8]>>(
    reader: &RingReader,
    image: &ImageBuffer<Luma<u8>, C>,
    c: &Candidate,
    in_shade: bool,
) -> RingReading {
    let (outer, black, white) = (&c.outer, c.black, c.white);
    if in_shade {
        return reader.read_in_shade(image, outer, black, white);
    }
    let reading = reader.read(image, outer, black, white);
    if reading.id != 0 {
        return reading;
    }
    // A shadow's edge across a ring whose structure still shows may hide
    // a bit's edge in the shade. Read as under even light, only a clean,
    // exact member counts: evening also flattens a motion blur's smear.
    let shaded = reader.read_in_shade(image, outer, black, white);
    let clean = shaded.erasures == 0
        && shaded
            .decoded
            .is_some_and(|x| x.status == MatchStatus::Exact);
    if shaded.id != 0 && clean {
        shaded
    } else {
        reading
    }
}

/// A ring too small to sample named through the focus blur its outline
/// shows, when that blur is past the small-ring model's own: the member
/// [`model::read_defocused_ring_of_its_count`] names (none when a ring of a
/// neighbouring count explains the pixels better). `None` under a motion blur, a blur
/// the small-ring model covers, or without a member named.
fn defocused_small_ring<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    gray: Gray<'_>,
    c: &Candidate,
    family: &Family,
) -> Option<SmallRing> {
    let outer = &c.outer;
    if ellipse::linear_blur(gray, outer).is_some_and(|b| b.length >= ellipse::MIN_MOTION_BLUR_PX) {
        return None;
    }
    let sigma = ellipse::defocus(gray, outer).filter(|&s| s >= MIN_SMALL_RING_DEFOCUS_PX)?;
    let ring = model::read_defocused_ring_of_its_count(image, outer, family, sigma)?;
    (ring.structured && ring.id != 0).then_some(ring)
}

/// The reading as the blurred ring model judges it: None when the model
/// sees no code ring (no opinion); else the model vouches for the ring (a
/// marker even when the structure test saw no Manchester structure) and
/// names the ID the reading could not; when the two name different
/// members, or the reading needed correcting where the model sees two
/// members alike, no ID is named.
fn with_blurred_model(read: RingRead, ring: &SmallRing) -> Option<RingRead> {
    if !ring.structured {
        return None;
    }
    let agrees = match (read.id, ring.id) {
        (0, 0) => true,
        (named, 0) => named != 0 && read.status == Some(MatchStatus::Exact),
        (named, modelled) => named == modelled,
    };
    if agrees {
        return Some(read);
    }
    let judged = if read.id == 0 {
        read.named_by_model(ring)
    } else {
        RingRead {
            id: 0,
            code: None,
            status: None,
            yaw: None,
            confidence: 0.0,
            ..read
        }
    };
    // The reader's rim point and centre belong to a reading that no
    // longer stands.
    Some(RingRead {
        axis_point: None,
        centre_estimate: None,
        ..judged
    })
}

/// The Manchester structure of a count at least two below `bits` that a
/// ring too small to test for `bits` shows (a neighbouring count may pass
/// for the ring's own when its sectors are this fine; see
/// [`manchester::examine`]). Counts of 8 bits and more: on so small a ring
/// the lobes of a blurred finer code pass for a short one (8-bit markers
/// 10 px across lost a sixth of their IDs to 4- to 6-bit readings).
fn coarser_ring<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    c: &Candidate,
    bits: u32,
) -> Option<RingStructure> {
    let outer = &c.outer;
    let coarser =
        manchester::BITS.filter(|&n| n >= 8 && n + 2 <= bits && manchester::testable(outer, n));
    match manchester::examine(image, outer, c.black, c.white, coarser, false) {
        RingEvidence::Manchester(ring) => Some(ring),
        _ => None,
    }
}

/// Focus blur (Gaussian sigma, pixels) from which a ring that the
/// structure test or the reader could not settle is read through it.
const MIN_DEFOCUS_PX: f64 = 0.5;

/// Focus blur (Gaussian sigma, pixels) from which a ring too small to
/// sample is also read through it: past the small-ring model's blurs
/// (its widest is 1.05 px with the pixel's own area).
const MIN_SMALL_RING_DEFOCUS_PX: f64 = 0.8;

/// Focus blur, relative to the half-sector's width, from which the sectors'
/// edges are too soft for the structure test and the reader.
const MIN_DEFOCUS_PER_SECTOR: f64 = 0.3;

/// Least sector width (pixels, see [`manchester::sector_pixels`]) at which
/// a ring read without a family is believed.
const AUTO_MIN_SECTOR_PX: f64 = 2.0;

/// What the candidate's ring shows: the bit count its track showed last
/// and the family's are tried first (the common case), then every other
/// count, so that a ring of another family is told apart from no ring at
/// all.
pub(super) fn evidence<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    c: &Candidate,
    family_bits: Option<u32>,
    remembered: Option<u32>,
) -> RingEvidence {
    let outer = &c.outer;
    match family_bits {
        Some(bits) if !manchester::testable(outer, bits) => RingEvidence::TooSmall,
        Some(bits) => {
            let first = remembered.filter(|&n| n != bits && manchester::testable(outer, n));
            // Counts too long to test on this ring are no evidence against
            // the family's.
            let others = manchester::BITS
                .filter(|&n| n != bits && Some(n) != first && manchester::testable(outer, n));
            manchester::examine(
                image,
                outer,
                c.black,
                c.white,
                first.into_iter().chain(std::iter::once(bits)).chain(others),
                first.is_none(),
            )
        }
        // Without a family nothing but the structure test vouches for the
        // ring, and on a ring of a few pixels the lobes of a letter or of
        // an off-centre hole pass for a short code: only counts whose
        // sectors are wide enough to show their own edges are tried.
        None => {
            let wide = |n: u32| manchester::sector_pixels(outer, n) >= AUTO_MIN_SECTOR_PX;
            let first = remembered.filter(|&n| manchester::BITS.contains(&n) && wide(n));
            let counts = manchester::BITS.filter(|&n| wide(n) && Some(n) != first);
            manchester::examine(
                image,
                outer,
                c.black,
                c.white,
                first.into_iter().chain(counts),
                false,
            )
        }
    }
}
