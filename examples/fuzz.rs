//! The fuzz harness's long run: mutated image files, random images up to 2
//! megapixels, family files, manifests, page templates, camera files, arena
//! files and boards through the library's loaders, detector and validation;
//! mutated bags and videos through `whycode detect`.
//!
//!     cargo build --release && cargo run --release --example fuzz -- [--minutes N] [--seed S]
//!
//! The command-line targets (bags, videos, output streams closed or full,
//! concurrent runs writing one output) run the `whycode` binary built beside this
//! example (target/release/whycode); without it they are skipped, and say so.
//!
//! Prints how many inputs each target tried; exits 1 on a panic, a hang,
//! detection slower than 1 s for a 2-megapixel image, or invalid JSON.

use std::time::Duration;

use whycode_testkit::fuzz as fuzz_support;

fn main() -> std::process::ExitCode {
    let mut minutes = 1.0f64;
    let mut seed = 1u64;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        let value = it.next();
        let parsed = match (flag.as_str(), value) {
            ("--minutes", Some(v)) => v.parse().map(|m| minutes = m).is_ok(),
            ("--seed", Some(v)) => v.parse().map(|s| seed = s).is_ok(),
            _ => false,
        };
        if !(parsed && minutes.is_finite() && minutes > 0.0) {
            eprintln!("usage: fuzz [--minutes N] [--seed S]");
            return std::process::ExitCode::FAILURE;
        }
    }
    let settings = fuzz_support::Settings {
        budget: Duration::from_secs_f64(minutes * 60.0),
        detect_limit: if cfg!(debug_assertions) {
            None
        } else {
            Some(Duration::from_secs(1))
        },
        hang_limit: Duration::from_secs(30),
        seed,
        whycode: whycode_binary(),
    };
    let summaries = fuzz_support::run(&settings);
    print!("{}", fuzz_support::report(&summaries));
    let total: u64 = summaries.iter().map(|s| s.inputs).sum();
    let failed = summaries.iter().any(|s| !s.failures.is_empty());
    println!(
        "{total} inputs in {minutes} min: {}",
        if failed {
            "FAILURES"
        } else {
            "no panic, hang or invalid JSON"
        }
    );
    if failed {
        std::process::ExitCode::FAILURE
    } else {
        std::process::ExitCode::SUCCESS
    }
}

/// target/<profile>/whycode, beside target/<profile>/examples/fuzz.
fn whycode_binary() -> Option<std::path::PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let binary = exe
        .parent()?
        .parent()?
        .join(format!("whycode{}", std::env::consts::EXE_SUFFIX));
    binary.is_file().then_some(binary)
}
