use std::time::Instant;
use whycode::family::{Decoder, Family};
fn main() {
    for n in [18, 20, 22, 24] {
        for d in 1..=n {
            let t = Instant::now();
            let f = Family::generate(n, d).unwrap();
            let e = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let dec = Decoder::new(&f);
            let e2 = t.elapsed().as_secs_f64();
            println!(
                "n={n} d={d} count={} gen {e:.3}s dec {e2:.3}s r={}",
                f.len(),
                dec.radius()
            );
            if e > 30.0 {
                return;
            }
        }
    }
}
