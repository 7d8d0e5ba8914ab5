//! Measures the detector against "the bar": AprilTag (tag36h11 at the same
//! printed footprint, pupil-apriltags, one thread) on the same simulated
//! scenes with tags in our markers' places, and the original WhyCode
//! detector on the very same frames, both in the same run (the original's
//! figures as quoted in issue 9 where it is not built). Prints each row
//! with our figure, the rivals' and pass/fail, then the table in Markdown.
//!
//!     cargo run --release --example detector_bar [-- --quick] [--only 1,3,8]
//!
//! `--quick` runs a third of the frames; `--only` runs those sections.
//! AprilTag needs a Python with pupil-apriltags ([`apriltag::SETUP`];
//! `APRILTAG_PYTHON` names one), ArUco (the defocus row, 9) one with
//! opencv-python-headless ([`aruco::SETUP`]; `ARUCO_PYTHON`), the original
//! a build of its sources (`original/build.sh`); without them their cells
//! say "not measured".
//! A new row is a [`Scenario`] (which markers, how many frames, the look;
//! `whycode_testkit::scenario`), its counts for ours and the rivals', and a
//! `table.row(...)`.

mod apriltag;
mod aruco;
mod defocus;
mod measures;
mod original;
mod real_camera;
mod rival;
mod speed;
mod table;

use std::f64::consts::PI;
use std::time::Instant;

use apriltag::AprilTag;
use aruco::Aruco;
use measures::{normal_errors, yaw_errors, NormalResult};
use original::Original;
use rival::Rival;
use table::{beats, beats_ids, cells, pct, Table};
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::simulate::{Background, MotionBlur};
use whycode_testkit::scenario::{detector_config, Families, Scenario, Spread};
use whycode_testkit::scenes::cast_shadow;
use whycode_testkit::tally::Counts;

/// The rivals in [`table::RIVALS`] order; `None` where one cannot be run.
pub type Rivals<'a> = [Option<&'a dyn Rival>; 3];

fn ids(c: &Counts) -> String {
    format!(
        "{}/{} detected, IDs {} right, {} unknown, {} wrong",
        c.detected, c.markers, c.correct_id, c.unknown_id, c.wrong_id
    )
}

fn rates(c: &Counts) -> String {
    format!(
        "detected {}, IDs {}, {} wrong",
        pct(c.detection_rate()),
        pct(c.id_rate()),
        c.wrong_id
    )
}

/// Every rival's counts on the scenario's frames.
fn rival_counts(scenario: &Scenario, rivals: &Rivals) -> [Option<Counts>; 3] {
    rivals.map(|r| rival::counts(scenario, r))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let scale = if quick { 1 } else { 3 };
    let only: Option<Vec<u32>> = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|k| args.get(k + 1))
        .map(|list| {
            list.split(',')
                .filter_map(|n| n.trim().parse().ok())
                .collect()
        });
    let run = |section: u32| only.as_ref().is_none_or(|o| o.contains(&section));
    let started = Instant::now();

    let apriltag = AprilTag::find()
        .inspect(|a| {
            println!(
                "AprilTag: pupil-apriltags, tag36h11, one thread, quad_decimate {}",
                a.quad_decimate
            )
        })
        .inspect_err(|e| println!("AprilTag: not measured ({e})"))
        .ok();
    let original = Original::find()
        .inspect(|_| println!("original WhyCode: measured (whycon-ros CWhycon, node defaults)"))
        .inspect_err(|e| println!("original WhyCode: not measured ({e})"))
        .ok();
    let aruco = Aruco::find()
        .inspect(|_| println!("ArUco: OpenCV cv2.aruco, DICT_4X4_50, one thread (speed, defocus and realistic-camera rows)"))
        .inspect_err(|e| println!("ArUco: not measured ({e})"))
        .ok();
    // ArUco joins on the speed, defocus and realistic-camera rows only.
    let rivals: Rivals = [
        apriltag.as_ref().map(|a| a as &dyn Rival),
        original.as_ref().map(|o| o as &dyn Rival),
        None,
    ];
    let mut table = Table::new([apriltag.is_none(), original.is_none(), aruco.is_none()]);
    let mut families = Families::default();
    let fam8 = families.get(8, 2);

    if run(1) {
        yaw_rows(&mut table, &mut families, scale, &rivals);
    }
    if run(2) {
        normal_rows(&mut table, &fam8, scale, &rivals);
    }
    if run(3) {
        clutter_rows(&mut table, &fam8, scale, &rivals);
    }
    if run(4) || run(5) {
        light_rows(&mut table, &fam8, scale, &rivals, run(4), run(5));
    }
    if run(6) {
        blur_and_tilt_rows(&mut table, &fam8, scale, &rivals);
    }
    if run(7) {
        println!("7. smallest diameter");
        smallest_rows(&mut table, &fam8, scale, &rivals);
    }
    if run(8) {
        println!("8. speed");
        let rivals: Rivals = [
            rivals[0],
            rivals[1],
            aruco.as_ref().map(|a| a as &dyn Rival),
        ];
        speed::rows(&mut table, &mut families, quick, &rivals);
    }
    if run(9) {
        println!("9. defocus");
        // AprilTag at full resolution (quad_decimate 1), as issue 25
        // measured it: its default halves the image, and loses the small
        // tags before decoding them.
        let apriltag_full = apriltag.as_ref().map(AprilTag::full_resolution);
        let rivals: Rivals = [
            apriltag_full.as_ref().map(|a| a as &dyn Rival),
            None,
            aruco.as_ref().map(|a| a as &dyn Rival),
        ];
        defocus::rows(&mut table, &fam8, scale, &rivals);
    }
    if run(10) {
        println!("10. realistic cameras");
        let apriltag_full = apriltag.as_ref().map(AprilTag::full_resolution);
        let rivals: Rivals = [
            apriltag_full.as_ref().map(|a| a as &dyn Rival),
            original.as_ref().map(|o| o as &dyn Rival),
            aruco.as_ref().map(|a| a as &dyn Rival),
        ];
        real_camera::rows(&mut table, &fam8, scale, &rivals);
    }
    table.print();
    println!("{:.0} s in all", started.elapsed().as_secs_f64());
}

