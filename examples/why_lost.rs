//! Where the scan lost each large dark segment of an image: the last
//! candidate test every segment at least `--min-half` px across reached
//! (feature `trace`), for finding out why a marker a person sees in a
//! photograph is not reported.
//!
//!     cargo run --release --features trace --example why_lost -- IMAGE [--legacy | --bits N] [--min-half PX]

use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|k| args.get(k + 1))
            .cloned()
    };
    let Some(path) = args.first() else {
        eprintln!("usage: why_lost IMAGE [--legacy | --bits N] [--min-half PX]");
        std::process::exit(2);
    };
    let target = if args.iter().any(|a| a == "--legacy") {
        Target::WhyCon
    } else {
        let bits = value("--bits").and_then(|b| b.parse().ok()).unwrap_or(8);
        Target::WhyCode(Family::generate(bits, 2).expect("bit count 2-24"))
    };
    let min_half: f64 = value("--min-half")
        .and_then(|m| m.parse().ok())
        .unwrap_or(5.0);
    let image = whycode::load_gray(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    let mut detector = Detector::new(DetectorConfig {
        target,
        report_unreadable: true,
        ..DetectorConfig::default()
    });
    for d in detector.detect(&image) {
        println!(
            "found  id {:>3} at ({:7.1}, {:7.1}) axes {:5.1} {:5.1} unreadable {}",
            d.id, d.u, d.v, d.axes[0], d.axes[1], d.unreadable
        );
    }
    for loss in detector.take_trace() {
        if loss.half_size >= min_half {
            println!(
                "lost at {:?}: centroid ({:7.1}, {:7.1}), half size {:5.1}",
                loss.reached, loss.u, loss.v, loss.half_size
            );
        }
    }
}
