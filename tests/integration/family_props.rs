//! Properties of generated families and their decoders, for random code
//! lengths and distances small enough to check against brute force.

use proptest::prelude::*;
use whycode::family::necklace::{cyclic_distance, is_periodic, min_rotation, rotl, rotr};
use whycode::family::{Decoded, Decoder, Family, MatchStatus};

fn bits_and_distance() -> impl Strategy<Value = (u32, u32)> {
    (2u32..=11).prop_flat_map(|n| (Just(n), 1..=n))
}

/// Nearest member rotations by comparing against every one of them.
fn nearest(family: &Family, word: u32) -> (u32, Vec<(u32, u32)>) {
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
    (best, matches)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn members_are_smallest_rotations_of_aperiodic_words((n, d) in bits_and_distance()) {
        let f = Family::generate(n, d).unwrap();
        prop_assert!(!f.is_empty());
        for (k, &code) in f.codes().iter().enumerate() {
            prop_assert!(!is_periodic(code, n), "code {code} periodic");
            prop_assert_eq!(min_rotation(code, n).0, code);
            prop_assert_eq!(f.id_of(code), Some(k as u32 + 1));
            prop_assert_eq!(f.code(k as u32 + 1), Some(code));
        }
        prop_assert_eq!(f.code(0), None);
        prop_assert_eq!(f.code(f.len() as u32 + 1), None);
    }

    #[test]
    fn every_pair_keeps_the_distance((n, d) in bits_and_distance()) {
        let f = Family::generate(n, d).unwrap();
        let mut smallest = None;
        for (i, &a) in f.codes().iter().enumerate() {
            for &b in &f.codes()[i + 1..] {
                let dist = cyclic_distance(a, b, n);
                prop_assert!(dist >= d, "codes {a} and {b} at distance {dist} < {d}");
                smallest = Some(smallest.map_or(dist, |s: u32| s.min(dist)));
            }
        }
        prop_assert_eq!(f.min_distance(), smallest);
        let self_distances = f.self_distances();
        for (k, &code) in f.codes().iter().enumerate() {
            let brute = (1..n).map(|r| (code ^ rotl(code, n, r)).count_ones()).min().unwrap();
            prop_assert_eq!(self_distances[k], brute);
        }
        prop_assert_eq!(f.min_self_distance(), *self_distances.iter().min().unwrap());
    }

    #[test]
    fn greedy_skips_only_necklaces_too_close_to_an_earlier_member((n, d) in bits_and_distance()) {
        // The spec's rule, word by word: an aperiodic necklace is left out
        // exactly when a member accepted before it is closer than d. This
        // gives both maximality and the reference's numbering.
        let f = Family::generate(n, d).unwrap();
        for c in 1..(1u32 << n) {
            if is_periodic(c, n) || min_rotation(c, n).0 != c {
                continue;
            }
            let blocked = f
                .codes()
                .iter()
                .take_while(|&&a| a < c)
                .any(|&a| cyclic_distance(a, c, n) < d);
            prop_assert_eq!(f.id_of(c).is_some(), !blocked, "necklace {}", c);
        }
    }

    #[test]
    fn every_rotation_of_every_member_decodes_exactly((n, d) in bits_and_distance()) {
        let f = Family::generate(n, d).unwrap();
        let decoder = Decoder::new(&f);
        for (k, &code) in f.codes().iter().enumerate() {
            for m in 0..n {
                let got = decoder.decode(rotr(code, n, m));
                prop_assert_eq!(got, Decoded {
                    status: MatchStatus::Exact,
                    id: k as u32 + 1,
                    code,
                    rotation: m,
                    rotation_ambiguous: false,
                    distance: 0,
                });
            }
        }
    }

    #[test]
    fn misreadings_within_the_radius_decode_to_the_right_member(
        (n, d) in bits_and_distance(),
        pick in any::<u64>(),
        shuffle in proptest::collection::vec(any::<u32>(), 11),
    ) {
        let f = Family::generate(n, d).unwrap();
        let decoder = Decoder::new(&f);
        let radius = decoder.radius();
        prop_assert_eq!(radius, (d - 1) / 2);
        let id = (pick % f.len() as u64) as u32 + 1;
        let m = ((pick >> 32) % u64::from(n)) as u32;
        // Flip `radius` distinct bits, picked by a partial shuffle.
        let mut positions: Vec<u32> = (0..n).collect();
        let mut error = 0u32;
        for i in 0..radius as usize {
            let j = i + shuffle[i] as usize % (n as usize - i);
            positions.swap(i, j);
            error |= 1 << positions[i];
        }
        let word = rotr(f.code(id).unwrap(), n, m) ^ error;
        let got = decoder.decode(word);
        let (best, matches) = nearest(&f, word);
        // Within the guaranteed radius no other member can be as close.
        prop_assert!(matches.iter().all(|&(other, _)| other == id));
        if matches.len() == 1 {
            let (expected_id, rotation) = matches[0];
            let status = if best == 0 { MatchStatus::Exact } else { MatchStatus::Corrected };
            prop_assert_eq!(got.status, status);
            prop_assert_eq!((got.id, got.rotation, got.distance), (expected_id, rotation, best));
            prop_assert!(!got.rotation_ambiguous);
            if best == error.count_ones() {
                // The misreading itself was undone: the right yaw too.
                prop_assert_eq!(got.rotation, m);
            }
        } else {
            // Two rotations of the same code equally close: the ID stands,
            // the yaw cannot be told, and the decoder says so.
            prop_assert_eq!(got.status, MatchStatus::Corrected);
            prop_assert_eq!((got.id, got.distance), (id, best));
            prop_assert!(got.rotation_ambiguous);
            let smallest = matches.iter().map(|m| m.1).min().unwrap();
            prop_assert_eq!(got.rotation, smallest);
        }
    }

    #[test]
    fn words_outside_the_family_never_name_a_member_at_radius_zero((n, d) in bits_and_distance()) {
        let f = Family::generate(n, d).unwrap();
        let decoder = Decoder::with_radius(&f, 0);
        for word in 0..(1u32 << n) {
            let got = decoder.decode(word);
            let (smallest, r) = min_rotation(word, n);
            match f.id_of(smallest) {
                Some(id) => {
                    prop_assert_eq!(got.status, MatchStatus::Exact);
                    prop_assert_eq!((got.id, got.code, got.rotation), (id, smallest, r));
                }
                None => {
                    prop_assert_eq!(got.status, MatchStatus::Rejected, "word {:b}", word);
                    prop_assert_eq!(got.id, 0);
                }
            }
        }
    }

    #[test]
    fn family_file_round_trips((n, d) in bits_and_distance()) {
        let f = Family::generate(n, d).unwrap();
        let loaded = Family::from_json(&f.to_json()).unwrap();
        prop_assert_eq!(&loaded, &f);
        // A decoder built from the loaded family answers like the original.
        let (a, b) = (Decoder::new(&f), Decoder::new(&loaded));
        for word in 0..(1u32 << n) {
            prop_assert_eq!(a.decode(word), b.decode(word));
        }
    }
}

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
            let f = Family::generate(n, d).unwrap();
            assert_eq!(f.len(), count, "n={n} d={d}");
            assert_eq!(
                f.min_distance().map(|m| m >= d),
                (count > 1).then_some(true)
            );
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
    assert_eq!(f.min_distance(), Some(2));
    assert_eq!(f.min_self_distance(), 2);
}

#[test]
fn bad_parameters_are_refused() {
    for (bits, d) in [(0, 1), (1, 1), (25, 3), (8, 0), (8, 9)] {
        assert!(Family::generate(bits, d).is_err(), "bits={bits} d={d}");
    }
    for bits in [2, 24] {
        assert!(Family::generate(bits, 1).is_ok());
        assert!(Family::generate(bits, bits).is_ok());
    }
}
