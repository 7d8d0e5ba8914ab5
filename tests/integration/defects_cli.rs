//! Regression tests for the defects a new user found (issue 10): outputs
//! that overwrote inputs or landed half, misleading results and messages.

use std::path::Path;
use std::process::Output;

use crate::support::{stderr, stdout, tool_marker_png, whycode_in};

fn ok(out: &Output) {
    assert!(out.status.success(), "{}", stderr(out));
}

#[test]
fn detect_annotate_into_the_inputs_folder_keeps_the_input() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let before = std::fs::read(dir.path().join("view.png")).unwrap();
    ok(&whycode_in(
        dir.path(),
        &["detect", "--annotate", ".", "view.png"],
    ));
    assert_eq!(std::fs::read(dir.path().join("view.png")).unwrap(), before);
    let annotated = image::open(dir.path().join("view.annotated.png")).unwrap();
    assert_eq!(annotated.color(), image::ColorType::Rgb8);
    // Annotating the annotated copy too must not replace it either.
    let first = std::fs::read(dir.path().join("view.annotated.png")).unwrap();
    ok(&whycode_in(
        dir.path(),
        &[
            "detect",
            "--annotate",
            ".",
            "view.png",
            "view.annotated.png",
        ],
    ));
    assert_eq!(std::fs::read(dir.path().join("view.png")).unwrap(), before);
    assert_eq!(
        std::fs::read(dir.path().join("view.annotated.png")).unwrap(),
        first
    );
    assert!(dir.path().join("view-2.annotated.png").is_file());
}

#[cfg(unix)]
#[test]
fn sheet_whose_pages_cannot_be_written_leaves_no_manifest() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink("/dev/full", dir.path().join("m.pdf")).unwrap();
    let args = ["sheet", "--ids", "1-2", "--no-check", "-o", "m.pdf"];
    let out = whycode_in(dir.path(), &args);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("m.pdf"), "{}", stderr(&out));
    assert!(
        !dir.path().join("m.json").exists(),
        "orphan manifest written"
    );
    // An older manifest stays as it was.
    std::fs::write(dir.path().join("m.json"), "old").unwrap();
    let out = whycode_in(dir.path(), &args);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("m.json")).unwrap(),
        "old"
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        2,
        "temporary files left"
    );
}

#[test]
fn outputs_under_a_regular_file_fail_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("plain"), "x").unwrap();
    for args in [
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "1",
            "--diameter",
            "20mm",
            "-o",
            "plain/m.svg",
        ][..],
        &["sheet", "--ids", "1-2", "--no-check", "-o", "plain/s.pdf"][..],
        &["ids", "--bits", "8", "-o", "plain/ids.txt"][..],
    ] {
        let out = whycode_in(dir.path(), args);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {}", stderr(&out));
        let err = stderr(&out);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.contains("plain is a file, not a folder"),
            "{args:?}: {err}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(dir.path().join("plain")).unwrap(),
        "x"
    );
}

#[test]
fn long_codes_pass_the_self_check_at_an_ordinary_size() {
    let dir = tempfile::tempdir().unwrap();
    for (bits, id, diameter, name) in [
        ("20", "1", "50mm", "b20.pdf"),
        ("24", "3", "60mm", "b24.svg"),
    ] {
        let args = [
            "marker",
            "--bits",
            bits,
            "--id",
            id,
            "--diameter",
            diameter,
            "-o",
            name,
        ];
        let out = whycode_in(dir.path(), &args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        assert!(dir.path().join(name).is_file());
    }
    let out = whycode_in(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "20",
            "--ids",
            "1-3",
            "--diameter",
            "50mm",
            "-o",
            "s20.pdf",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn scatter_places_every_marker_or_says_how_many_did_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let out = whycode_in(
        dir.path(),
        &[
            "simulate",
            "--bits",
            "12",
            "--distance",
            "1",
            "--ids",
            "1-300",
            "--layout",
            "scatter",
            "-o",
            "crowd.png",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("of 300 markers fit"), "{err}");
    assert!(!dir.path().join("crowd.png").exists());
    assert!(!dir.path().join("crowd.json").exists());
    // A scatter that fits has every marker in its ground truth.
    let out = whycode_in(
        dir.path(),
        &[
            "simulate", "--bits", "8", "--ids", "1-16", "--layout", "scatter", "-o", "ok.png",
        ],
    );
    ok(&out);
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("ok.json")).unwrap()).unwrap();
    assert_eq!(truth["markers"].as_array().unwrap().len(), 16);
}

#[test]
fn an_edge_on_board_is_not_in_view() {
    let dir = tempfile::tempdir().unwrap();
    let out = whycode_in(
        dir.path(),
        &[
            "simulate", "--bits", "8", "--ids", "1-4", "--tilt", "90deg", "-o", "edge.png",
        ],
    );
    ok(&out);
    assert!(
        stdout(&out).contains("0 wholly in view"),
        "{}",
        stdout(&out)
    );
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("edge.json")).unwrap()).unwrap();
    for m in truth["markers"].as_array().unwrap() {
        assert_eq!(m["visible"], false, "{m}");
    }
    // Nothing is drawn: the image is the plain background.
    let image = image::open(dir.path().join("edge.png")).unwrap().to_luma8();
    let (lo, hi) = image
        .pixels()
        .fold((255u8, 0u8), |(lo, hi), p| (lo.min(p.0[0]), hi.max(p.0[0])));
    assert!(hi - lo < 40, "something was drawn: grey levels {lo}..{hi}");
}

