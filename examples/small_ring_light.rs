//! The spread of `ring::model::light_elongation` on real small rings and
//! on letters, behind `MAX_LIGHT_ELONGATION` (issue 25's 11 px 'O'):
//!
//!     cargo run --release --example small_ring_light [-- rings|letters]
//!
//! `rings`: every ring of 8-14 px the 8-bit detector reports on the
//! detector bar's row 7 scenes (its full run's frames and seeds) and every
//! ring under 14 px across its minor axis on row 9's 20 and 30 px cells
//! (3 frames each, the bar's seeds). `letters`: every candidate of 7.5 px
//! and more in lines of "O O O 0 0 o o o" in the stroke font (9-14.5 pt,
//! pens 1.6-2.6 times the font's, paper 0.86 or 0.45, ink 20 or 50),
//! with `report_unreadable` so that the letters refuted before this test
//! count too. Prints the minimum, 5th, 50th and 95th percentile and the
//! maximum of each set, and the reported letters.

use whycode::camera::Camera;
use whycode::detect::ring::model::{light_elongation, MAX_LIGHT_ELONGATION};
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::math::Ellipse;
use whycode::simulate::{render, Background, Scene};
use whycode_testkit::desk;
use whycode_testkit::scenario::{
    defocused, detector, Print, Scenario, Spread, DEFOCUS_SIGMAS, DEFOCUS_SIZES, DEFOCUS_VIEWS,
};

fn outline(d: &Detection) -> Ellipse {
    Ellipse {
        u: d.u,
        v: d.v,
        semi_major: d.axes[0],
        semi_minor: d.axes[1],
        angle: d.angle,
    }
}

fn spread(name: &str, mut values: Vec<f64>) {
    if values.is_empty() {
        println!("{name}: none");
        return;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    let at = |k: usize| values[k.min(n - 1)];
    println!(
        "{name}: {n}, min {:+.3}, p5 {:+.3}, median {:+.3}, p95 {:+.3}, max {:+.3}, over {MAX_LIGHT_ELONGATION}: {}",
        at(0),
        at(n / 20),
        at(n / 2),
        at(n - 1 - n / 20),
        at(n - 1),
        values.iter().filter(|&&e| e > MAX_LIGHT_ELONGATION).count()
    );
}

/// Light elongations of the reports on `scenario` that lie on a true
/// marker, those under `max_minor_px` across their minor axis.
fn real_rings(scenario: &Scenario<'_>, family: &Family, max_minor_px: f64) -> Vec<f64> {
    let mut det = detector(Some(family), &scenario.camera(), false);
    let mut out = Vec::new();
    for f in 0..scenario.frames {
        let frame = scenario.frame(f, Print::WhyCode);
        for d in det.detect(&frame.image) {
            let on_marker = frame
                .targets
                .iter()
                .any(|t| (t.u - d.u).hypot(t.v - d.v) < 0.3 * t.size_px + 1.0);
            if on_marker && 2.0 * d.axes[1] < max_minor_px {
                out.extend(light_elongation(&frame.image, &outline(&d)));
            }
        }
    }
    out
}

fn main() {
    let what = std::env::args().nth(1).unwrap_or_default();
    let fam8 = Family::generate(8, 2).unwrap();
    if what.is_empty() || what == "rings" {
        let mut all = Vec::new();
        for d in [8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0] {
            // Row 7's coded scenes (examples/detector_bar/main.rs).
            let seed = 800_000 + (d as u64) * 100 + 50;
            let scenario = Scenario::new(Some(&fam8), Spread::tilted(20, (d, d), 15.0), 3, seed)
                .size(640, 480)
                .look(|s, _, _| {
                    s.focus_blur_px = 0.5;
                    s.noise = 2.0;
                });
            let e = real_rings(&scenario, &fam8, f64::INFINITY);
            spread(&format!("row 7, {d} px"), e.clone());
            all.extend(e);
        }
        let mut cell = 0u64;
        let mut row9 = Vec::new();
        for &size in &DEFOCUS_SIZES {
            for &view in &DEFOCUS_VIEWS {
                for &sigma in &DEFOCUS_SIGMAS {
                    let seed = 1_000_000 + 100 * cell;
                    cell += 1;
                    if size <= 30.0 {
                        let scenario = defocused(&fam8, size, view, sigma, 3, seed);
                        row9.extend(real_rings(&scenario, &fam8, 14.0));
                    }
                }
            }
        }
        spread("row 9, minor axis under 14 px", row9.clone());
        all.extend(row9);
        spread("all real rings", all);
    }
    if what.is_empty() || what == "letters" {
        let cam = Camera::ideal(1280, 720, 60.0);
        let mut letters = Vec::new();
        for paper in [0.86, 0.45] {
            for ink in [20.0, 50.0] {
                for k in 0..12 {
                    for j in (0..12).step_by(2) {
                        let (size_pt, weight) = (9.0 + 0.5 * k as f64, 1.6 + 0.1 * j as f64);
                        let mut scene = Scene::new(cam);
                        scene.background = Background::Uniform(paper);
                        scene.noise = 2.0;
                        scene.seed = (100 * k + j) as u64;
                        let (mut image, _) = render(&scene);
                        let text = "O O O 0 0 o o o";
                        desk::stroke_letters(
                            &mut image,
                            text,
                            (100.0, 400.0),
                            size_pt,
                            weight,
                            ink,
                        );
                        let found = Detector::new(DetectorConfig {
                            target: Target::WhyCode(fam8.clone()),
                            report_unreadable: true,
                            ..Default::default()
                        })
                        .detect(&image);
                        for d in found.iter().filter(|d| 2.0 * d.axes[0] >= 7.5) {
                            letters.extend(light_elongation(&image, &outline(d)));
                            if !d.unreadable {
                                println!(
                                    "reported: paper {paper}, ink {ink}, {size_pt} pt, pen x{weight:.1}: {:.1} x {:.1} px, ID {}",
                                    2.0 * d.axes[0],
                                    2.0 * d.axes[1],
                                    d.id
                                );
                            }
                        }
                    }
                }
            }
        }
        spread("letter candidates", letters);
    }
}