/// Row 1: Yaw bias and worst error, 8-16 bits, face-on and tilted.
fn yaw_rows(table: &mut Table, families: &mut Families, scale: usize, rivals: &Rivals) {
    println!("1. yaw");
    for (name, max_tilt_deg, seed) in [
        ("1a yaw, face-on, 8-16 bits", 0.0, 100_000),
        ("1b yaw, tilt & pan ≤45° each, 8-16 bits", 45.0, 200_000),
    ] {
        let spread = Spread::tilted(9, (70.0, 110.0), max_tilt_deg);
        let bits = [8, 10, 12, 14, 16];
        let (ours, theirs) = yaw_errors(families, &bits, 2 * scale, spread, seed, rivals);
        let show = |r: &measures::YawResult| {
            let e = &r.errors;
            format!(
                "bias {:+.3}°, mean abs {:.3}°, max {:.2}° over {}",
                e.mean(),
                e.mean_abs(),
                e.max_abs,
                e.n
            )
        };
        let e = &ours.errors;
        let pass = e.mean().abs() < 1.0
            && e.max_abs < 1.0
            && ours.counts.wrong_id == 0
            && e.n > 0
            && beats(&ours, &theirs, |o, t| o.errors.max_abs <= t.errors.max_abs);
        table.row(name, show(&ours), cells(&theirs, show), "~4° bias", pass);
        table.note(format!(
            "{}; worst at seed/marker {:?}",
            ids(&ours.counts),
            e.worst
        ));
    }
}

