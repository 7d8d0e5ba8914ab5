//! Decoding ring readings into family members.
//!
//! Convention shared with the renderer and the detector: a marker rotated
//! counter-clockwise by `m` bit steps (m·360°/n) is read, starting at image
//! angle 0, as `rotr(code, m)`. The decoder returns the left rotation `m`
//! with `rotl(word, m) == code`, so the marker's yaw is m·360°/n plus the
//! measured edge phase.

use super::necklace::{ball_size, for_each_mask_with_ones, min_rotation, rotl, rotr};
use super::Family;

/// Largest bit count that gets a dense table (2^20 entries, 4 MiB).
pub const DENSE_MAX_BITS: u32 = 20;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
/// How a ring reading matched the family.
pub enum MatchStatus {
    /// The word is a rotation of a member.
    Exact,
    /// The word is within the correction radius of exactly one member rotation.
    Corrected,
    /// Two or more members are equally close: no answer.
    Ambiguous,
    /// No member rotation within the correction radius.
    Rejected,
}

/// The result of decoding one ring reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decoded {
    /// How the word matched.
    pub status: MatchStatus,
    /// The member's ID, or 0 unless the status is `Exact` or `Corrected`.
    pub id: u32,
    /// The member's code, or 0 when `id` is 0.
    pub code: u32,
    /// Left rotation that maps the word onto the member's code (the smallest
    /// of the tied ones when `rotation_ambiguous`).
    pub rotation: u32,
    /// The member is certain but two of its rotations are equally close to
    /// the word (a code with a small self-distance, read with an error):
    /// the ID stands, the yaw does not.
    pub rotation_ambiguous: bool,
    /// Hamming distance between the rotated word and the code (for
    /// `Ambiguous`, the distance of the tied matches; for `Rejected`, 0).
    pub distance: u32,
}

impl Decoded {
    fn rejected() -> Decoded {
        Decoded {
            status: MatchStatus::Rejected,
            id: 0,
            code: 0,
            rotation: 0,
            rotation_ambiguous: false,
            distance: 0,
        }
    }

    fn ambiguous(distance: u32) -> Decoded {
        Decoded {
            status: MatchStatus::Ambiguous,
            distance,
            ..Decoded::rejected()
        }
    }

    /// True when the word names a member (exactly or after correction).
    pub fn is_member(&self) -> bool {
        matches!(self.status, MatchStatus::Exact | MatchStatus::Corrected)
    }
}

/// Decodes n-bit words into (ID, rotation).
///
/// Up to [`DENSE_MAX_BITS`] bits every answer is precomputed in a table
/// (4 bytes per word, 4 MiB at 20 bits): a decode is one lookup. Above
/// that a table would take 64 MiB, so the decoder keeps a bitset of all
/// member rotations (2^n bits, 2 MiB at 24 bits) and searches:
/// it walks the Hamming ball of the word, one bitset probe per neighbour,
/// or, when that ball is larger than the family, compares against every
/// member rotation. The search is slowest where the ball and the family are
/// about equally large; per-word times (a mix of exact, 1- and 2-bit-error
/// and random readings) are measured by `cargo bench --bench family`
/// (`decode_1000_words`), building the decoder by `decoder_build`.
#[derive(Debug, Clone)]
pub struct Decoder {
    family: Family,
    radius: u32,
    table: Option<Vec<u32>>,
    /// For the search above the dense limit: bit w is set when word w is a
    /// rotation of a member.
    rotations: Vec<u64>,
}

// Dense entry layout: 0 means rejected; otherwise bits 0..20 hold the ID
// (a 20-bit family has at most 2^20/20 members), bit 20 marks a tie between
// rotations of that one member, 21..26 the rotation, 26..31 the distance and
// bit 31 a tie between different members.
const ID_BITS: u32 = 20;
const ID_MASK: u32 = (1 << ID_BITS) - 1;
const ROTATION_TIE_BIT: u32 = 1 << ID_BITS;
const ROT_SHIFT: u32 = 21;
const ROT_MASK: u32 = 31 << ROT_SHIFT;
const DIST_SHIFT: u32 = 26;
const TIE_BIT: u32 = 1 << 31;

impl Decoder {
    /// A decoder correcting up to the family's guaranteed radius floor((d-1)/2).
    pub fn new(family: &Family) -> Decoder {
        Decoder::with_radius(family, family.default_correction_radius())
    }

    /// A decoder with an explicit correction radius. Radii above the
    /// guaranteed one can return `Ambiguous` where members' balls overlap.
    pub fn with_radius(family: &Family, radius: u32) -> Decoder {
        let radius = radius.min(family.bits());
        if family.bits() <= DENSE_MAX_BITS {
            Decoder {
                family: family.clone(),
                radius,
                table: Some(dense_table(family, radius)),
                rotations: Vec::new(),
            }
        } else {
            Decoder::searching(family, radius)
        }
    }

