//! The command line fills the library's specs: options that do not apply
//! are refused rather than ignored, and every quantity is held to the one
//! table of plausible ranges (`whycode::limits`).

use crate::support::{stderr, whycode_in};

fn refused(dir: &std::path::Path, args: &[&str], says: &str) {
    let out = whycode_in(dir, args);
    assert_eq!(out.status.code(), Some(1), "whycode {}", args.join(" "));
    let err = stderr(&out);
    assert!(err.contains(says), "whycode {}: {err}", args.join(" "));
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn options_of_the_other_subject_are_refused_not_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert!(whycode_in(d, &["sheet", "--ids", "1-4", "-o", "s.pdf"])
        .status
        .success());
    refused(
        d,
        &[
            "simulate",
            "--ids",
            "1-2",
            "--print-scale",
            "0.97",
            "-o",
            "a.png",
        ],
        "--print-scale: applies to a sheet's page",
    );
    refused(
        d,
        &[
            "simulate",
            "--manifest",
            "s.json",
            "--diameter",
            "30mm",
            "-o",
            "b.png",
        ],
        "--diameter: describes loose markers",
    );
    refused(
        d,
        &[
            "simulate",
            "--manifest",
            "s.json",
            "--layout",
            "scatter",
            "-o",
            "c.png",
        ],
        "--layout: describes loose markers",
    );
    for name in ["a.png", "b.png", "c.png"] {
        assert!(!d.join(name).exists(), "{name} was written");
    }
}

#[test]
fn implausible_quantities_are_refused_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("cam.yaml"),
        "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n",
    )
    .unwrap();
    assert!(whycode_in(
        d,
        &["simulate", "--ids", "1-2", "--size", "640x480", "-o", "v.png"]
    )
    .status
    .success());
    // A bare number is metres: 40 m is no marker.
    refused(
        d,
        &[
            "detect",
            "--diameter",
            "40",
            "--camera",
            "cam.yaml",
            "v.png",
        ],
        "--diameter: 40000 mm is outside 0.5 to 10000 mm",
    );
    refused(
        d,
        &[
            "detect",
            "--diameter",
            "1e-300mm",
            "--camera",
            "cam.yaml",
            "v.png",
        ],
        "--diameter: 1e-300 mm is outside 0.5 to 10000 mm",
    );
    refused(
        d,
        &[
            "marker",
            "--id",
            "1",
            "--diameter",
            "1e-300mm",
            "--no-check",
            "-o",
            "m.svg",
        ],
        "--diameter: 1e-300 mm is outside 0.5 to 10000 mm",
    );
    assert!(!d.join("m.svg").exists());
    refused(
        d,
        &[
            "simulate",
            "--ids",
            "1-2",
            "--camera-distance",
            "5000m",
            "-o",
            "far.png",
        ],
        "--camera-distance: 5000 m is outside 0.01 to 1000 m",
    );
}