/// Row 2: Normal, in-plane rotation and centre errors with tilts 0-60°.
fn normal_rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    println!("2. normal");
    let tilts = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0];
    let (r, theirs) = normal_errors(fam8, &tilts, scale, 9, (80.0, 120.0), 5.0, 300_000, rivals);
    let normal = |r: &NormalResult| {
        format!(
            "mean {:.2}°, max {:.2}°, wrong picks (>5°) {}/{}",
            r.all.mean(),
            r.all.max_abs,
            r.wrong_picks,
            r.all.n
        )
    };
    table.row(
        "2 normal, tilt 0-60° (view angles 0-75°)",
        normal(&r),
        cells(&theirs, normal),
        "up to 17°+ (wrong normal)",
        r.all.max_abs < 1.0
            && r.wrong_picks == 0
            && r.all.n > 0
            && beats(&r, &theirs, |o, t| o.all.max_abs <= t.all.max_abs),
    );
    for (view, e) in &r.per_view {
        table.note(format!(
            "view angle {view:>2}-{:<2}°: mean {:.2}°, max {:.2}° (n={}, worst seed/marker {:?})",
            view + 10.0,
            e.mean(),
            e.max_abs,
            e.n,
            e.worst
        ));
    }
    if let Some(w) = r.first_wrong {
        table.note(format!(
            "first wrong pick: seed {} marker {} error {:.1}°",
            w.0, w.1, w.2
        ));
    }
    let face_on = |r: &NormalResult| {
        let e = r.face_on();
        format!("max {:.2}°, mean {:.2}° (n={})", e.max_abs, e.mean(), e.n)
    };
    table.row(
        "2a normal face-on (view 0-10°)",
        face_on(&r),
        cells(&theirs, face_on),
        "",
        r.face_on().max_abs < 1.0
            && beats(&r, &theirs, |o, t| {
                o.face_on().max_abs <= t.face_on().max_abs
            }),
    );
    let roll = |r: &NormalResult| {
        if r.pose_roll.n == 0 {
            return "no full rotation reported".into();
        }
        format!(
            "bias {:+.2}°, mean abs {:.2}°, max {:.2}° over {}",
            r.pose_roll.mean(),
            r.pose_roll.mean_abs(),
            r.pose_roll.max_abs,
            r.pose_roll.n
        )
    };
    table.row(
        "2b pose rotation about the normal (full pose)",
        roll(&r),
        cells(&theirs, roll),
        "",
        r.pose_roll.max_abs < 1.0 && r.pose_roll.n > 0,
    );
    table.note(format!("worst at seed/marker {:?}", r.pose_roll.worst));
    let centre = |r: &NormalResult| {
        format!(
            "u,v: mean {:.2} px, max {:.2} px; pose projected: mean {:.3} px, max {:.3} px",
            r.centre.mean(),
            r.centre.max_abs,
            r.pose_centre.mean(),
            r.pose_centre.max_abs
        )
    };
    table.row(
        "2c centre error, 80-120 px markers",
        centre(&r),
        cells(&theirs, centre),
        "",
        r.centre.max_abs < 0.5 && beats(&r, &theirs, |o, t| o.centre.max_abs <= t.centre.max_abs),
    );
    table.note(format!("worst u,v at seed/marker {:?}", r.centre.worst));
}

/// Rows 3-6 count what happened to the markers of one scenario each:
/// markers spread over 800x600 (unless said), then the row's look.
fn few(count: usize) -> Spread {
    Spread::tilted(count, (40.0, 90.0), 30.0)
}

/// Row 3: False reports in clutter, 1280x720, a few real markers among it.
fn clutter_rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    println!("3. clutter");
    for (name, target, seed) in [
        (
            "3a false reports/cluttered 1280x720 frame, 8-bit",
            Target::WhyCode(fam8.clone()),
            400_000,
        ),
        (
            "3b false reports/cluttered 1280x720 frame, --bits auto",
            Target::AnyBits { distance: None },
            405_000,
        ),
        (
            "3c false reports/cluttered 1280x720 frame, legacy WhyCon",
            Target::WhyCon,
            410_000,
        ),
    ] {
        let family = match &target {
            Target::WhyCon => None,
            _ => Some(fam8),
        };
        let scenario = Scenario::new(family, few(3), 10 * scale, seed)
            .size(1280, 720)
            .look(|s, _, _| {
                s.background = Background::Clutter { density: 3.0 };
                s.noise = 2.0;
            });
        let mut det = Detector::new(DetectorConfig {
            target,
            ..detector_config(None, &scenario.camera(), false)
        });
        let mut c = Counts::default();
        scenario.run(&mut det, &mut c, |_, _| {});
        let theirs = rival_counts(&scenario, rivals);
        let show = |c: &Counts| {
            format!(
                "{:.2}/frame ({} in {} frames, {} with an ID); real: {}/{}",
                c.false_per_frame(),
                c.false_detections,
                c.frames,
                c.false_with_id,
                c.detected,
                c.markers
            )
        };
        let limit = if family.is_none() { 0.05 } else { 0.0 };
        table.row(
            name,
            show(&c),
            cells(&theirs, show),
            "~2/frame",
            c.false_per_frame() <= limit
                && beats(&c, &theirs, |o, t| o.false_detections <= t.false_detections),
        );
        if let Some(f) = c.first_false {
            table.note(format!("first false report: seed {} at {:.1?}", f.0, f.1));
        }
    }
}