    fn searching(family: &Family, radius: u32) -> Decoder {
        let bits = family.bits();
        let mut rotations = vec![0u64; (1usize << bits).div_ceil(64)];
        for &code in family.codes() {
            for r in 0..bits {
                let w = rotl(code, bits, r);
                rotations[(w >> 6) as usize] |= 1 << (w & 63);
            }
        }
        Decoder {
            family: family.clone(),
            radius,
            table: None,
            rotations,
        }
    }

    fn is_member_rotation(&self, word: u32) -> bool {
        self.rotations[(word >> 6) as usize] >> (word & 63) & 1 == 1
    }

    /// The family the decoder was built for.
    pub fn family(&self) -> &Family {
        &self.family
    }

    /// How many bit errors a reading may have and still be corrected (by
    /// default floor((d-1)/2), the most the family's distance guarantees).
    pub fn radius(&self) -> u32 {
        self.radius
    }

    /// Decodes one ring reading (any rotation) to a member, its status telling whether it was exact, corrected or refused.
    pub fn decode(&self, word: u32) -> Decoded {
        let bits = self.family.bits();
        let word = word & super::necklace::mask(bits);
        match &self.table {
            Some(table) => {
                let e = table[word as usize];
                if e == 0 {
                    return Decoded::rejected();
                }
                let distance = (e >> DIST_SHIFT) & 31;
                if e & TIE_BIT != 0 {
                    return Decoded::ambiguous(distance);
                }
                let rotation_tie = e & ROTATION_TIE_BIT != 0;
                self.member(e & ID_MASK, (e >> ROT_SHIFT) & 31, distance, rotation_tie)
            }
            None => self.search(word),
        }
    }

    fn member(&self, id: u32, rotation: u32, distance: u32, rotation_ambiguous: bool) -> Decoded {
        Decoded {
            status: if distance == 0 {
                MatchStatus::Exact
            } else {
                MatchStatus::Corrected
            },
            id,
            code: self.family.code(id).unwrap_or(0),
            rotation,
            rotation_ambiguous,
            distance,
        }
    }

    /// The member and rotation when `word` is exactly a member rotation.
    fn member_rotation(&self, word: u32) -> Option<(u32, u32)> {
        if !self.is_member_rotation(word) {
            return None;
        }
        let (min, r) = min_rotation(word, self.family.bits());
        self.family.id_of(min).map(|id| (id, r))
    }

    fn search(&self, word: u32) -> Decoded {
        let bits = self.family.bits();
        if let Some((id, r)) = self.member_rotation(word) {
            return self.member(id, r, 0, false);
        }
        // A bitset probe costs about as much as two XOR-popcount comparisons.
        let ball_cost = ball_size(bits, self.radius).saturating_mul(2);
        let scan_cost = self.family.len() as u64 * u64::from(bits);
        if ball_cost <= scan_cost {
            for k in 1..=self.radius {
                let mut found: Option<(u32, u32)> = None;
                let mut tie = false;
                let mut rotation_tie = false;
                for_each_mask_with_ones(bits, k, |m| {
                    if let Some((id, r)) = self.member_rotation(word ^ m) {
                        match found {
                            None => found = Some((id, r)),
                            Some((prev, _)) if prev != id => tie = true,
                            Some((prev_id, prev)) if prev != r => {
                                rotation_tie = true;
                                found = Some((prev_id, prev.min(r)));
                            }
                            _ => {}
                        }
                    }
                });
                match (found, tie) {
                    (Some(_), true) => return Decoded::ambiguous(k),
                    (Some((id, r)), false) => return self.member(id, r, k, rotation_tie),
                    _ => {}
                }
            }
            Decoded::rejected()
        } else {
            let mut best = u32::MAX;
            let mut best_match = (0, 0);
            let mut tie = false;
            let mut rotation_tie = false;
            for (k, &code) in self.family.codes().iter().enumerate() {
                let id = k as u32 + 1;
                for r in 0..bits {
                    let d = (rotl(word, bits, r) ^ code).count_ones();
                    if d < best {
                        best = d;
                        best_match = (id, r);
                        tie = false;
                        rotation_tie = false;
                    } else if d == best {
                        if id == best_match.0 {
                            rotation_tie = true;
                        } else {
                            tie = true;
                        }
                    }
                }
            }
            if best > self.radius {
                Decoded::rejected()
            } else if tie {
                Decoded::ambiguous(best)
            } else {
                self.member(best_match.0, best_match.1, best, rotation_tie)
            }
        }
    }
}

