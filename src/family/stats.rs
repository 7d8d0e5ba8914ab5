//! How robust a family is: the distance actually achieved between members
//! and each code's distance to its own rotations.

use super::necklace::{cyclic_distance, masks_with_ones, min_rotation, rotl, self_distance};
use super::Family;

/// Figures that describe a family's robustness.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FamilyStats {
    /// Number of members.
    pub count: usize,
    /// Smallest cyclic Hamming distance between two different members
    /// (`None` for a family of one).
    pub min_distance: Option<u32>,
    /// Smallest self-distance over all members: the family's least certain yaw.
    pub min_self_distance: u32,
    /// Self-distance of each code, in ID order.
    pub self_distances: Vec<u32>,
}

impl Family {
    /// Minimum Hamming distance between the code of `id` and its own
    /// non-trivial rotations. A misreading of that many bits can turn the
    /// marker's yaw by a multiple of 360°/n without changing its ID.
    pub fn self_distance(&self, id: u32) -> Option<u32> {
        self.code(id).map(|code| self_distance(code, self.bits))
    }

    /// Self-distance of every code, in ID order.
    pub fn self_distances(&self) -> Vec<u32> {
        self.codes
            .iter()
            .map(|&code| self_distance(code, self.bits))
            .collect()
    }

    /// The worst (smallest) self-distance in the family.
    pub fn min_self_distance(&self) -> u32 {
        self.codes
            .iter()
            .map(|&code| self_distance(code, self.bits))
            .min()
            .unwrap_or(0)
    }

    /// The smallest cyclic distance between two different members, which is
    /// at least [`Family::distance`]; `None` when the family has one member.
    pub fn min_distance(&self) -> Option<u32> {
        self.closest_pair().map(|(_, _, d)| d)
    }

    /// Two IDs (smaller first) at the family's smallest cyclic distance, and
    /// that distance.
    pub fn closest_pair(&self) -> Option<(u32, u32, u32)> {
        closest_pair(self.bits, &self.codes, self.distance, self.bits)
            .map(|(i, j, d)| (i as u32 + 1, j as u32 + 1, d))
    }

    /// All statistics at once.
    pub fn stats(&self) -> FamilyStats {
        let self_distances = self.self_distances();
        FamilyStats {
            count: self.len(),
            min_distance: self.min_distance(),
            min_self_distance: self_distances.iter().copied().min().unwrap_or(0),
            self_distances,
        }
    }
}

/// Finds two codes at the smallest cyclic distance within `lower..=upper`,
/// given that no two codes are closer than `lower` (and none are equal).
/// Returns their indices (smaller first) and the distance.
///
/// Comparing all pairs costs count²/2·n; for large families it is far
/// cheaper to walk outwards from every code one Hamming shell at a time and
/// look each word up in a bitset of all member rotations: shell k costs
/// count·C(n, k), and the walk stops at the first shell that hits another
/// member. Each shell picks whichever of the two is cheaper.
pub(crate) fn closest_pair(
    bits: u32,
    codes: &[u32],
    lower: u32,
    upper: u32,
) -> Option<(usize, usize, u32)> {
    let count = codes.len() as u64;
    if count < 2 || lower > upper {
        return None;
    }
    let pairwise_cost = count * (count - 1) / 2 * u64::from(bits);
    let mut members: Option<MemberIndex> = None;
    for k in lower.max(1)..=upper {
        let shell_cost = count * binomial(bits, k);
        if shell_cost > pairwise_cost {
            return closest_pair_by_pairs(bits, codes, k, upper);
        }
        let members = members.get_or_insert_with(|| MemberIndex::new(bits, codes));
        for (i, &code) in codes.iter().enumerate() {
            for m in masks_with_ones(bits, k) {
                let word = code ^ m;
                if !members.contains_rotation(word) {
                    continue;
                }
                let j = members.index_of(min_rotation(word, bits).0);
                // A word can also be a rotation of the code itself.
                if j != i {
                    return Some((i.min(j), i.max(j), k));
                }
            }
        }
    }
    None
}

