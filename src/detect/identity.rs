//! Who a candidate disc is: the whole decision of a marker's ID, and of
//! whether it is a marker at all, in one place. A detection is a marker by
//! its geometry, and named only when its ring says which member it carries
//! (paper section 5: detection reaches further than identification). The
//! pixels are read below (the ring's verdict in `ring`, the legacy rules in
//! `legacy`, the followed code in `tracking`); what they decide is here,
//! in this order:
//!
//! | evidence                                   | marker            | ID          | why unnamed                  |
//! |--------------------------------------------|-------------------|-------------|------------------------------|
//! | a settled track's code, followed by edges  | yes               | the track's | —                            |
//! | the ring names a member                    | yes               | the member  | —                            |
//! | a ring of another bit count                | yes               | 0           | `other_bit_count`            |
//! | the ring reads as no member, or as two     | yes               | 0           | `not_a_member`, `ambiguous`  |
//! | a ring read with no family to name it in   | yes               | 0           | `no_family`                  |
//! | a ring too unsure to name                  | yes               | 0           | `ring_unread`                |
//! | no code ring, and a settled track          | yes               | 0           | `no_code_ring`               |
//! | no code ring, a WhyCon inside, ≥ 20 px     | yes               | 0           | `no_code_ring`               |
//! | no code ring, a blurred WhyCon inside      | yes               | 0           | `no_code_ring`               |
//! | no code ring otherwise                     | no (`unreadable`) | 0           | `no_code_ring`               |
//! | legacy target: a WhyCon inside, or followed| yes               | 0           | —                            |
//!
//! Then a tracked marker's ID is the ID filter's belief over its frames
//! (paper 5.1), not this frame's reading alone: one misread does not change
//! it, and a marker whose readings disagree is unknown until they settle.
//! A WhyCode marker left with ID 0 always says why.

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::describe::detection;
use super::pose::Posed;
use super::ring::{RingRead, RingVerdict};
use super::segment::Gray;
use super::tracking::idfilter::IdFilter;
use super::tracking::FollowedCode;
use super::{legacy, rectify, Candidate, Detection, Detector, Workspace};
use crate::family::MatchStatus;
use crate::geometry::Design;

impl Detector {
    /// Candidate `c`'s detection (before its pose) by the table above, the
    /// ring reading its pose starts from, and a followed marker's pose.
    pub(super) fn identity<C: Deref<Target = [u8]>>(
        &mut self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, RingRead, Option<Posed>) {
        let reading = self.read_tracked(ws, image, gray, c);
        self.settle_identity(gray, c, reading)
    }

