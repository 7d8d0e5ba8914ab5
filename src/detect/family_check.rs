//! Is the family the one the markers were printed with? A ring of another
//! bit count never decodes (its bit count is read from the ring), but a
//! ring of the right length from a denser family often lies one bit from a
//! member of a sparser one, which is exactly what error correction repairs.
//! One such reading proves nothing; most readings of a frame or a sequence
//! needing correction is the sign of a wrong `--distance`.

use std::collections::BTreeMap;

use super::Detection;
use crate::family::MatchStatus;

/// Fewest member readings before the share of corrected ones is judged.
const MIN_READINGS: usize = 4;

/// Tally of how the markers of one or more frames decoded.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FamilyCheck {
    /// The family's bit count (None in auto mode or for legacy markers).
    pub family_bits: Option<u32>,
    /// Readings that matched a member exactly.
    pub exact: usize,
    /// Readings that matched a member only after correcting bits.
    pub corrected: usize,
    /// Markers whose ring shows another bit count, by count.
    pub other_bits: BTreeMap<u32, usize>,
    /// Discs with WhyCon's plain white centre and no code ring, seen while
    /// looking for WhyCode markers: a user who forgot `--legacy` gets told.
    pub legacy_looking: usize,
}

impl FamilyCheck {
    /// A tally against a family of `family_bits` bits (`None`: any count).
    pub fn new(family_bits: Option<u32>) -> FamilyCheck {
        FamilyCheck {
            family_bits,
            ..FamilyCheck::default()
        }
    }

    /// Counts the markers of one frame.
    pub fn observe(&mut self, markers: &[Detection]) {
        for m in markers {
            match (m.bits, self.family_bits) {
                (Some(bits), Some(family)) if bits != family => {
                    *self.other_bits.entry(bits).or_default() += 1;
                    continue;
                }
                (Some(bits), None) => {
                    *self.other_bits.entry(bits).or_default() += 1;
                    continue;
                }
                _ => {}
            }
            if m.id == 0 {
                continue;
            }
            match m.status {
                Some(MatchStatus::Exact) => self.exact += 1,
                Some(MatchStatus::Corrected) => self.corrected += 1,
                _ => {}
            }
        }
    }

    /// Adds another tally (of other frames) to this one.
    pub fn merge(&mut self, other: &FamilyCheck) {
        self.exact += other.exact;
        self.corrected += other.corrected;
        self.legacy_looking += other.legacy_looking;
        for (&bits, &n) in &other.other_bits {
            *self.other_bits.entry(bits).or_default() += n;
        }
    }

    /// Most markers decoded only through error correction: the family is
    /// probably not the one printed.
    pub fn mostly_corrected(&self) -> bool {
        let members = self.exact + self.corrected;
        members >= MIN_READINGS && 2 * self.corrected > members
    }

    /// The bit count most markers of another count showed, if any.
    pub fn dominant_other_bits(&self) -> Option<u32> {
        self.other_bits
            .iter()
            .max_by_key(|&(&bits, &n)| (n, std::cmp::Reverse(bits)))
            .map(|(&bits, _)| bits)
    }

    /// A sentence for the user when the family looks wrong (or, in auto
    /// mode, which bit counts were seen); None when all is as expected.
    pub fn note(&self) -> Option<String> {
        let seen = |counts: &BTreeMap<u32, usize>| {
            counts
                .iter()
                .map(|(bits, n)| format!("{n} with {bits}-bit codes"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if let Some(bits) = self.dominant_other_bits() {
            let family = self
                .family_bits
                .map_or(String::new(), |f| format!(" (not the family's {f} bits)"));
            return Some(format!(
                "{bits}-bit codes{family}: {}; pass --bits {bits} --distance D for IDs",
                seen(&self.other_bits)
            ));
        }
        if self.legacy_looking > 0 && self.exact + self.corrected == 0 {
            let n = self.legacy_looking;
            return Some(format!(
                "{n} disc{} looked like legacy WhyCon markers (a white centre, no code ring); \
                 --legacy reads them",
                if n == 1 { "" } else { "s" }
            ));
        }
        if self.mostly_corrected() {
            return Some(format!(
                "{} of {} IDs decoded only through error correction: the markers were \
                 probably printed with another family (check --bits and --distance)",
                self.corrected,
                self.exact + self.corrected
            ));
        }
        None
    }
}
