//! How many IDs each (bits, distance) family holds: the matrix behind
//! `whycode ids --counts`, Python's `family_counts` and the page's table.

use super::FamilyError;
use super::{Family, MAX_BITS, MIN_BITS};

/// A count table that cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum CountsError {
    /// A bit count outside the families this crate makes.
    #[error("{0} is outside {MIN_BITS}..{MAX_BITS}")]
    Bits(u32),
    /// A distance no family of the table's bit counts has.
    #[error("{distance} is outside 1..{max_bits} (1 to the largest bit count)")]
    Distance {
        /// The distance asked for.
        distance: u32,
        /// The table's largest bit count.
        max_bits: u32,
    },
    /// A family that could not be generated.
    #[error(transparent)]
    Family(FamilyError),
}

/// Family sizes for every bit count and distance asked for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CountTable {
    /// Bit counts, one column each, in the order asked for.
    pub bits: Vec<u32>,
    /// Distances, one row each, in the order asked for.
    pub distances: Vec<u32>,
    /// `counts[row][column]`: IDs of the `bits[column]`-bit family with
    /// distance `distances[row]`; `None` where the distance exceeds the
    /// bit count (no such family).
    pub counts: Vec<Vec<Option<usize>>>,
}

impl CountTable {
    /// Generates every family of the table.
    pub fn new(bits: &[u32], distances: &[u32]) -> Result<CountTable, CountsError> {
        if let Some(&n) = bits.iter().find(|n| !(MIN_BITS..=MAX_BITS).contains(*n)) {
            return Err(CountsError::Bits(n));
        }
        let max_bits = bits.iter().max().copied().unwrap_or(0);
        if let Some(&d) = distances.iter().find(|&&d| d == 0 || d > max_bits) {
            return Err(CountsError::Distance {
                distance: d,
                max_bits,
            });
        }
        let counts = distances
            .iter()
            .map(|&d| {
                bits.iter()
                    .map(|&n| {
                        Ok(if d <= n {
                            Some(Family::generate(n, d).map_err(CountsError::Family)?.len())
                        } else {
                            None
                        })
                    })
                    .collect::<Result<Vec<_>, CountsError>>()
            })
            .collect::<Result<Vec<_>, CountsError>>()?;
        Ok(CountTable {
            bits: bits.to_vec(),
            distances: distances.to_vec(),
            counts,
        })
    }

    /// Every family that exists, bit count by bit count: ((bits, distance), IDs).
    pub fn entries(&self) -> impl Iterator<Item = ((u32, u32), usize)> + '_ {
        self.bits.iter().enumerate().flat_map(move |(column, &n)| {
            self.distances
                .iter()
                .zip(&self.counts)
                .filter_map(move |(&d, row)| row[column].map(|count| ((n, d), count)))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{CountTable, CountsError};

    #[test]
    fn the_table_leaves_out_distances_above_the_bit_count() {
        let table = CountTable::new(&[4, 8], &[2, 5]).unwrap();
        assert_eq!(table.counts[1][0], None);
        assert_eq!(table.counts[0][1], Some(16));
        let entries: Vec<_> = table.entries().collect();
        assert_eq!(entries.len(), 3);
        assert_eq!(entries[1], ((8, 2), 16));
        assert!(CountTable::new(&[8], &[9]).is_err());
        let err = CountTable::new(&[1], &[1]).unwrap_err();
        assert!(matches!(err, CountsError::Bits(1)), "{err:?}");
        // The front ends' message names the option, as spec maps it.
        let message = crate::spec::SpecError::from(err).to_string();
        assert!(message.starts_with("bits: 1 is outside"), "{message}");
    }
}
