//! ID families: aperiodic binary necklaces with a minimum cyclic Hamming
//! distance, numbered exactly as the original WhyCode implementation numbers
//! them (spec section 3), and the lookup that decodes ring readings into IDs.

pub mod lookup;
pub mod necklace;

pub use lookup::{Decoded, Decoder, MatchStatus};

use necklace::{ball_size, for_each_mask_with_ones, is_periodic, mask, rotl};

/// Smallest and largest supported code lengths.
pub const MIN_BITS: u32 = 2;
pub const MAX_BITS: u32 = 24;

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum FamilyError {
    #[error("bits must be between {MIN_BITS} and {MAX_BITS}, got {0}")]
    Bits(u32),
    #[error("distance must be between 1 and the bit count {bits}, got {distance}")]
    Distance { bits: u32, distance: u32 },
}

/// A family of marker codes: `codes[k]` is the code of ID k + 1. Every code
/// is the smallest rotation of an aperiodic necklace. ID 0 is reserved for
/// "unknown".
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Family {
    bits: u32,
    distance: u32,
    codes: Vec<u32>,
}

impl Family {
    /// Builds the greedy family of the spec: integers 1..2^n in increasing
    /// order, accepting each aperiodic word whose every rotation keeps at
    /// least `distance` from every accepted code.
    pub fn generate(bits: u32, distance: u32) -> Result<Family, FamilyError> {
        if !(MIN_BITS..=MAX_BITS).contains(&bits) {
            return Err(FamilyError::Bits(bits));
        }
        if distance == 0 || distance > bits {
            return Err(FamilyError::Distance { bits, distance });
        }
        let radius = distance - 1;
        let words = 1u64 << bits;
        // Marking the Hamming ball around every rotation of every accepted
        // code costs about count·n·ball; checking each candidate against the
        // accepted list costs about 2^n·count·n. Mark while the ball is small.
        let codes = if ball_size(bits, radius) * 4 <= words {
            generate_by_marking(bits, radius)
        } else {
            generate_by_checking(bits, distance)
        };
        Ok(Family {
            bits,
            distance,
            codes,
        })
    }

    /// A family from an explicit code list (e.g. a loaded family file). The
    /// codes must be minimal rotations of aperiodic words.
    pub fn from_codes(bits: u32, distance: u32, codes: Vec<u32>) -> Result<Family, FamilyError> {
        if !(MIN_BITS..=MAX_BITS).contains(&bits) {
            return Err(FamilyError::Bits(bits));
        }
        if distance == 0 || distance > bits {
            return Err(FamilyError::Distance { bits, distance });
        }
        Ok(Family {
            bits,
            distance,
            codes,
        })
    }

    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The minimum cyclic Hamming distance the family was built for.
    pub fn distance(&self) -> u32 {
        self.distance
    }

    pub fn len(&self) -> usize {
        self.codes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Codes in ID order: `codes()[k]` belongs to ID k + 1.
    pub fn codes(&self) -> &[u32] {
        &self.codes
    }

    /// The code of an ID (IDs start at 1).
    pub fn code(&self, id: u32) -> Option<u32> {
        if id == 0 {
            return None;
        }
        self.codes.get(id as usize - 1).copied()
    }

    /// The ID whose code is exactly `code` (a stored, minimal rotation).
    pub fn id_of(&self, code: u32) -> Option<u32> {
        // Codes are accepted in increasing order, so the list is sorted.
        self.codes.binary_search(&code).ok().map(|k| k as u32 + 1)
    }

    /// The correction radius the family's distance guarantees.
    pub fn default_correction_radius(&self) -> u32 {
        (self.distance - 1) / 2
    }
}

fn generate_by_marking(bits: u32, radius: u32) -> Vec<u32> {
    let words = 1usize << bits;
    let mut forbidden = vec![0u64; words.div_ceil(64)];
    let mut codes = Vec::new();
    for c in 1..(words as u32) {
        if forbidden[(c >> 6) as usize] >> (c & 63) & 1 == 1 || is_periodic(c, bits) {
            continue;
        }
        codes.push(c);
        for r in 0..bits {
            let rotated = rotl(c, bits, r);
            for ones in 0..=radius {
                for_each_mask_with_ones(bits, ones, |m| {
                    let w = rotated ^ m;
                    forbidden[(w >> 6) as usize] |= 1 << (w & 63);
                });
            }
        }
    }
    codes
}

fn generate_by_checking(bits: u32, distance: u32) -> Vec<u32> {
    let mut rotations: Vec<u32> = Vec::new();
    let mut codes = Vec::new();
    for c in 1..=mask(bits) {
        if rotations.iter().any(|&r| (r ^ c).count_ones() < distance) || is_periodic(c, bits) {
            continue;
        }
        codes.push(c);
        rotations.extend((0..bits).map(|r| rotl(c, bits, r)));
    }
    codes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_count_table() {
        let table: [(u32, [usize; 7]); 4] = [
            (1, [3, 9, 30, 99, 335, 1161, 4080]),
            (2, [2, 5, 16, 51, 170, 585, 2048]),
            (3, [1, 2, 3, 7, 16, 48, 125]),
            (4, [1, 2, 2, 5, 10, 24, 69]),
        ];
        for (d, counts) in table {
            for (k, &count) in counts.iter().enumerate() {
                let n = 4 + 2 * k as u32;
                assert_eq!(Family::generate(n, d).unwrap().len(), count, "n={n} d={d}");
            }
        }
    }

    #[test]
    fn spec_test_vector() {
        let f = Family::generate(8, 2).unwrap();
        assert_eq!(
            f.codes(),
            &[1, 7, 11, 13, 19, 21, 25, 31, 37, 47, 55, 59, 61, 87, 91, 127]
        );
    }

    #[test]
    fn both_strategies_agree() {
        for bits in 4..=10 {
            for d in 1..=bits {
                assert_eq!(
                    generate_by_marking(bits, d - 1),
                    generate_by_checking(bits, d),
                    "n={bits} d={d}"
                );
            }
        }
    }
}
