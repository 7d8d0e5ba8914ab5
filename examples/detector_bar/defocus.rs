//! Row 9 (issue 25): markers through soft focus, small and steep. Every
//! cell of size × view × defocus (`whycode_testkit::scenario::defocused`:
//! 1280x720, f = 1000 px, noise sigma 4, light clutter) is read by ours
//! and by each rival on the same scenes with its tags at the same printed
//! footprint (AprilTag at full resolution, OpenCV's ArUco 4x4), in one
//! run; a cell is lost when ours names fewer markers than the better
//! rival.

use std::time::Instant;

use whycode::family::Family;
use whycode::simulate::Sighting;
use whycode_testkit::scenario::{
    defocused, detector, Print, DEFOCUS_SIGMAS, DEFOCUS_SIZES, DEFOCUS_VIEWS,
};
use whycode_testkit::tally::Counts;

use crate::rival;
use crate::table::{beats_ids, cells, median, pct, Table};
use crate::Rivals;

fn named(c: &Counts) -> String {
    format!("{}/{}", c.correct_id, c.markers)
}

/// One cell's figures: ours, each rival's, and the times per frame.
struct Cell {
    label: String,
    ours: Counts,
    theirs: [Option<Counts>; 3],
}

pub fn rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    let mut ours_total = Counts::default();
    let mut theirs_total: [Option<Counts>; 3] = rivals.map(|r| r.map(|_| Counts::default()));
    let mut by_sigma: Vec<(f64, Counts, [Option<Counts>; 3])> = DEFOCUS_SIGMAS
        .iter()
        .map(|&s| (s, Counts::default(), theirs_total))
        .collect();
    let mut ours_ms = Vec::new();
    let mut theirs_ms: [Vec<f64>; 3] = Default::default();
    let mut grid = Vec::new();
    let mut cell_index = 0u64;
    for &size in &DEFOCUS_SIZES {
        for &view in &DEFOCUS_VIEWS {
            for (k, &sigma) in DEFOCUS_SIGMAS.iter().enumerate() {
                let seed = 1_000_000 + 100 * cell_index;
                cell_index += 1;
                let scenario = defocused(fam8, size, view, sigma, scale, seed);
                let mut det = detector(Some(fam8), &scenario.camera(), false);
                let mut ours = Counts::default();
                for f in 0..scenario.frames {
                    let frame = scenario.frame(f, Print::WhyCode);
                    let t = Instant::now();
                    let found = det.detect(&frame.image);
                    ours_ms.push(t.elapsed().as_secs_f64() * 1000.0);
                    let seen: Vec<Sighting> = found.iter().map(Sighting::from).collect();
                    ours.add(frame.seed, &frame.targets, &seen);
                }
                let mut theirs: [Option<Counts>; 3] = [None; 3];
                for (slot, (rival, times)) in theirs
                    .iter_mut()
                    .zip(rivals.iter().zip(theirs_ms.iter_mut()))
                {
                    let Some(rival) = rival else { continue };
                    let mut c = Counts::default();
                    match rival::run(&scenario, *rival, &mut c, |_, _| {}) {
                        Ok(t) => {
                            times.extend(t);
                            *slot = Some(c);
                        }
                        Err(e) => eprintln!("{} failed: {e}", rival.name()),
                    }
                }
                ours_total.merge(&ours);
                by_sigma[k].1.merge(&ours);
                for j in 0..3 {
                    if let (Some(t), Some(c)) = (theirs_total[j].as_mut(), &theirs[j]) {
                        t.merge(c);
                    }
                    if let (Some(t), Some(c)) = (by_sigma[k].2[j].as_mut(), &theirs[j]) {
                        t.merge(c);
                    }
                }
                let cell = Cell {
                    label: format!("{size:>2} px, {view:>2}°, σ {sigma}"),
                    ours,
                    theirs,
                };
                table.note(format!(
                    "{}: ours {} named, {} found, {} wrong; {}",
                    cell.label,
                    named(&cell.ours),
                    cell.ours.detected,
                    cell.ours.wrong_id,
                    rival_cells(&cell.theirs)
                ));
                grid.push(cell);
            }
        }
    }
    let behind = grid
        .iter()
        .filter(|c| !beats_ids(&c.ours, &c.theirs))
        .count();
    let show = |c: &Counts| {
        format!(
            "named {}, found {}, {} wrong",
            pct(c.id_rate()),
            pct(c.detection_rate()),
            c.wrong_id
        )
    };
    table.row(
        &format!(
            "9 defocus σ 1-2 px, 20-60 px, views 0-65°, {} cells",
            grid.len()
        ),
        format!(
            "{}; behind the better rival in {behind} of {} cells",
            show(&ours_total),
            grid.len()
        ),
        cells(&theirs_total, show),
        "",
        ours_total.wrong_id == 0 && ours_total.id_rate() >= 0.75 && behind == 0,
    );
    for (sigma, ours, theirs) in &by_sigma {
        table.row(
            &format!("9 defocus σ {sigma} px"),
            show(ours),
            cells(theirs, show),
            "",
            ours.wrong_id == 0 && beats_ids(ours, theirs),
        );
    }
    let ms = |v: &Vec<f64>| (!v.is_empty()).then(|| median(v.clone()));
    let ours_median = median(ours_ms);
    table.row(
        "9 defocus, ms per frame (median, one thread)",
        format!("{ours_median:.1} ms"),
        [0, 1, 2].map(|k| ms(&theirs_ms[k]).map(|t| format!("{t:.1} ms"))),
        "",
        true,
    );
    println!();
    println!("| size | view | σ | ours named (found) | AprilTag named | ArUco named |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for c in &grid {
        let theirs = |k: usize| c.theirs[k].as_ref().map_or("-".into(), named);
        let mark = if beats_ids(&c.ours, &c.theirs) {
            ""
        } else {
            " **behind**"
        };
        let parts: Vec<&str> = c.label.split(", ").collect();
        println!(
            "| {} | {} | {} | {} ({}){mark} | {} | {} |",
            parts[0],
            parts[1],
            parts[2],
            named(&c.ours),
            c.ours.detected,
            theirs(0),
            theirs(2)
        );
    }
    println!();
}

fn rival_cells(theirs: &[Option<Counts>; 3]) -> String {
    crate::table::RIVALS
        .iter()
        .zip(theirs)
        .filter_map(|(name, c)| c.as_ref().map(|c| format!("{name} {} named", named(c))))
        .collect::<Vec<_>>()
        .join(", ")
}
