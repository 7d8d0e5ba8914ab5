//! Row 8: speed where users run it, ours and each rival's (AprilTag, the
//! original, ArUco) on the same frames in the same run (medians, ms per
//! frame, one thread each), and the ratio.

use std::time::Instant;

use image::GrayImage;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig};
use whycode::family::Family;
use whycode::math::Pcg32;
use whycode::simulate::{self, Background, Sighting};
use whycode_testkit::scenario::{
    camera, cluttered_desk, detector, detector_config, scene, spread_markers, Families, Print,
    Scenario, Spread, DEG, DIAMETER_M,
};
use whycode_testkit::tally::Counts;

use crate::rival::{self, Setup};
use crate::table::{median, Cells, Table};
use crate::Rivals;

fn time_ms(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64() * 1000.0
}

/// "4.2x faster" or "2.5x slower": ours against a rival's time.
fn faster(theirs_ms: f64, ours_ms: f64) -> String {
    if theirs_ms >= ours_ms {
        format!("{:.1}x faster", theirs_ms / ours_ms)
    } else {
        format!("{:.1}x slower", ours_ms / theirs_ms)
    }
}

/// Frames a tracker sees before its tracked frames are timed: the ID
/// filter settles a marker's ID after three agreeing readings, and until
/// then every frame reads the ring in full. The timed frames are the
/// steady state of a stream, not its start-up.
const SETTLE_FRAMES: usize = 3;

/// Each rival's median ms over its runs of `scenario` and how many times
/// ours is faster: `ours_ms` untracked, and tracked for a rival that tracks
/// (the original keeps its markers from one run to the next).
fn versus(scenario: &Scenario, runs: usize, rivals: &Rivals, ours_ms: (f64, f64)) -> Cells {
    rivals.map(|rival| {
        let rival = rival?;
        let (ours_ms, ours_label) = if rival.tracks() && runs > 1 {
            (ours_ms.1, " tracked, told the count")
        } else {
            (ours_ms.0, "")
        };
        let mut times = Vec::new();
        for _ in 0..runs {
            match rival::run(scenario, rival, &mut Counts::default(), |_, _| {}) {
                Ok(t) => times.extend(t),
                Err(e) => {
                    eprintln!("{} failed: {e}", rival.name());
                    return None;
                }
            }
        }
        let theirs = median(times);
        Some(format!(
            "{theirs:.2} ms (ours{ours_label} {})",
            faster(theirs, ours_ms)
        ))
    })
}

/// Median ms of `runs` tracked frames of `image` after [`SETTLE_FRAMES`],
/// ours for `family` told at most `max_markers`; and how many the last
/// frame found.
fn tracked(
    family: Option<&Family>,
    cam: &Camera,
    image: &GrayImage,
    max_markers: usize,
    runs: usize,
) -> (f64, usize) {
    let mut tracker = Detector::new(DetectorConfig {
        max_markers,
        ..detector_config(family, cam, true)
    });
    for _ in 0..SETTLE_FRAMES {
        tracker.detect(image);
    }
    let mut n = 0;
    let times: Vec<f64> = (0..runs)
        .map(|_| time_ms(|| n = tracker.detect(image).len()))
        .collect();
    (median(times), n)
}