    /// What [`Detector::identity`] reads of a candidate before its track's
    /// ID filter: it changes nothing, so the tracked markers of a frame
    /// can be read on several threads.
    pub(super) fn read_tracked<C: Deref<Target = [u8]>>(
        &self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> Reading {
        let followed = c.track.and_then(|i| self.follow_code(ws, gray, c, i));
        let (d, read) = match &followed {
            Some(followed) => (detection(c, &followed.read, false), followed.read),
            None => self.read_identity(ws, image, gray, c),
        };
        Reading {
            detection: d,
            read,
            followed,
        }
    }

    /// The rest of [`Detector::identity`] after [`Detector::read_tracked`]:
    /// the reading through the candidate's track's ID filter (which it
    /// updates).
    pub(super) fn settle_identity(
        &mut self,
        gray: Gray<'_>,
        c: &Candidate,
        reading: Reading,
    ) -> (Detection, RingRead, Option<Posed>) {
        let Reading {
            detection: mut d,
            read,
            followed,
        } = reading;
        if let Some(i) = c.track {
            self.filter_identity(gray, c, i, &mut d, followed.is_some());
        }
        self.say_why_unnamed(&mut d);
        (d, read, followed.and_then(|f| f.posed))
    }

    /// [`Detector::identity`] of a candidate with no track (a scan's find):
    /// what its pixels say alone.
    pub(super) fn found_identity<C: Deref<Target = [u8]>>(
        &self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, RingRead) {
        let (mut d, read) = self.read_identity(ws, image, gray, c);
        self.say_why_unnamed(&mut d);
        (d, read)
    }

    /// Candidate `c` by its ring, or by the legacy rules, before any ID
    /// filter.
    fn read_identity<C: Deref<Target = [u8]>>(
        &self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, RingRead) {
        let quality = 1.0 - (c.area_error / self.tolerances.area.tolerance()).min(1.0);
        let outline = (0.5 + 0.5 * quality).clamp(0.0, 1.0);
        if self.config.target.design() == Design::WhyCode {
            self.by_ring(ws, image, gray, c, outline)
        } else {
            self.by_legacy_rule(image, gray, c, outline)
        }
    }

    /// A named detection says nothing of why it would be unnamed; a
    /// WhyCode marker left unnamed always says why.
    fn say_why_unnamed(&self, d: &mut Detection) {
        if d.id != 0 {
            d.unnamed = None;
        } else if d.unnamed.is_none() && self.config.target.design() == Design::WhyCode {
            // A followed marker whose ring this frame did not name.
            d.unnamed = Some(Unnamed::Unread);
        }
    }

    /// A WhyCode candidate by what its ring says, and without a code ring
    /// by its track and the legacy rules.
    fn by_ring<C: Deref<Target = [u8]>>(
        &self,
        ws: &mut Workspace,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
        outline: f64,
    ) -> (Detection, RingRead) {
        // A followed ring is tested for the bit count it showed last first:
        // passing that surely spares testing every other count (each
        // frame's cost on rings of another family, or without one).
        let remembered = c.track.and_then(|i| self.tracks[i].bits);
        let verdict = self.rings.identify(image, gray, c, outline, remembered);
        // A settled track whose ring blurs is still the marker.
        let settled = c.track.is_some_and(|i| self.settled(i));
        let mut marker = !matches!(verdict, RingVerdict::NotAMarker(_)) || settled;
        if !marker {
            // No code ring shows: a marker still, when its geometry says so
            // (a legacy WhyCon circle, a ring blurred past reading),
            // reported without an ID.
            let large = 2.0 * c.outer.semi_minor >= MIN_NO_RING_DIAMETER_PX;
            let sharp = legacy::is_marker(image, gray, c, self.config.legacy_min_ink_px);
            if sharp && c.track.is_none() {
                ws.legacy_looking += 1;
            }
            marker = (sharp && large) || legacy::is_blurred_marker(gray, c);
        }
        let family = self.config.target.family().is_some();
        let mut d = detection(c, verdict.read(), !marker);
        d.unnamed = Unnamed::of_verdict(&verdict, family);
        (d, *verdict.read())
    }

    /// A legacy WhyCon candidate: a marker by its inside, or by its track.
    fn by_legacy_rule<C: Deref<Target = [u8]>>(
        &self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
        outline: f64,
    ) -> (Detection, RingRead) {
        // A marker followed for a while stays one when its inside blurs, so
        // its inside need not be looked at (the ray test costs more than
        // following it).
        let followed = c.track.is_some_and(|i| self.tracks[i].hits >= 3);
        let marker = followed
            || legacy::is_marker(image, gray, c, self.config.legacy_min_ink_px)
            || legacy::is_blurred_marker(gray, c);
        let read = RingRead::nothing(outline);
        (detection(c, &read, !marker), read)
    }

    /// Tracked markers report what the ID filter believes after this
    /// frame's reading, not the single reading: one misread (motion blur,
    /// a glint) does not change a marker's ID, and a marker whose readings
    /// disagree is "unknown" until they settle.
    fn filter_identity(
        &mut self,
        gray: Gray<'_>,
        c: &Candidate,
        index: usize,
        d: &mut Detection,
        followed: bool,
    ) {
        let Some(family) = self.config.target.family() else {
            return;
        };
        let track = &mut self.tracks[index];
        let previous_yaw = track.yaw;
        let estimate = track.observe_reading(family.len(), d);
        if followed || estimate.id == d.id {
            if estimate.id != 0 {
                d.confidence = estimate.probability;
            }
            return;
        }
        // This frame's reading, if it named something, contradicts the
        // belief that is reported instead.
        let contradicted = d.id != 0 || d.status == Some(MatchStatus::Rejected);
        d.confidence = if contradicted && estimate.id != 0 {
            IdFilter::contradicted(estimate, d.confidence)
        } else {
            estimate.probability
        };
        d.id = estimate.id;
        d.code = family.code(estimate.id);
        // The reading's yaw belongs to the code it read; the believed code's
        // edges give the yaw instead.
        d.yaw = match (d.code, previous_yaw) {
            (Some(code), Some(yaw)) => {
                rectify::follow_ring(gray, &c.outer, family.bits(), code, yaw)
            }
            _ => None,
        };
    }
}

/// What a candidate's pixels (and its track, read only) say of it before
/// the ID filter: see [`Detector::read_tracked`].
#[derive(Debug, Clone)]
pub(super) struct Reading {
    detection: Detection,
    read: RingRead,
    followed: Option<FollowedCode>,
}

/// Why a WhyCode marker was reported with ID 0 ("unknown").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unnamed {
    /// A black disc round a concentric light centre with a white margin,
    /// but no code ring shows: a legacy WhyCon circle, or a WhyCode ring
    /// blurred or compressed past reading.
    NoCodeRing,
    /// A code ring shows, but too small, too blurred or too unsure to name
    /// a member.
    Unread,
    /// The ring reads as a code that no member carries: a periodic code,
    /// or more bits wrong than the family corrects.
    NotMember,
    /// Two members fit the ring equally well.
    Ambiguous,
    /// The ring carries a code of another bit count than the family's.
    OtherBits,
    /// The ring's code was read, with no family to name it in (any bit
    /// count, no distance given).
    NoFamily,
}

impl Unnamed {
    /// The reason as one lower-case word pair for JSON and tables.
    pub fn key(self) -> &'static str {
        match self {
            Unnamed::NoCodeRing => "no_code_ring",
            Unnamed::Unread => "ring_unread",
            Unnamed::NotMember => "not_a_member",
            Unnamed::Ambiguous => "ambiguous",
            Unnamed::OtherBits => "other_bit_count",
            Unnamed::NoFamily => "no_family",
        }
    }

    /// Why the ring named no member, from its verdict (None for a member).
    /// `family` tells whether a family was there to name it in.
    fn of_verdict(verdict: &RingVerdict, family: bool) -> Option<Unnamed> {
        match verdict {
            RingVerdict::Member(_) => None,
            RingVerdict::OtherBits(_) => Some(Unnamed::OtherBits),
            RingVerdict::NotAMarker(_) => Some(Unnamed::NoCodeRing),
            RingVerdict::Unknown(read) => Some(match read.status {
                Some(MatchStatus::Rejected) => Unnamed::NotMember,
                Some(MatchStatus::Ambiguous) => Unnamed::Ambiguous,
                _ if !family && read.code.is_some() => Unnamed::NoFamily,
                _ => Unnamed::Unread,
            }),
        }
    }
}

/// Smallest outer diameter (pixels, across the outline's minor axis) at
/// which a WhyCode detector reports a disc whose ring shows no code: the
/// bold letters of printed text that pass a WhyCon marker's every test are
/// 8-16 px across, and a legacy WhyCon circle is reported from here on as
/// an unknown marker.
pub const MIN_NO_RING_DIAMETER_PX: f64 = 20.0;