fn dense_table(family: &Family, radius: u32) -> Vec<u32> {
    let bits = family.bits();
    // Stamping every ball costs count·n·ball(radius), which overlapping
    // balls (a large radius, or close rotations of one code) can push far
    // beyond the 2^n·n of a breadth-first sweep that visits each word once.
    let ball_cost = (family.len() as u64)
        .saturating_mul(u64::from(bits))
        .saturating_mul(ball_size(bits, radius));
    let sweep_cost = (1u64 << bits) * u64::from(bits);
    if ball_cost <= sweep_cost {
        dense_table_by_balls(family, radius)
    } else {
        dense_table_by_sweep(family, radius)
    }
}

fn dense_table_by_balls(family: &Family, radius: u32) -> Vec<u32> {
    let bits = family.bits();
    let mut table = vec![0u32; 1usize << bits];
    // Fill layer by layer so that every word keeps its nearest member; a
    // second member at the same distance marks a tie, another rotation of
    // the same member a rotation tie.
    for k in 0..=radius {
        for (index, &code) in family.codes().iter().enumerate() {
            let id = index as u32 + 1;
            for r in 0..bits {
                let base = rotr(code, bits, r);
                let entry = id | (r << ROT_SHIFT) | (k << DIST_SHIFT);
                for_each_mask_with_ones(bits, k, |m| {
                    let slot = &mut table[(base ^ m) as usize];
                    if *slot == 0 {
                        *slot = entry;
                    } else if (*slot >> DIST_SHIFT) & 31 == k {
                        *slot = merge_tie(*slot, entry);
                    }
                });
            }
        }
    }
    table
}

/// Breadth-first from all member rotations at once: the words at distance k
/// are the unvisited neighbours of the words at distance k - 1, and their
/// nearest matches are the union of those neighbours' matches.
fn dense_table_by_sweep(family: &Family, radius: u32) -> Vec<u32> {
    const MATCH_MASK: u32 = ID_MASK | ROTATION_TIE_BIT | ROT_MASK;
    let bits = family.bits();
    let mut table = vec![0u32; 1usize << bits];
    let mut frontier = Vec::with_capacity(family.len() * bits as usize);
    for (index, &code) in family.codes().iter().enumerate() {
        let id = index as u32 + 1;
        for r in 0..bits {
            let word = rotr(code, bits, r);
            table[word as usize] = id | (r << ROT_SHIFT);
            frontier.push(word);
        }
    }
    let mut next = Vec::new();
    for k in 1..=radius {
        for &word in &frontier {
            let from = table[word as usize];
            let spread = (from & (MATCH_MASK | TIE_BIT)) | (k << DIST_SHIFT);
            for b in 0..bits {
                let neighbour = word ^ (1 << b);
                let slot = &mut table[neighbour as usize];
                if *slot == 0 {
                    *slot = spread;
                    next.push(neighbour);
                } else if (*slot >> DIST_SHIFT) & 31 == k {
                    *slot = merge_tie(*slot, spread);
                }
            }
        }
        std::mem::swap(&mut frontier, &mut next);
        next.clear();
        if frontier.is_empty() {
            break;
        }
    }
    table
}

