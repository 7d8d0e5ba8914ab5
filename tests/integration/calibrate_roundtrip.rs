//! `whycode calibrate` on simulated photos of an A4 sheet through a
//! strongly distorting lens: the camera comes back, in every format
//! `detect --camera` reads, and each refusal is one line.

use std::path::{Path, PathBuf};

use crate::support::{run_err, run_ok};
use whycode::calibrate::disagreement;
use whycode::camera::Camera;
use whycode::simulate::layout;
use whycode_testkit::calibration;

/// The sheet's manifest and `placements`' photos of it, written into `dir`.
fn photos(dir: &Path, placements: &[whycode::simulate::Placement]) -> (PathBuf, Vec<PathBuf>) {
    let truth = calibration::lens();
    let manifest = calibration::a4_sheet();
    let manifest_path = dir.join("sheet.json");
    std::fs::write(&manifest_path, serde_json::to_string(&manifest).unwrap()).unwrap();
    let paths = placements
        .iter()
        .enumerate()
        .map(|(k, placement)| {
            let path = dir.join(format!("view{k:02}.png"));
            calibration::sheet_view(&truth, &manifest, *placement, 7 + k as u64)
                .save(&path)
                .unwrap();
            path
        })
        .collect();
    (manifest_path, paths)
}

fn args<'a>(manifest: &'a Path, photos: &'a [PathBuf], out: &'a Path) -> Vec<&'a str> {
    let mut args = vec!["calibrate", "--manifest", manifest.to_str().unwrap()];
    args.extend(photos.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", out.to_str().unwrap()]);
    args
}

#[test]
fn calibration_recovers_a_known_camera() {
    let dir = tempfile::tempdir().unwrap();
    let truth = calibration::lens();
    let (manifest, photos) = photos(dir.path(), &calibration::views(&truth, 20, 3));
    let out = dir.path().join("camera.yaml");
    let report = run_ok(&args(&manifest, &photos, &out));
    assert!(report.contains("overall RMS"), "{report}");
    let camera = Camera::load(&out).unwrap();
    let d = disagreement(&truth, &camera);
    let focal = (camera.fx / truth.fx - 1.0)
        .abs()
        .max((camera.fy / truth.fy - 1.0).abs());
    // The targets (mean < 0.05 px, worst < 0.2 px, focal within
    // 0.01 %) are what examples/calibration_bar measures over seeds; the
    // round trip holds twice that on its one draw of views and noise.
    assert!(d.mean < 0.1 && d.worst < 0.4, "{d:?}\n{report}");
    assert!(
        focal < 2e-4,
        "focal off by {:.4} %\n{report}",
        100.0 * focal
    );

    // The other formats carry the same camera to `detect --camera`.
    for name in ["camera.yml", "camera.xml"] {
        let other = dir.path().join(name);
        run_ok(&args(&manifest, &photos, &other));
        assert_eq!(Camera::load(&other).unwrap(), camera, "{name}");
    }
}

#[test]
fn each_refusal_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let truth = calibration::lens();
    let out = dir.path().join("camera.yaml");
    let tilted = calibration::views(&truth, 2, 5);
    let (manifest, two) = photos(dir.path(), &tilted);
    let err = run_err(&args(&manifest, &two, &out));
    assert!(err.contains("only 2 usable views (3 needed)"), "{err}");

    let face_on: Vec<_> = [(0.0, 0.0), (0.03, -0.02), (-0.03, 0.02), (0.02, 0.03)]
        .iter()
        .enumerate()
        .map(|(k, &(x, y))| {
            let mut p = layout::centred(0.45 + 0.03 * k as f64, 0.0, 0.0, 0.3 * k as f64);
            p.position.x += x;
            p.position.y += y;
            p
        })
        .collect();
    let flat = tempfile::tempdir().unwrap();
    let (manifest, photos) = photos(flat.path(), &face_on);
    let err = run_err(&args(&manifest, &photos, &out));
    assert!(err.contains("fronto-parallel"), "{err}");
    assert!(
        !out.exists(),
        "a refused calibration wrote {}",
        out.display()
    );
}
