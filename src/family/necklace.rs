//! Bit-level operations on n-bit cyclic words (n <= 32).
//!
//! Bit i of a code word (i = 0 first) is bit number n-1-i of the integer, so a
//! left rotation moves every bit one place earlier around the ring.

/// All-ones mask of `bits` bits.
#[inline]
pub fn mask(bits: u32) -> u32 {
    if bits >= 32 {
        u32::MAX
    } else {
        (1u32 << bits) - 1
    }
}

/// Rotates an n-bit word left by `r` places (towards the most significant bit).
#[inline]
pub fn rotl(word: u32, bits: u32, r: u32) -> u32 {
    let r = r % bits;
    if r == 0 {
        return word;
    }
    ((word << r) | (word >> (bits - r))) & mask(bits)
}

/// Rotates an n-bit word right by `r` places.
#[inline]
pub fn rotr(word: u32, bits: u32, r: u32) -> u32 {
    rotl(word, bits, bits - r % bits)
}

/// The smallest rotation of `word` and the left rotation that produces it
/// (the smallest such rotation when several do).
pub fn min_rotation(word: u32, bits: u32) -> (u32, u32) {
    let mut best = word;
    let mut best_r = 0;
    for r in 1..bits {
        let w = rotl(word, bits, r);
        if w < best {
            best = w;
            best_r = r;
        }
    }
    (best, best_r)
}

/// True when the word equals one of its own non-trivial rotations.
pub fn is_periodic(word: u32, bits: u32) -> bool {
    // A word's smallest period divides n, so only the rotations by n/p for
    // prime p need checking.
    let mut m = bits;
    let mut p = 2;
    while p * p <= m {
        if m.is_multiple_of(p) {
            if rotl(word, bits, bits / p) == word {
                return true;
            }
            while m.is_multiple_of(p) {
                m /= p;
            }
        }
        p += 1;
    }
    m > 1 && rotl(word, bits, bits / m) == word
}

/// Minimum Hamming distance between `a` and any rotation of `b`.
pub fn cyclic_distance(a: u32, b: u32, bits: u32) -> u32 {
    (0..bits)
        .map(|r| (a ^ rotl(b, bits, r)).count_ones())
        .min()
        .unwrap_or(0)
}

/// Minimum Hamming distance between a word and its own non-trivial rotations:
/// how far apart the candidate yaw readings of this code are.
pub fn self_distance(word: u32, bits: u32) -> u32 {
    (1..bits)
        .map(|r| (word ^ rotl(word, bits, r)).count_ones())
        .min()
        .unwrap_or(0)
}

/// Number of n-bit words within Hamming distance `radius` of a word.
pub fn ball_size(bits: u32, radius: u32) -> u64 {
    let mut total = 0u64;
    let mut binom = 1u64;
    for k in 0..=radius.min(bits) {
        total += binom;
        binom = binom * u64::from(bits - k) / u64::from(k + 1);
    }
    total
}

/// Calls `f` with every n-bit mask that has exactly `ones` bits set
/// (Gosper's hack), in increasing order.
pub fn for_each_mask_with_ones(bits: u32, ones: u32, mut f: impl FnMut(u32)) {
    if ones > bits {
        return;
    }
    if ones == 0 {
        f(0);
        return;
    }
    let limit: u64 = 1u64 << bits;
    let mut m: u64 = (1u64 << ones) - 1;
    while m < limit {
        f(m as u32);
        let c = m & m.wrapping_neg();
        let r = m + c;
        m = (((r ^ m) >> 2) / c) | r;
    }
}

/// The n-bit masks with exactly `ones` bits set, in increasing order (an
/// iterator twin of [`for_each_mask_with_ones`] for searches that stop early).
pub fn masks_with_ones(bits: u32, ones: u32) -> MasksWithOnes {
    let limit = 1u64 << bits;
    let next = if ones > bits {
        limit
    } else {
        (1u64 << ones) - 1
    };
    MasksWithOnes {
        next,
        limit,
        done: false,
    }
}

/// Iterator returned by [`masks_with_ones`].
#[derive(Debug, Clone)]
pub struct MasksWithOnes {
    next: u64,
    limit: u64,
    done: bool,
}

impl Iterator for MasksWithOnes {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.done || self.next >= self.limit {
            return None;
        }
        let m = self.next;
        if m == 0 {
            self.done = true;
        } else {
            let c = m & m.wrapping_neg();
            let r = m + c;
            self.next = (((r ^ m) >> 2) / c) | r;
        }
        Some(m as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_round_trip() {
        for bits in 2..=24 {
            let w = 0x00b5_a5c3 & mask(bits);
            for r in 0..bits {
                assert_eq!(rotr(rotl(w, bits, r), bits, r), w);
            }
        }
    }

    #[test]
    fn periodicity_matches_brute_force() {
        for bits in 2..=12 {
            for w in 0..(1u32 << bits) {
                let brute = (1..bits).any(|r| rotl(w, bits, r) == w);
                assert_eq!(is_periodic(w, bits), brute, "w={w} bits={bits}");
            }
        }
    }

    #[test]
    fn masks_are_enumerated_once() {
        let mut seen = Vec::new();
        for_each_mask_with_ones(6, 2, |m| seen.push(m));
        assert_eq!(seen.len(), 15);
        assert!(seen.iter().all(|m| m.count_ones() == 2 && *m < 64));
        assert_eq!(ball_size(6, 2), 1 + 6 + 15);
        for bits in 1..=8 {
            for ones in 0..=bits + 1 {
                let mut expected = Vec::new();
                for_each_mask_with_ones(bits, ones, |m| expected.push(m));
                let got: Vec<u32> = masks_with_ones(bits, ones).collect();
                assert_eq!(got, expected, "bits={bits} ones={ones}");
            }
        }
    }
}