/// A word's entry once `incoming` reaches it at the same distance as the
/// match it already holds (`held`). Different members make a tie; two
/// rotations of one member a rotation tie that keeps the smaller rotation, so
/// that every way of building the table (and the search) gives one answer.
fn merge_tie(held: u32, incoming: u32) -> u32 {
    if (held | incoming) & TIE_BIT != 0 || held & ID_MASK != incoming & ID_MASK {
        return held | TIE_BIT;
    }
    let rotation_tie =
        (held | incoming) & ROTATION_TIE_BIT != 0 || held & ROT_MASK != incoming & ROT_MASK;
    if !rotation_tie {
        return held;
    }
    let rotation = (held & ROT_MASK).min(incoming & ROT_MASK);
    (held & !ROT_MASK) | rotation | ROTATION_TIE_BIT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rotation_decodes_exactly() {
        for (bits, d) in [(8, 2), (12, 3), (22, 5)] {
            let f = Family::generate(bits, d).unwrap();
            let dec = Decoder::new(&f);
            for (k, &code) in f.codes().iter().enumerate().step_by(7) {
                for r in 0..bits {
                    let got = dec.decode(rotr(code, bits, r));
                    assert_eq!(got.status, MatchStatus::Exact);
                    assert_eq!((got.id, got.rotation, got.distance), (k as u32 + 1, r, 0));
                }
            }
        }
    }

    /// The nearest member rotations by exhaustive comparison.
    fn oracle(family: &Family, radius: u32, word: u32) -> Decoded {
        let bits = family.bits();
        let mut best = u32::MAX;
        let mut matches = Vec::new();
        for (k, &code) in family.codes().iter().enumerate() {
            for r in 0..bits {
                let d = (rotl(word, bits, r) ^ code).count_ones();
                if d < best {
                    best = d;
                    matches.clear();
                }
                if d == best {
                    matches.push((k as u32 + 1, r));
                }
            }
        }
        if best > radius {
            Decoded::rejected()
        } else if matches.iter().any(|m| m.0 != matches[0].0) {
            Decoded::ambiguous(best)
        } else {
            Decoded {
                status: if best == 0 {
                    MatchStatus::Exact
                } else {
                    MatchStatus::Corrected
                },
                id: matches[0].0,
                code: family.code(matches[0].0).unwrap(),
                rotation: matches.iter().map(|m| m.1).min().unwrap(),
                rotation_ambiguous: matches.len() > 1,
                distance: best,
            }
        }
    }

    #[test]
    fn every_method_agrees_with_exhaustive_comparison() {
        for bits in 2..=10 {
            for d in 1..=bits {
                let f = Family::generate(bits, d).unwrap();
                let guaranteed = f.default_correction_radius();
                for radius in [guaranteed, guaranteed + 1, bits] {
                    // A tie between members names nobody: the rest of its entry is free.
                    let settled = |table: Vec<u32>| -> Vec<u32> {
                        let tie = |e: u32| e & TIE_BIT != 0;
                        table
                            .into_iter()
                            .map(|e| {
                                if tie(e) {
                                    e & (TIE_BIT | (31 << DIST_SHIFT))
                                } else {
                                    e
                                }
                            })
                            .collect()
                    };
                    let balls = settled(dense_table_by_balls(&f, radius));
                    let sweep = settled(dense_table_by_sweep(&f, radius));
                    assert_eq!(balls, sweep, "n={bits} d={d} radius={radius}");
                    let dense = Decoder::with_radius(&f, radius);
                    let sparse = Decoder::searching(&f, radius);
                    for word in 0..(1u32 << bits) {
                        let expected = oracle(&f, radius, word);
                        let context = format!("n={bits} d={d} radius={radius} word={word:b}");
                        assert_eq!(dense.decode(word), expected, "dense {context}");
                        assert_eq!(sparse.decode(word), expected, "sparse {context}");
                    }
                }
            }
        }
    }

    #[test]
    fn large_words_decode_like_exhaustive_comparison() {
        // Above the dense limit: both the ball walk (small radius) and the
        // member scan (large radius) against the oracle on sampled words.
        for (bits, d, radius) in [(22, 3, 1), (22, 7, 3), (24, 5, 2), (24, 11, 11), (21, 2, 1)] {
            let f = Family::generate(bits, d).unwrap();
            let dec = Decoder::with_radius(&f, radius);
            assert!(dec.table.is_none());
            let mut state = 0x2545_f491_4f6c_dd1du64;
            for i in 0..300u32 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let code = f.codes()[(state % f.len() as u64) as usize];
                // Mostly words near members, where the answers are interesting.
                let flips = (state >> 32) as u32 % (radius + 2);
                let mut word = rotr(code, bits, i % bits);
                for j in 0..flips {
                    word ^= 1 << ((state >> (8 + 5 * j)) as u32 % bits);
                }
                if i % 10 == 0 {
                    word = (state >> 20) as u32 & crate::family::necklace::mask(bits);
                }
                assert_eq!(
                    dec.decode(word),
                    oracle(&f, radius, word),
                    "n={bits} d={d} radius={radius} word={word:b}"
                );
            }
        }
    }

    #[test]
    fn a_tie_between_rotations_of_one_member_keeps_the_id() {
        // n = 8, d = 3: a single-bit error often lies as close to two
        // rotations of the same code; the ID is certain, only the yaw is not.
        let f = Family::generate(8, 3).unwrap();
        let dense = Decoder::new(&f);
        let sparse = Decoder::searching(&f, dense.radius());
        let mut rotation_ties = 0;
        for (k, &code) in f.codes().iter().enumerate() {
            for b in 0..8 {
                let word = code ^ (1 << b);
                for dec in [&dense, &sparse] {
                    let got = dec.decode(word);
                    assert_eq!(got.status, MatchStatus::Corrected, "word {word:08b}");
                    assert_eq!(got.id, k as u32 + 1, "word {word:08b}");
                    rotation_ties += usize::from(got.rotation_ambiguous);
                }
            }
        }
        assert!(
            rotation_ties > 0,
            "the test no longer covers a rotation tie"
        );
    }

    #[test]
    fn periodic_words_are_rejected() {
        let f = Family::generate(8, 1).unwrap();
        let dec = Decoder::new(&f);
        for w in [0u32, 0xff, 0x55, 0x33, 0x11] {
            assert_eq!(dec.decode(w).id, 0, "word {w:#x}");
        }
    }
}
