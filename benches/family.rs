//! Family generation, statistics and decoding speed (single thread).
//!
//! Targets: every family up to 16 bits under 50 ms; 20 bits at d = 2 and 3
//! under 1 s; 24 bits at d = 3 under 10 s and 100 MB (see "max alloc").
//! Run with `cargo bench --bench family`.

use divan::{black_box, AllocProfiler, Bencher};
use whycode::family::necklace::{mask, rotr};
use whycode::family::{Decoder, Family};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// "bits/distance" → (bits, distance).
fn parse(family: &str) -> (u32, u32) {
    let (n, d) = family.split_once('/').unwrap();
    (n.parse().unwrap(), d.parse().unwrap())
}

/// Every (bits, distance) with bits 2..=16, one after another.
#[divan::bench(sample_count = 10)]
fn generate_every_family_up_to_16_bits() -> usize {
    let mut total = 0;
    for n in 2..=16 {
        for d in 1..=n {
            total += Family::generate(black_box(n), black_box(d)).unwrap().len();
        }
    }
    total
}

/// The largest of the 16-bit-or-less families one at a time.
#[divan::bench(args = 1..=16, sample_count = 20)]
fn generate_16_bits(distance: u32) -> Family {
    Family::generate(16, black_box(distance)).unwrap()
}

#[divan::bench(args = ["20/1", "20/2", "20/3", "20/4", "24/1", "24/2", "24/3"], sample_count = 5, sample_size = 1)]
fn generate_large(family: &str) -> Family {
    let (n, d) = parse(family);
    Family::generate(black_box(n), black_box(d)).unwrap()
}

#[divan::bench(args = ["16/2", "16/3", "20/2", "20/3", "24/1", "24/2", "24/3"], sample_count = 5, sample_size = 1)]
fn statistics(bencher: Bencher, family: &str) {
    let (n, d) = parse(family);
    let f = Family::generate(n, d).unwrap();
    bencher.bench_local(|| black_box(&f).stats());
}

/// Loading checks every code and the family's distance.
#[divan::bench(args = ["16/2", "20/3", "24/3"], sample_count = 5, sample_size = 1)]
fn validate_loaded_family(bencher: Bencher, family: &str) {
    let (n, d) = parse(family);
    let text = Family::generate(n, d).unwrap().to_json();
    bencher.bench_local(|| Family::from_json(black_box(&text)).unwrap());
}

#[divan::bench(args = ["8/2", "16/1", "16/2", "16/3", "20/1", "20/2", "20/3", "20/20", "24/3"], sample_count = 5, sample_size = 1)]
fn decoder_build(bencher: Bencher, family: &str) {
    let (n, d) = parse(family);
    let f = Family::generate(n, d).unwrap();
    bencher.bench_local(|| Decoder::new(black_box(&f)));
}

/// Words as a ring reader produces them: member rotations, some with one
/// or two misread bits, and some noise.
fn readings(f: &Family, count: usize) -> Vec<u32> {
    let bits = f.bits();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    (0..count)
        .map(|i| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let code = f.codes()[(state % f.len() as u64) as usize];
            let word = rotr(code, bits, (state >> 40) as u32 % bits);
            match i % 4 {
                0 => word,
                1 => word ^ (1 << ((state >> 20) as u32 % bits)),
                2 => {
                    word ^ (1 << ((state >> 20) as u32 % bits))
                        ^ (1 << ((state >> 30) as u32 % bits))
                }
                _ => (state >> 8) as u32 & mask(bits),
            }
        })
        .collect()
}

/// Time per 1000 decoded words. Up to 20 bits the decoder is a table
/// lookup; above, it searches (see `Decoder`'s documentation).
#[divan::bench(args = ["16/2", "20/3", "21/3", "22/1", "22/3", "24/1", "24/2", "24/3", "24/5", "24/7", "24/9", "24/24"], sample_count = 20)]
fn decode_1000_words(bencher: Bencher, family: &str) {
    let (n, d) = parse(family);
    let f = Family::generate(n, d).unwrap();
    let decoder = Decoder::new(&f);
    let words = readings(&f, 1000);
    bencher.bench_local(|| {
        let mut members = 0u32;
        for &w in &words {
            members += decoder.decode(black_box(w)).id.min(1);
        }
        members
    });
}
