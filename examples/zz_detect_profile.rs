#[path = "../tests/detect_common/mod.rs"]
mod detect_common;
use detect_common::{render, scatter, Look, Pinhole, Rng};
use whycode::detect::{Detector, DetectorConfig};
use whycode::family::Family;
use whycode::geometry::Marker;
fn main() {
    let path = std::path::Path::new("/tmp/big_scene.png");
    let image = if path.exists() {
        image::open(path).unwrap().into_luma8()
    } else {
        let codes = Family::generate(8, 2).unwrap().codes().to_vec();
        let camera = Pinhole {
            f: 5000.0,
            cx: 2500.0,
            cy: 2500.0,
        };
        let mut rng = Rng(5000);
        let placements = scatter(
            &mut rng,
            &camera,
            5000,
            5000,
            550,
            (60.0, 120.0),
            &mut |k| Marker::whycode(8, codes[k % codes.len()], 100.0),
        );
        let img = render(
            5000,
            5000,
            &camera,
            &placements,
            Look {
                gradient_right: 0.5,
                blur: 1,
                noise: 2.0,
                ..Look::default()
            },
        );
        img.save(path).unwrap();
        img
    };
    let mode = std::env::args().nth(1).unwrap_or_default();
    let family = Some(Family::generate(8, 2).unwrap());
    let legacy = mode.contains("legacy");
    let mut det = Detector::new(DetectorConfig {
        family: if legacy { None } else { family },
        tracking: mode.contains("track"),
        max_markers: 550,
        ..Default::default()
    });
    let cpu = || {
        let s = std::fs::read_to_string("/proc/self/stat").unwrap();
        let f: Vec<&str> = s.rsplit(')').next().unwrap().split_whitespace().collect();
        f[11].parse::<f64>().unwrap() * 10.0
    };
    let n = det.detect(&image).len();
    let c0 = cpu();
    let t = std::time::Instant::now();
    for _ in 0..20 {
        det.detect(&image);
    }
    eprintln!(
        "{n} markers: {:.1} ms cpu, {:.1} ms wall per frame",
        (cpu() - c0) / 20.0,
        t.elapsed().as_secs_f64() * 1e3 / 20.0
    );
}
