//! `whycode simulate` and `whycode validate` end to end through the binary:
//! files in, report and exit status out.

use std::path::Path;

use crate::support::{sheets, whycode, whycode_in};

fn simulate_photo(dir: &Path, name: &str, extra: &[&str]) -> String {
    let manifest = dir.join("sheet.json");
    sheets::a4_manifest().save(&manifest).unwrap();
    let photo = dir.join(name);
    let mut args = vec![
        "simulate",
        "--manifest",
        manifest.to_str().unwrap(),
        "--size",
        "1600x1200",
        "--tilt",
        "20deg",
        "--pan",
        "-10deg",
        "--blur",
        "1px",
        "--noise",
        "3",
        "--gradient",
        "2.5",
        "-o",
        photo.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = whycode(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(photo.exists() && photo.with_extension("json").exists());
    photo.to_str().unwrap().to_string()
}

#[test]
fn simulated_photo_validates_with_exit_0_and_annotates() {
    let dir = tempfile::tempdir().unwrap();
    let photo = simulate_photo(dir.path(), "good.jpg", &["--jpeg", "90"]);
    let manifest = dir.path().join("sheet.json");
    let annotated = dir.path().join("out");
    let out = whycode(&[
        "validate",
        "--manifest",
        manifest.to_str().unwrap(),
        &photo,
        "--annotate",
        annotated.to_str().unwrap(),
        "--format",
        "json",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["ok"], true);
    assert_eq!(report["counts"]["found"], 12);
    let picture = image::open(annotated.join("good.annotated.png")).unwrap();
    assert_eq!((picture.width(), picture.height()), (1600, 1200));
}

#[test]
fn shrunken_print_and_blot_fail_with_exit_2_and_a_readable_table() {
    let dir = tempfile::tempdir().unwrap();
    let photo = simulate_photo(
        dir.path(),
        "bad.png",
        &["--print-scale", "95%", "--blot", "8"],
    );
    let manifest = dir.path().join("sheet.json");
    let out = whycode(&["validate", "--manifest", manifest.to_str().unwrap(), &photo]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{stdout}");
    assert!(stdout.contains("printed at 95."), "{stdout}");
    let line8 = stdout
        .lines()
        .find(|l| l.starts_with("8 "))
        .unwrap_or_else(|| panic!("no line for marker 8 in\n{stdout}"));
    assert!(
        line8.contains("unidentified") || line8.contains("misread"),
        "{stdout}"
    );
}

#[test]
fn bad_input_is_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.json");
    let out = whycode(&["validate", "--manifest", missing.to_str().unwrap(), "x.jpg"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with("whycode: error: ") && stderr.lines().count() == 1,
        "{stderr}"
    );
    let out = whycode(&["simulate", "--bits", "8", "--ids", "1-40", "-o", "x.png"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr)
        .contains("--ids: ID 17 is not in the 8-bit distance-2 family (IDs 1-16)"));
}

/// The README's own flow: the default sheet (12 markers on page 1, 4 on
/// page 2), photographed page by page. A page of four markers cannot be
/// pinned by their centres alone (four points fit any homography exactly),
/// so this also covers locating a page by the markers' rims and measuring
/// its scale by the discs' size against the paper.
#[test]
fn default_sheet_validates_including_its_four_marker_page() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| whycode_in(dir.path(), args);
    assert!(run(&["sheet"]).status.success());
    for (page, name, scale) in [
        ("1", "p1.png", "100%"),
        ("2", "p2.png", "100%"),
        ("2", "p2-97.png", "97%"),
    ] {
        let out = run(&[
            "simulate",
            "--manifest",
            "swarm.json",
            "--page",
            page,
            "--tilt",
            "20deg",
            "--pan",
            "10deg",
            "--noise",
            "3",
            "--blur",
            "1px",
            "--print-scale",
            scale,
            "-o",
            name,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let out = run(&["validate", "--manifest", "swarm.json", "p1.png", "p2.png"]);
    let table = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{table}");
    assert!(table.contains("16 printed: 16 found"), "{table}");

    let out = run(&[
        "validate",
        "--manifest",
        "swarm.json",
        "--format",
        "json",
        "p2-97.png",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let page2 = report["pages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["page"] == 2)
        .unwrap();
    let scale = page2["scale"].as_f64().unwrap();
    assert!((scale - 0.97).abs() < 0.005, "page 2 measured at {scale}");
    assert_eq!(page2["scale_status"], "error", "{page2}");
}

#[test]
fn simulate_refuses_to_overwrite_the_sheet_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("sheet.json");
    sheets::a4_manifest().save(&manifest).unwrap();
    let before = std::fs::read(&manifest).unwrap();
    let out = whycode(&[
        "simulate",
        "--manifest",
        manifest.to_str().unwrap(),
        "-o",
        dir.path().join("sheet.png").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("is a sheet manifest"), "{stderr}");
    assert_eq!(std::fs::read(&manifest).unwrap(), before);
    assert!(!dir.path().join("sheet.png").exists());
}

/// Objects lying around the paper, some touching its edges, must not be
/// taken for the paper's edge, nor the sheet's own scale bar and caption
/// (printed by the simulator from the real layout): the printed scale reads
/// right within 0.5 %. (Seeds 1 and 3 once read 97.8 % and 98.9 % for a
/// perfect print, and the scale bar alone once made 101-102 %.)
#[test]
fn clutter_beside_the_paper_does_not_bend_the_scale() {
    let dir = tempfile::tempdir().unwrap();
    let out = whycode_in(dir.path(), &["sheet", "--ids", "1-12", "-o", "sheet.pdf"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let manifest = dir.path().join("sheet.json");
    for seed in ["1", "3"] {
        for (print_scale, expected) in [("100%", 1.0), ("97%", 0.97)] {
            let photo = dir.path().join(format!("clutter-{seed}-{print_scale}.png"));
            let out = whycode(&[
                "simulate",
                "--manifest",
                manifest.to_str().unwrap(),
                "--tilt",
                "20deg",
                "--pan",
                "-15deg",
                "--background",
                "clutter",
                "--seed",
                seed,
                "--print-scale",
                print_scale,
                "-o",
                photo.to_str().unwrap(),
            ]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let out = whycode(&[
                "validate",
                "--manifest",
                manifest.to_str().unwrap(),
                "--format",
                "json",
                photo.to_str().unwrap(),
            ]);
            let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            let scale = report["pages"][0]["scale"].as_f64().unwrap();
            assert!(
                (scale - expected).abs() < 0.005,
                "seed {seed}, printed at {print_scale}: measured {scale}"
            );
        }
    }
}

/// A page holding one large marker: its rim locates the page, the paper
/// corners found near it pin the rest, and the disc's printed size gives the
/// scale (it read "unknown" when only the marker pinned the page).
#[test]
fn a_page_with_one_marker_is_located_and_measured() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| whycode_in(dir.path(), args);
    assert!(
        run(&["sheet", "--ids", "7", "--diameter", "60mm", "-o", "one.pdf"])
            .status
            .success()
    );
    let out = run(&[
        "simulate",
        "--manifest",
        "one.json",
        "--tilt",
        "30deg",
        "--pan",
        "10deg",
        "--noise",
        "4",
        "-o",
        "view.png",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(&[
        "validate",
        "--manifest",
        "one.json",
        "--format",
        "json",
        "view.png",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(0), "{report}");
    let scale = report["pages"][0]["scale"].as_f64().unwrap();
    assert!((scale - 1.0).abs() < 0.005, "measured {scale}");
}
