//! How far the calibration's marker centres land from where the true
//! camera projects the markers' centres, on the calibration bar's views:
//! with the live detector's 48 rays a circle and with rays at every pixel
//! (`DetectorConfig::fine_edges`), on views rendered at 4×4, 8×8 and 16×16
//! samples a pixel, with and without the views' sensor noise. It separates
//! what the detector gets wrong from what the renderer does
//! (docs/calibration.md).
//!
//!     cargo run --release --example calibration_centres [-- VIEWS SEED]

use whycode::calibrate::{observe, sheet_detector, Posed};
use whycode::detect::{Detector, DetectorConfig};
use whycode::simulate::{self, Placement, SceneObject, SheetPage};
use whycode_testkit::calibration;

/// Root mean square and median distance, pixels, of every detected centre
/// from the truth over `placements`' views.
fn centre_errors(
    config: &DetectorConfig,
    placements: &[Placement],
    seed: u64,
    samples: u32,
    noise: f64,
) -> (f64, f64) {
    let truth = calibration::lens();
    let manifest = calibration::a4_sheet();
    let posed = Posed {
        camera: &truth,
        diameter_m: config.diameter_m.expect("the sheet detector poses"),
    };
    let mut errors = Vec::new();
    for (k, placement) in placements.iter().enumerate() {
        let page = SheetPage::new(manifest.clone(), 1, *placement);
        let mut scene = calibration::scene(&truth, SceneObject::Page(page), seed * 1000 + k as u64);
        scene.noise = noise;
        scene.supersampling = samples;
        let image = simulate::render(&scene).0;
        let found = Detector::new(config.clone()).detect(&image);
        for view in observe(&manifest, "view", &found, 1.0, Some(posed)) {
            for (id, [u, v]) in view.ids.iter().zip(&view.pixels) {
                let m = manifest
                    .markers
                    .iter()
                    .find(|m| m.id == *id)
                    .expect("an ID");
                let (tu, tv) = calibration::projected_centre(&truth, placement, m)
                    .expect("in front of the camera");
                errors.push((u - tu).hypot(v - tv));
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    (rms, errors[errors.len() / 2])
}

fn main() {
    let mut args = std::env::args().skip(1);
    let count: usize = args
        .next()
        .map_or(10, |a| a.parse().expect("VIEWS is a number"));
    let seed: u64 = args
        .next()
        .map_or(9, |a| a.parse().expect("SEED is a number"));
    let truth = calibration::lens();
    let placements = calibration::views(&truth, count, seed);
    let fine = sheet_detector(&calibration::a4_sheet(), Some(truth)).expect("a WhyCode sheet");
    let live = DetectorConfig {
        fine_edges: false,
        ..fine.clone()
    };
    println!("{count} views, seed {seed}: centres through the true camera, px (rms / median)");
    println!(
        "{:>10} {:>6} {:>18} {:>18}",
        "samples", "noise", "48 rays", "rays every pixel"
    );
    for (samples, noise) in [(4, 0.0), (8, 0.0), (16, 0.0), (4, 1.5), (8, 1.5)] {
        let (a, b) = centre_errors(&live, &placements, seed, samples, noise);
        let (c, d) = centre_errors(&fine, &placements, seed, samples, noise);
        println!(
            "{:>10} {noise:>6} {:>18} {:>18}",
            format!("{samples}x{samples}"),
            format!("{a:.4} / {b:.4}"),
            format!("{c:.4} / {d:.4}")
        );
    }
}