fn calibration(dir: &Path, name: &str, matrix: &str, distortion: &str) {
    let text = format!(
        "image_width: 640\nimage_height: 480\n\
         camera_matrix: {{rows: 3, cols: 3, data: [{matrix}]}}\n\
         distortion_coefficients: {{rows: 1, cols: 5, data: [{distortion}]}}\n"
    );
    std::fs::write(dir.join(name), text).unwrap();
}

#[test]
fn absurd_calibrations_are_refused_naming_the_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    ok(&whycode_in(
        dir.path(),
        &[
            "simulate", "--bits", "8", "--ids", "1-4", "--size", "640x480", "-o", "v.png",
        ],
    ));
    let lens = "600, 0, 319.5, 0, 600, 239.5, 0, 0, 1";
    for (name, matrix, distortion, field) in [
        (
            "huge_k1.yaml",
            lens,
            "1e30, 0, 0, 0, 0",
            "distortion_coefficients",
        ),
        (
            "folding.yaml",
            lens,
            "-2, 0, 0, 0, 0",
            "distortion_coefficients",
        ),
        (
            "nan.yaml",
            lens,
            ".nan, 0, 0, 0, 0",
            "distortion_coefficients",
        ),
        (
            "fx.yaml",
            "1e308, 0, 319.5, 0, 600, 239.5, 0, 0, 1",
            "0, 0, 0, 0, 0",
            "fx",
        ),
        (
            "cx.yaml",
            "600, 0, 1e9, 0, 600, 239.5, 0, 0, 1",
            "0, 0, 0, 0, 0",
            "cx",
        ),
    ] {
        calibration(dir.path(), name, matrix, distortion);
        let out = whycode_in(
            dir.path(),
            &["detect", "--camera", name, "--diameter", "50mm", "v.png"],
        );
        assert_eq!(out.status.code(), Some(1), "{name}: {}", stdout(&out));
        let err = stderr(&out);
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name) && err.contains(field), "{name}: {err}");
        assert!(err.len() < 300, "{name}: {err}");
    }
    // A real lens passes and gives poses about a metre away.
    calibration(dir.path(), "good.yaml", lens, "-0.3, 0.1, 0, 0, 0");
    let out = whycode_in(
        dir.path(),
        &[
            "detect",
            "--camera",
            "good.yaml",
            "--diameter",
            "50mm",
            "--format",
            "csv",
            "v.png",
        ],
    );
    ok(&out);
    let rows: Vec<String> = stdout(&out).lines().skip(1).map(String::from).collect();
    assert_eq!(rows.len(), 4, "{}", stdout(&out));
    for row in rows {
        let z: f64 = row.split(',').nth(11).unwrap().parse().unwrap();
        assert!((0.8..1.4).contains(&z), "{row}");
    }
}

