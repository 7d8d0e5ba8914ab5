//! ID families: aperiodic binary necklaces with a minimum cyclic Hamming
//! distance, numbered exactly as the original WhyCode implementation numbers
//! them (spec section 3), and the lookup that decodes ring readings into IDs.

mod counts;
mod file;
mod id_list;
pub mod lookup;
pub mod necklace;
mod stats;

pub use counts::{CountTable, CountsError};
pub use file::{FAMILY_FILE_FORMAT, FAMILY_FILE_VERSION};
pub use id_list::{check_id_list, parse_id_list, IdListError, MAX_LISTED_IDS};
pub use lookup::{Decoded, Decoder, MatchStatus};
pub use stats::FamilyStats;

use necklace::{ball_size, for_each_mask_with_ones, is_periodic, mask, min_rotation, rotl};

/// Shortest supported code length.
pub const MIN_BITS: u32 = 2;
/// Longest supported code length.
pub const MAX_BITS: u32 = 24;

/// The family `whycode ids` shows when asked for none in particular: 8 bits
/// give 16 IDs at distance 2, which detects every single-bit misreading (the
/// paper's recommendation together with the Bayesian ID filter).
pub const DEFAULT_BITS: u32 = 8;
/// Default minimum cyclic Hamming distance (see [`DEFAULT_BITS`]).
pub const DEFAULT_DISTANCE: u32 = 2;

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
/// Why a family could not be made: bad parameters or a code list that breaks the family's promises. The messages are the CLI's, one line each.
pub enum FamilyError {
    #[error("bits must be between {MIN_BITS} and {MAX_BITS}, got {0}")]
    /// The bit count is outside [`MIN_BITS`]..=[`MAX_BITS`].
    Bits(u32),
    #[error("distance must be between 1 and the bit count {bits}, got {distance}")]
    /// The distance is 0 or larger than the bit count.
    Distance {
        /// The family's bit count.
        bits: u32,
        /// The distance asked for.
        distance: u32,
    },
    #[error("a family needs at least one code")]
    /// The code list is empty.
    Empty,
    #[error("ID {id}: code {code} does not fit in {bits} bits")]
    /// A code has bits set above the family's bit count.
    CodeRange {
        /// The code's ID.
        id: u32,
        /// The code.
        code: u32,
        /// The family's bit count.
        bits: u32,
    },
    #[error("ID {id}: code {code} is periodic (equal to one of its own rotations)")]
    /// A code equals one of its own rotations, so it cannot give a yaw.
    Periodic {
        /// The code's ID.
        id: u32,
        /// The code.
        code: u32,
    },
    #[error("ID {id}: code {code} is not stored as its smallest rotation {smallest}")]
    /// A code is not stored as its smallest rotation, as the spec requires.
    NotSmallestRotation {
        /// The code's ID.
        id: u32,
        /// The code as given.
        code: u32,
        /// Its smallest rotation.
        smallest: u32,
    },
    #[error("IDs {first} and {second} have the same code {code}")]
    /// Two IDs carry the same code.
    Duplicate {
        /// The first ID.
        first: u32,
        /// The second ID.
        second: u32,
        /// The code both carry.
        code: u32,
    },
    #[error(
        "IDs {first} and {second} are at cyclic distance {found}, below the family's distance {distance}"
    )]
    /// Two codes are closer under rotation than the family's distance.
    TooClose {
        /// The first ID.
        first: u32,
        /// The second ID.
        second: u32,
        /// Their smallest cyclic Hamming distance.
        found: u32,
        /// The family's distance.
        distance: u32,
    },
}

/// A family of marker codes: `codes[k]` is the code of ID k + 1. Every code
/// is the smallest rotation of an aperiodic necklace, and every two members
/// are at least `distance` apart under any rotation (checked on
/// construction, so every `Family` value keeps that promise). ID 0 is
/// reserved for "unknown".
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Family {
    bits: u32,
    distance: u32,
    codes: Vec<u32>,
    /// Indices into `codes` in increasing code order, for families whose
    /// codes are not already sorted (generated families always are).
    sorted_order: Option<Vec<u32>>,
}

impl Family {
    /// Builds the greedy family of the spec: integers 1..2^n in increasing
    /// order, accepting each aperiodic word whose every rotation keeps at
    /// least `distance` from every accepted code.
    pub fn generate(bits: u32, distance: u32) -> Result<Family, FamilyError> {
        check_parameters(bits, distance)?;
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
            sorted_order: None,
        })
    }

    /// A family from an explicit code list in ID order (e.g. a loaded family
    /// file, or a hand-picked subset). Every code must be the smallest
    /// rotation of an aperiodic `bits`-bit word, and every two codes must be
    /// at least `distance` apart under any rotation. Costs about as much as
    /// generating a family of the same size.
    pub fn from_codes(bits: u32, distance: u32, codes: Vec<u32>) -> Result<Family, FamilyError> {
        check_parameters(bits, distance)?;
        if codes.is_empty() {
            return Err(FamilyError::Empty);
        }
        for (index, &code) in codes.iter().enumerate() {
            let id = index as u32 + 1;
            if code > mask(bits) {
                return Err(FamilyError::CodeRange { id, code, bits });
            }
            if is_periodic(code, bits) {
                return Err(FamilyError::Periodic { id, code });
            }
            let (smallest, _) = min_rotation(code, bits);
            if smallest != code {
                return Err(FamilyError::NotSmallestRotation { id, code, smallest });
            }
        }
        let sorted_order = if codes.windows(2).all(|w| w[0] < w[1]) {
            None
        } else {
            let mut order: Vec<u32> = (0..codes.len() as u32).collect();
            order.sort_by_key(|&k| (codes[k as usize], k));
            if let Some(w) = order
                .windows(2)
                .find(|w| codes[w[0] as usize] == codes[w[1] as usize])
            {
                return Err(FamilyError::Duplicate {
                    first: w[0] + 1,
                    second: w[1] + 1,
                    code: codes[w[0] as usize],
                });
            }
            Some(order)
        };
        if let Some((i, j, found)) = stats::closest_pair(bits, &codes, 1, distance - 1) {
            return Err(FamilyError::TooClose {
                first: i as u32 + 1,
                second: j as u32 + 1,
                found,
                distance,
            });
        }
        Ok(Family {
            bits,
            distance,
            codes,
            sorted_order,
        })
    }

    /// Code length n: the ring has 2n sectors (Manchester encoding).
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The minimum cyclic Hamming distance the family was built for.
    pub fn distance(&self) -> u32 {
        self.distance
    }

    /// Number of members (IDs 1..=len).
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    /// Whether the family has no members (for the `len` convention).
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
        match &self.sorted_order {
            // Generated codes are accepted in increasing order.
            None => self.codes.binary_search(&code).ok().map(|k| k as u32 + 1),
            Some(order) => order
                .binary_search_by_key(&code, |&k| self.codes[k as usize])
                .ok()
                .map(|pos| order[pos] + 1),
        }
    }

    /// The correction radius the family's distance guarantees.
    pub fn default_correction_radius(&self) -> u32 {
        (self.distance - 1) / 2
    }
}

fn check_parameters(bits: u32, distance: u32) -> Result<(), FamilyError> {
    if !(MIN_BITS..=MAX_BITS).contains(&bits) {
        return Err(FamilyError::Bits(bits));
    }
    if distance == 0 || distance > bits {
        return Err(FamilyError::Distance { bits, distance });
    }
    Ok(())
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
