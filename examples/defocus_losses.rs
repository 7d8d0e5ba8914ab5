//! Where the detector loses the markers of the detector bar's defocus row
//! (issue 25): for every marker not named, the stage that lost it. Built
//! with the `trace` feature, whose scan records the last candidate test
//! each dark segment reached (`whycode::detect::trace`); the describe
//! stage's verdict is read off detections made with `report_unreadable`.
//!
//!     cargo run --release --features trace --example defocus_losses [-- --frames N]
//!
//! A marker is charged to the deepest stage any segment centred on it
//! (within half its size, and no larger than it) reached: a segment
//! lost at the ellipse fit beats one lost at the roundness test.

use std::collections::BTreeMap;

use whycode::detect::trace::Reached;
use whycode::detect::{Detector, DetectorConfig};
use whycode::simulate::{match_reports, Reach, Sighting};
use whycode_testkit::scenario::{
    defocused, detector_config, Families, Print, DEFOCUS_SIGMAS, DEFOCUS_SIZES, DEFOCUS_VIEWS,
};

/// The stage that lost a marker, in pipeline order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Lost {
    /// No dark segment of the marker's size centred on it at all.
    NoSegment,
    /// A segment reached this candidate test and failed it.
    Segment(Reached),
    /// A candidate, and the structure test or the ring model said it is
    /// no marker.
    RingTest,
    /// A marker without an ID.
    Reader,
    /// A marker with another member's ID.
    WrongId,
}

fn label(lost: Lost) -> String {
    match lost {
        Lost::NoSegment => "segmentation: no dark segment".into(),
        Lost::Segment(Reached::EllipseFit) => "ellipse fit".into(),
        Lost::Segment(Reached::Candidate) => "dropped after the scan".into(),
        Lost::Segment(r) => format!("segmentation: {r:?}"),
        Lost::RingTest => "ring test (not a marker)".into(),
        Lost::Reader => "reader (no ID)".into(),
        Lost::WrongId => "reader (wrong ID)".into(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|k| args.get(k + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(1);
    let fam8 = Families::default().get(8, 2);
    // (σ index, stage) → markers; per cell too.
    let mut losses: BTreeMap<(Lost, usize), usize> = BTreeMap::new();
    let mut markers = [0usize; 3];
    let mut named = [0usize; 3];
    let mut cell_index = 0u64;
    for &size in &DEFOCUS_SIZES {
        for &view in &DEFOCUS_VIEWS {
            for (k, &sigma) in DEFOCUS_SIGMAS.iter().enumerate() {
                // The bar's seeds, so that the cells are the bar's.
                let seed = 1_000_000 + 100 * cell_index;
                cell_index += 1;
                let scenario = defocused(&fam8, size, view, sigma, frames, seed);
                let mut det = Detector::new(DetectorConfig {
                    report_unreadable: true,
                    ..detector_config(Some(&fam8), &scenario.camera(), false)
                });
                let mut cell: Vec<Lost> = Vec::new();
                for f in 0..scenario.frames {
                    let frame = scenario.frame(f, Print::WhyCode);
                    let found = det.detect(&frame.image);
                    let trace = det.take_trace();
                    let seen: Vec<Sighting> = found.iter().map(Sighting::from).collect();
                    let matched = match_reports(&frame.targets, &seen, Reach::default());
                    for &(t, d) in &matched.pairs {
                        let target = &frame.targets[t];
                        markers[k] += 1;
                        let lost = match d {
                            Some(d) if seen[d].id == Some(target.id) => {
                                named[k] += 1;
                                continue;
                            }
                            Some(d) if seen[d].id.is_some() => Lost::WrongId,
                            Some(d) if found[d].unreadable => Lost::RingTest,
                            Some(_) => Lost::Reader,
                            None => trace
                                .iter()
                                .filter(|l| {
                                    (l.u - target.u).hypot(l.v - target.v) < 0.5 * target.size_px
                                        && l.half_size <= 0.75 * target.size_px
                                })
                                .map(|l| Lost::Segment(l.reached))
                                .max()
                                .unwrap_or(Lost::NoSegment),
                        };
                        *losses.entry((lost, k)).or_default() += 1;
                        cell.push(lost);
                    }
                }
                if !cell.is_empty() {
                    let mut tally: BTreeMap<Lost, usize> = BTreeMap::new();
                    for l in &cell {
                        *tally.entry(*l).or_default() += 1;
                    }
                    let parts: Vec<String> = tally
                        .iter()
                        .map(|(l, n)| format!("{n} {}", label(*l)))
                        .collect();
                    println!(
                        "{size:>2} px, {view:>2}°, σ {sigma}: {} lost: {}",
                        cell.len(),
                        parts.join(", ")
                    );
                }
            }
        }
    }
    println!();
    let head: Vec<String> = DEFOCUS_SIGMAS.iter().map(|s| format!("σ {s}")).collect();
    println!(
        "| stage that lost the marker | {} | all |",
        head.join(" | ")
    );
    println!("| --- |{}", " ---: |".repeat(head.len() + 1));
    let stages: Vec<Lost> = {
        let mut s: Vec<Lost> = losses.keys().map(|(l, _)| *l).collect();
        s.dedup();
        s
    };
    for stage in stages {
        let per: Vec<usize> = (0..3)
            .map(|k| losses.get(&(stage, k)).copied().unwrap_or(0))
            .collect();
        let cells: Vec<String> = per.iter().map(usize::to_string).collect();
        println!(
            "| {} | {} | {} |",
            label(stage),
            cells.join(" | "),
            per.iter().sum::<usize>()
        );
    }
    let all: usize = markers.iter().sum();
    let cells: Vec<String> = (0..3)
        .map(|k| format!("{}/{}", named[k], markers[k]))
        .collect();
    println!(
        "| named | {} | {}/{all} |",
        cells.join(" | "),
        named.iter().sum::<usize>()
    );
}
