//! Why a marker is reported without an ID: a detection is a marker by its
//! geometry, and named only when its ring says which member it carries
//! (paper section 5: detection reaches further than identification). The
//! reason goes with the detection, so a user who sees ID 0 knows whether
//! the ring was absent, unread, or read as no member.

use super::ring::RingVerdict;
use crate::family::MatchStatus;

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
    pub(super) fn of_verdict(verdict: &RingVerdict, family: bool) -> Option<Unnamed> {
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