fn closest_pair_by_pairs(
    bits: u32,
    codes: &[u32],
    lower: u32,
    upper: u32,
) -> Option<(usize, usize, u32)> {
    let mut best: Option<(usize, usize, u32)> = None;
    for (i, &a) in codes.iter().enumerate() {
        for (j, &b) in codes.iter().enumerate().skip(i + 1) {
            let d = cyclic_distance(a, b, bits);
            if d <= upper && best.is_none_or(|(_, _, e)| d < e) {
                best = Some((i, j, d));
                if d <= lower {
                    return best;
                }
            }
        }
    }
    best
}

/// Every rotation of every member in a bitset, plus a code → index map.
struct MemberIndex {
    rotations: Vec<u64>,
    by_code: Vec<(u32, u32)>,
}

impl MemberIndex {
    fn new(bits: u32, codes: &[u32]) -> MemberIndex {
        let mut rotations = vec![0u64; (1usize << bits).div_ceil(64)];
        for &code in codes {
            for r in 0..bits {
                let w = rotl(code, bits, r);
                rotations[(w >> 6) as usize] |= 1 << (w & 63);
            }
        }
        let mut by_code: Vec<(u32, u32)> = codes
            .iter()
            .enumerate()
            .map(|(k, &c)| (c, k as u32))
            .collect();
        by_code.sort_unstable();
        MemberIndex { rotations, by_code }
    }

    fn contains_rotation(&self, word: u32) -> bool {
        self.rotations[(word >> 6) as usize] >> (word & 63) & 1 == 1
    }

    fn index_of(&self, code: u32) -> usize {
        let pos = self
            .by_code
            .binary_search_by_key(&code, |&(c, _)| c)
            .expect("a word in the rotation set has a member as its smallest rotation");
        self.by_code[pos].1 as usize
    }
}

fn binomial(n: u32, k: u32) -> u64 {
    if k > n {
        return 0;
    }
    (0..k).fold(1u64, |acc, i| acc * u64::from(n - i) / u64::from(i + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_min_distance(bits: u32, codes: &[u32]) -> Option<u32> {
        let mut best = None;
        for (i, &a) in codes.iter().enumerate() {
            for &b in &codes[i + 1..] {
                let d = cyclic_distance(a, b, bits);
                best = Some(best.map_or(d, |e: u32| e.min(d)));
            }
        }
        best
    }

    #[test]
    fn min_distance_matches_all_pairs() {
        for bits in 2..=12 {
            for d in 1..=bits {
                let f = Family::generate(bits, d).unwrap();
                let expected = brute_min_distance(bits, f.codes());
                assert_eq!(f.min_distance(), expected, "n={bits} d={d}");
                if let Some((a, b, dist)) = f.closest_pair() {
                    let (ca, cb) = (f.code(a).unwrap(), f.code(b).unwrap());
                    assert!(a < b);
                    assert_eq!(cyclic_distance(ca, cb, bits), dist);
                }
            }
        }
    }

    #[test]
    fn both_search_strategies_agree() {
        // A family with members far apart, where the shell walk has to
        // cross several empty shells before its first hit.
        let f = Family::generate(14, 6).unwrap();
        let shells = {
            let members = MemberIndex::new(14, f.codes());
            let mut found = None;
            'outer: for k in 1..=14 {
                for (i, &code) in f.codes().iter().enumerate() {
                    for m in masks_with_ones(14, k) {
                        let w = code ^ m;
                        if members.contains_rotation(w) {
                            let j = members.index_of(min_rotation(w, 14).0);
                            if j != i {
                                found = Some(k);
                                break 'outer;
                            }
                        }
                    }
                }
            }
            found
        };
        let pairs = closest_pair_by_pairs(14, f.codes(), 1, 14).map(|p| p.2);
        assert_eq!(shells, pairs);
        assert_eq!(f.min_distance(), pairs);
    }

    #[test]
    fn self_distance_of_known_codes() {
        let f = Family::generate(8, 2).unwrap();
        // 00000001 differs from each rotation in two places.
        assert_eq!(f.self_distance(1), Some(2));
        // 00000111 against 00001110: two places.
        assert_eq!(f.self_distance(2), Some(2));
        assert_eq!(f.self_distance(0), None);
        assert_eq!(f.min_self_distance(), 2);
        let stats = f.stats();
        assert_eq!(stats.count, 16);
        assert_eq!(stats.min_distance, Some(2));
        assert_eq!(stats.self_distances.len(), 16);
    }
}