#[test]
fn detect_applies_validates_rule_for_a_calibration_of_another_size() {
    let dir = tempfile::tempdir().unwrap();
    calibration(
        dir.path(),
        "cam.yaml",
        "600, 0, 319.5, 0, 600, 239.5, 0, 0, 1",
        "0, 0, 0, 0, 0",
    );
    let pose_z = |image: &str| -> Vec<f64> {
        let out = whycode_in(
            dir.path(),
            &[
                "detect",
                "--camera",
                "cam.yaml",
                "--diameter",
                "50mm",
                "--format",
                "csv",
                image,
            ],
        );
        ok(&out);
        stdout(&out)
            .lines()
            .skip(1)
            .map(|r| r.split(',').nth(11).unwrap().parse().unwrap())
            .collect()
    };
    for size in ["640x480", "1280x960"] {
        ok(&whycode_in(
            dir.path(),
            &[
                "simulate",
                "--bits",
                "8",
                "--ids",
                "1-4",
                "--size",
                size,
                "--fov",
                "56.145deg",
                "-o",
                &format!("{size}.png"),
            ],
        ));
    }
    // The same sensor at twice the resolution: rescaled, same distances.
    let (small, large) = (pose_z("640x480.png"), pose_z("1280x960.png"));
    assert_eq!(small.len(), 4);
    assert_eq!(large.len(), 4);
    for z in small.iter().chain(&large) {
        assert!((z - 1.0).abs() < 0.03, "{small:?} {large:?}");
    }
    // Another aspect ratio: refused, naming the image.
    ok(&whycode_in(
        dir.path(),
        &[
            "simulate",
            "--bits",
            "8",
            "--ids",
            "1-4",
            "--size",
            "1920x1080",
            "-o",
            "wide.png",
        ],
    ));
    let out = whycode_in(
        dir.path(),
        &[
            "detect",
            "--camera",
            "cam.yaml",
            "--diameter",
            "50mm",
            "wide.png",
        ],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out)
            .contains("wide.png: image is 1920x1080 but the camera calibration is for 640x480"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn validate_refuses_broken_manifests_and_words_its_notes() {
    let dir = tempfile::tempdir().unwrap();
    ok(&whycode_in(
        dir.path(),
        &[
            "sheet",
            "--ids",
            "1-4",
            "--diameter",
            "40mm",
            "-o",
            "four.pdf",
        ],
    ));
    ok(&whycode_in(
        dir.path(),
        &[
            "simulate",
            "--manifest",
            "four.json",
            "--print-scale",
            "0.98",
            "-o",
            "p98.png",
        ],
    ));
    let out = whycode_in(
        dir.path(),
        &["validate", "--manifest", "four.json", "p98.png"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let table = stdout(&out);
    assert!(!table.contains("size. "), "{table}");
    assert!(
        table.contains("printed at 97.9 % of the intended size; measured from the size of 4 discs"),
        "{table}"
    );

    let original: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("four.json")).unwrap()).unwrap();
    let broken = |edit: &dyn Fn(&mut serde_json::Value), expected: &str| {
        let mut m = original.clone();
        edit(&mut m);
        std::fs::write(dir.path().join("bad.json"), m.to_string()).unwrap();
        let out = whycode_in(
            dir.path(),
            &["validate", "--manifest", "bad.json", "p98.png"],
        );
        assert_eq!(out.status.code(), Some(1), "{expected}: {}", stdout(&out));
        let err = stderr(&out);
        assert!(
            err.contains("bad.json") && err.contains(expected),
            "{expected}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    };
    broken(
        &|m| m["markers"][1]["id"] = 999.into(),
        "ID 999 on page 1 is not in the 8-bit family",
    );
    broken(
        &|m| m["markers"][1]["id"] = 0.into(),
        "ID 0 on page 1 is not in the 8-bit family",
    );
    broken(
        &|m| m["markers"][1]["code"] = 11.into(),
        "has code 11, but ID 2 is code 7",
    );
    broken(
        &|m| {
            m["markers"][1]["x_mm"] = m["markers"][0]["x_mm"].clone();
            m["markers"][1]["y_mm"] = m["markers"][0]["y_mm"].clone();
        },
        "markers ID 1 and ID 2 on page 1 overlap",
    );
    broken(&|m| m["pages"] = 0.into(), "pages is 0");
}

#[test]
fn detect_table_is_sorted_by_id() {
    let dir = tempfile::tempdir().unwrap();
    ok(&whycode_in(
        dir.path(),
        &[
            "simulate", "--bits", "8", "--ids", "1-12", "--roll", "200deg", "-o", "v.png",
        ],
    ));
    let out = whycode_in(dir.path(), &["detect", "v.png"]);
    ok(&out);
    let ids: Vec<u32> = stdout(&out)
        .lines()
        .skip(1)
        .map(|l| l.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(ids, (1..=12).collect::<Vec<_>>(), "{}", stdout(&out));
}

/// Found by the fuzz harness: both ran for hours.
#[test]
fn absurd_template_gaps_and_manifest_pages_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let a4 =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/templates/a4.toml")).unwrap();
    let huge_gap = a4.replace("gap = \"3mm\"", "gap = \"4294967296mm\"");
    assert_ne!(huge_gap, a4);
    std::fs::write(dir.path().join("gap.toml"), huge_gap).unwrap();
    let out = whycode_in(
        dir.path(),
        &[
            "sheet",
            "--template",
            "gap.toml",
            "--ids",
            "1-3",
            "--no-check",
            "-o",
            "t.pdf",
        ],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("gap.toml: gap 4294967296 mm is wider than the page"),
        "{}",
        stderr(&out)
    );

    ok(&whycode_in(
        dir.path(),
        &["sheet", "--ids", "1-3", "--no-check", "-o", "s.pdf"],
    ));
    let mut m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("s.json")).unwrap()).unwrap();
    m["page_size_mm"][0] = 4294967296u64.into();
    std::fs::write(dir.path().join("big.json"), m.to_string()).unwrap();
    let out = whycode_in(
        dir.path(),
        &["simulate", "--manifest", "big.json", "-o", "v.png"],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("big.json: page size 4294967296 x 297 mm is not a page"),
        "{}",
        stderr(&out)
    );
}