/// Row 4: Dark frames on a dark table top with sensor noise; every other frame
/// a worn, greyer ink. Exposure 0.15-0.35 gives frames with a mean grey of
/// 10-25 (white paper at 33-77); 0.065-0.13 gives means of 5-9 (paper at
/// 14-28). Row 5: a light gradient of `ratio`:1 across the frame in a random
/// direction, plus (with `shadow`) a soft cast shadow at that fraction of
/// the light over part of the frame.
fn light_rows(
    table: &mut Table,
    fam8: &Family,
    scale: usize,
    rivals: &Rivals,
    dark: bool,
    gradient: bool,
) {
    if dark {
        println!("4. dark");
    }
    for (name, exposure, seed) in [
        (
            "4a dark frames, mean grey 10-25, 8-bit",
            (0.15, 0.35),
            500_000,
        ),
        ("4b very dark, mean grey 5-9, 8-bit", (0.065, 0.13), 510_000),
    ]
    .into_iter()
    .filter(|_| dark)
    {
        let mut means = (f64::MAX, f64::MIN);
        let scenario = Scenario::new(Some(fam8), few(8), 8 * scale, seed).look(|s, rng, frame| {
            s.background = Background::Table;
            s.exposure = rng.range(exposure.0, exposure.1);
            s.noise = rng.range(1.0, 2.5);
            if frame % 2 == 1 {
                s.ink_reflectance = 0.15;
            }
        });
        let c = scenario.counts_with(|frame, _| {
            let image = &frame.image;
            let mean =
                image.as_raw().iter().map(|&p| f64::from(p)).sum::<f64>() / image.len() as f64;
            means = (means.0.min(mean), means.1.max(mean));
        });
        let theirs = rival_counts(&scenario, rivals);
        table.row(
            name,
            format!("{} (frame means {:.0}-{:.0})", rates(&c), means.0, means.1),
            cells(&theirs, rates),
            "finds nothing",
            c.detection_rate() >= 0.95 && c.wrong_id == 0 && beats_ids(&c, &theirs),
        );
        table.note(format!("{}; first miss {:?}", ids(&c), c.first_miss));
    }
    if gradient {
        println!("5. gradient");
    }
    for (name, ratio, shadow, seed) in [
        ("5a gradient 3:1, 8-bit", 3.0, None, 600_000),
        ("5b gradient 5:1 + shadow at 40%", 5.0, Some(0.4), 610_000),
        ("5c gradient 8:1 + shadow at 30%", 8.0, Some(0.3), 620_000),
    ]
    .into_iter()
    .filter(|_| gradient)
    {
        let scenario = Scenario::new(Some(fam8), few(8), 8 * scale, seed)
            .look(|s, rng, _| {
                s.background = Background::Table;
                s.gradient = ratio;
                s.gradient_angle = rng.range(0.0, 2.0 * PI);
                s.exposure = 1.1;
                s.noise = 1.5;
            })
            .after_render(|image, rng| {
                if let Some(factor) = shadow {
                    let through = (rng.range(200.0, 600.0), rng.range(150.0, 450.0));
                    cast_shadow(image, through, rng.range(0.0, 2.0 * PI), factor, 12.0);
                }
            });
        let c = scenario.counts();
        let theirs = rival_counts(&scenario, rivals);
        table.row(
            name,
            rates(&c),
            cells(&theirs, rates),
            "loses a third (67%)",
            c.detection_rate() >= 0.95 && c.wrong_id == 0 && beats_ids(&c, &theirs),
        );
        table.note(format!("{}; first miss {:?}", ids(&c), c.first_miss));
    }
}

/// Row 6: Motion blur of `length` px in a random direction on 76-84 px markers
/// in 640x480 (issue 9's targets), then steep views.
fn blur_and_tilt_rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    println!("6. motion blur, steep views");
    for (length, target, seed) in [
        (5.0, 0.95, 710_000),
        (12.0, 0.95, 740_000),
        (15.0, 0.90, 750_000),
        (20.0, 0.60, 760_000),
        (25.0, 0.40, 770_000),
    ] {
        let scenario = Scenario::new(
            Some(fam8),
            Spread::tilted(6, (76.0, 84.0), 30.0),
            6 * scale,
            seed,
        )
        .size(640, 480)
        .look(|s, rng, _| {
            s.motion_blur = Some(MotionBlur {
                length_px: length,
                angle: rng.range(0.0, PI),
            });
            s.noise = 2.0;
        });
        let c = scenario.counts();
        let theirs = rival_counts(&scenario, rivals);
        table.row(
            &format!("6 motion blur {length} px, 76-84 px markers, 8-bit"),
            rates(&c),
            cells(&theirs, rates),
            "misreads IDs",
            c.wrong_id == 0 && c.id_rate() >= target && beats_ids(&c, &theirs),
        );
        if let Some(w) = c.first_wrong {
            table.note(format!("first wrong ID: seed {} marker {}", w.0, w.1));
        }
    }
    let scenario = Scenario::new(
        Some(fam8),
        Spread::fixed_view(6, (60.0, 90.0), 70.0),
        6 * scale,
        780_000,
    )
    .look(|s, _, _| s.noise = 2.0);
    let c = scenario.counts();
    let theirs = rival_counts(&scenario, rivals);
    table.row(
        "6b view 70°, 60-90 px markers, 8-bit",
        rates(&c),
        cells(&theirs, rates),
        "",
        c.correct_id == c.markers && c.markers > 0 && beats_ids(&c, &theirs),
    );
    table.note(format!("{}; first miss {:?}", ids(&c), c.first_miss));
}