pub fn rows(table: &mut Table, families: &mut Families, quick: bool, rivals: &Rivals) {
    let fam8 = families.get(8, 2);
    let runs = if quick { 3 } else { 7 };

    // Cluttered 1280x720 frames without a marker: what costs time when
    // there is nothing to find.
    let clutter = cluttered_desk(&fam8, runs);
    let mut det = detector(Some(&fam8), &clutter.camera(), false);
    let mut times = Vec::new();
    for f in 0..clutter.frames {
        let frame = clutter.frame(f, Print::WhyCode);
        det.detect(&frame.image);
        times.push(time_ms(|| drop(det.detect(&frame.image))));
    }
    let ours = median(times);
    table.row(
        "8a cluttered 1280x720, no markers, 8-bit",
        format!("{ours:.2} ms"),
        versus(&clutter, 1, rivals, (ours, ours)),
        "",
        ours < 2.0,
    );

    // 640x480 textured table top with a few markers, pose included.
    let table_top = Scenario::new(
        Some(&fam8),
        Spread::tilted(4, (40.0, 90.0), 30.0),
        1,
        910_000,
    )
    .size(640, 480)
    .look(|s, _, _| {
        s.background = Background::Table;
        s.noise = 2.0;
    });
    let frame = table_top.frame(0, Print::WhyCode);
    let cam = table_top.camera();
    let mut counts = Counts::default();
    let mut det: Detector = detector(Some(&fam8), &cam, false);
    let seen: Vec<Sighting> = det
        .detect(&frame.image)
        .iter()
        .map(Sighting::from)
        .collect();
    counts.add(frame.seed, &frame.targets, &seen);
    let n = if quick { 50 } else { 300 };
    let untracked = median(
        (0..n)
            .map(|_| time_ms(|| drop(det.detect(&frame.image))))
            .collect(),
    );
    // Tracked as a stream would be, and told the frame's marker count as
    // the original is (then no band of rows is searched for newcomers).
    let track = |max_markers| tracked(Some(&fam8), &cam, &frame.image, max_markers, n).0;
    let (tracked_ms, told_ms) = (
        track(DetectorConfig::default().max_markers),
        track(table_top.spread.count),
    );
    table.row(
        "8b 640x480 table, 4 markers, 8-bit, pose",
        format!(
            "untracked {untracked:.3} ms, tracked {tracked_ms:.3} ms ({told_ms:.3} ms told {}); {}/{} IDs",
            table_top.spread.count, counts.correct_id, counts.markers
        ),
        // One frame, read as many times by each rival for a median; the
        // original, told the count, against ours told it.
        versus(
            &table_top,
            if quick { 5 } else { 20 },
            rivals,
            (untracked, told_ms),
        ),
        "",
        untracked < 1.0 && counts.correct_id == counts.markers,
    );

    // Paper Table 5: 5000x5000, 550 markers of 60-120 px, full pose.
    let fam14 = families.get(14, 2);
    let cam = camera(5000, 5000);
    let mut rng = Pcg32::new(900_000, 1);
    let spread = Spread {
        count: 550,
        diameter_px: (60.0, 120.0),
        max_tilt: 20.0 * DEG,
        fixed_tilt: None,
        against_view: false,
    };
    for (k, (label, family, background)) in [
        ("WhyCode 14-bit, white sheet", Some(&fam14), 0.86),
        ("legacy WhyCon, white sheet", None, 0.86),
        ("WhyCode 14-bit, cards on grey floor", Some(&fam14), 0.45),
    ]
    .into_iter()
    .enumerate()
    {
        let mut s = scene(
            &cam,
            spread_markers(&cam, family, spread, &mut rng),
            900_001,
        );
        s.background = Background::Uniform(background);
        s.noise = 2.0;
        let t = Instant::now();
        let (image, truth) = simulate::render(&s);
        let render_s = t.elapsed().as_secs_f64();
        let targets = truth.targets();
        let mut counts = Counts::default();
        let mut first = Vec::new();
        for _ in 0..runs {
            let mut det = detector(family, &cam, false);
            let mut found = Vec::new();
            first.push(time_ms(|| found = det.detect(&image)));
            if counts.frames == 0 {
                let seen: Vec<Sighting> = found.iter().map(Sighting::from).collect();
                counts.add(900_001, &targets, &seen);
            }
        }
        let track = |max_markers| tracked(family, &cam, &image, max_markers, runs);
        let (tracked_ms, tracked_n) = track(DetectorConfig::default().max_markers);
        let (known_ms, known_n) = track(550);
        let first_ms = median(first);
        // Each rival once, on the first scene, with its own tags in our
        // markers' places where it has them: 25 megapixels take AprilTag
        // seconds.
        let theirs: Cells = rivals.map(|rival| {
            let rival = rival.filter(|_| k == 0)?;
            let mut printed = s.clone();
            rival.print().apply(&mut printed);
            let (image, truth) = simulate::render(&printed);
            let setup = Setup {
                camera: &cam,
                size_m: DIAMETER_M,
                family: family.map(|f| (f.bits(), f.distance())),
                targets: spread.count,
            };
            match rival.detect(&setup, &[&image]) {
                Ok(mut r) => {
                    let (seen, ms) = r.remove(0);
                    let mut c = Counts::default();
                    c.add(900_001, &truth.targets(), &seen);
                    Some(format!(
                        "{ms:.0} ms, found {}/{}, {} IDs right (ours {})",
                        c.detected,
                        c.markers,
                        c.correct_id,
                        faster(ms, first_ms)
                    ))
                }
                Err(e) => {
                    eprintln!("{} failed: {e}", rival.name());
                    None
                }
            }
        });
        table.row(
            &format!("8c 5000x5000, 550 markers, pose, {label}"),
            format!(
                "first {first_ms:.0} ms, tracked {tracked_ms:.0} ms ({known_ms:.0} ms told 550); found {}/{}",
                counts.detected, counts.markers
            ),
            theirs,
            "",
            first_ms < 150.0 && known_ms < 15.0 && counts.detection_rate() >= 0.99,
        );
        table.note(format!(
            "tracked frames found {tracked_n} / {known_n}; scene rendered in {render_s:.1} s"
        ));
    }
}
