//! The fuzz harness's bounded run (`whycode_testkit::fuzz`): about 40
//! seconds spread over all targets; `cargo run --release --example fuzz --
//! --minutes N` runs it for longer.

use whycode_testkit::fuzz as fuzz_support;

use std::time::Duration;

#[test]
fn loaders_and_detector_survive_mutated_and_random_inputs() {
    let settings = fuzz_support::Settings {
        budget: Duration::from_secs(40),
        // Unoptimised test builds are no measure of speed; only hangs count.
        detect_limit: None,
        hang_limit: Duration::from_secs(60),
        seed: 20_26,
        whycode: Some(env!("CARGO_BIN_EXE_whycode").into()),
    };
    let summaries = fuzz_support::run(&settings);
    let report = fuzz_support::report(&summaries);
    eprintln!("{report}");
    assert!(
        summaries.iter().all(|s| s.failures.is_empty()),
        "fuzzing found failures:\n{report}"
    );
    for s in &summaries {
        assert!(s.inputs > 0, "{} tried no input:\n{report}", s.name);
    }
}