/// Row 7: Smallest diameter: markers of one size on 640x480, slight tilts, a
/// little focus blur and noise.
fn smallest_rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    let mut smallest_detect = None;
    let mut smallest_legacy = None;
    let mut smallest_id = None;
    let mut smallest_rival: [Option<f64>; 3] = [None; 3];
    let mut by_size = Vec::new();
    for d in [
        8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 16.0, 18.0, 20.0, 24.0,
    ] {
        let seed = 800_000 + (d as u64) * 100;
        let small = |family, seed| {
            Scenario::new(family, Spread::tilted(20, (d, d), 15.0), scale, seed)
                .size(640, 480)
                .look(|s, _, _| {
                    s.focus_blur_px = 0.5;
                    s.noise = 2.0;
                })
        };
        let legacy = small(None, seed).counts();
        let coded_scenario = small(Some(fam8), seed + 50);
        let coded = coded_scenario.counts();
        let theirs = rival_counts(&coded_scenario, rivals);
        let shown = cells(&theirs, rates).map(|c| c.unwrap_or("not measured".into()));
        table.note(format!(
            "{d:>4} px: legacy detected {}, WhyCode 8-bit detected {}, IDs {} right / {} unknown / {} wrong; AprilTag {}; original {}",
            pct(legacy.detection_rate()),
            pct(coded.detection_rate()),
            pct(coded.id_rate()),
            coded.unknown_id,
            coded.wrong_id,
            shown[0],
            shown[1]
        ));
        if coded.detection_rate() >= 0.9 && smallest_detect.is_none() {
            smallest_detect = Some(d);
        }
        if legacy.detection_rate() >= 0.9 && smallest_legacy.is_none() {
            smallest_legacy = Some(d);
        }
        if coded.id_rate() >= 0.9 && coded.wrong_id == 0 && smallest_id.is_none() {
            smallest_id = Some(d);
        }
        for (slot, t) in smallest_rival.iter_mut().zip(&theirs) {
            if t.as_ref()
                .is_some_and(|t| t.id_rate() >= 0.9 && t.wrong_id == 0)
            {
                slot.get_or_insert(d);
            }
        }
        if [8.0, 10.0, 12.0].contains(&d) {
            by_size.push((d, coded, theirs));
        }
    }
    let px = |d: Option<f64>| d.map_or("-".into(), |d| format!("{d} px"));
    table.row(
        "7 smallest diameter (≥90% of markers)",
        format!(
            "8-bit detected from {}, ID read from {}; legacy detected from {} (the original's size floor)",
            px(smallest_detect),
            px(smallest_id),
            px(smallest_legacy)
        ),
        [0, 1, 2].map(|k| rivals[k].map(|_| format!("ID read from {}", px(smallest_rival[k])))),
        "stops at 16 px",
        smallest_detect.is_some_and(|d| d < 16.0)
            && smallest_legacy.is_some_and(|d| d < 16.0)
            && smallest_id
                .is_some_and(|d| d <= 12.0 && smallest_rival.iter().flatten().all(|&t| d <= t)),
    );
    for (d, ours, theirs) in by_size {
        let (target_id, target_detect) = match d as u32 {
            8 => (0.0, 0.75),
            10 => (0.75, 0.0),
            _ => (0.95, 0.0),
        };
        table.row(
            &format!("7 {d} px markers, 8-bit"),
            rates(&ours),
            cells(&theirs, rates),
            "IDs from 16 px",
            ours.id_rate() >= target_id
                && ours.detection_rate() >= target_detect
                && ours.wrong_id == 0
                && beats_ids(&ours, &theirs),
        );
    }
}
