//! Words for a user who is stuck (issue 24 item 13): the commands say what
//! they saw when the answer is "nothing", instead of only "no markers" or
//! "missing".

use crate::support::{stderr, stdout, whycode_in};
use std::path::Path;

fn ok(dir: &Path, args: &[&str]) -> (String, String) {
    let out = whycode_in(dir, args);
    assert!(
        out.status.success() || out.status.code() == Some(2),
        "whycode {}: {}",
        args.join(" "),
        stderr(&out)
    );
    (stdout(&out), stderr(&out))
}

#[test]
fn legacy_markers_read_without_legacy_say_how_to_read_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(
        d,
        &[
            "sheet",
            "--legacy",
            "--count",
            "6",
            "--diameter",
            "50mm",
            "-o",
            "whycon.pdf",
        ],
    );
    ok(
        d,
        &[
            "simulate",
            "--manifest",
            "whycon.json",
            "--camera-distance",
            "0.5m",
            "--tilt",
            "20deg",
            "-o",
            "view.png",
        ],
    );
    // Reported as markers of unknown ID, and why.
    let (out, err) = ok(d, &["detect", "view.png"]);
    assert_eq!(out.matches("(unknown: no_code_ring)").count(), 6, "{out}");
    assert!(
        err.contains("6 discs looked like legacy WhyCon markers") && err.contains("--legacy"),
        "{err}"
    );
    let (out, err) = ok(d, &["detect", "--legacy", "view.png"]);
    assert_eq!(out.lines().count(), 7, "{out}");
    assert!(!err.contains("legacy"), "{err}");
    // WhyCode markers read as such give no such hint.
    ok(
        d,
        &["sheet", "--ids", "1-6", "--diameter", "50mm", "-o", "s.pdf"],
    );
    ok(
        d,
        &[
            "simulate",
            "--manifest",
            "s.json",
            "--camera-distance",
            "0.5m",
            "-o",
            "codes.png",
        ],
    );
    let (_, err) = ok(d, &["detect", "codes.png"]);
    assert!(!err.contains("legacy"), "{err}");
}

#[test]
fn validating_against_another_sheets_manifest_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sheet = |args: &[&str], out: &str| {
        let mut all = vec!["sheet", "--diameter", "50mm", "--no-check", "-o", out];
        all.extend_from_slice(args);
        ok(d, &all);
    };
    sheet(&["--ids", "1-6"], "s8.pdf");
    sheet(&["--ids", "7-12"], "other.pdf");
    sheet(
        &["--bits", "12", "--distance", "3", "--ids", "1-6"],
        "s12.pdf",
    );
    for (manifest, photo) in [
        ("other.json", "view-other.png"),
        ("s12.json", "view-s12.png"),
    ] {
        ok(
            d,
            &[
                "simulate",
                "--manifest",
                manifest,
                "--camera-distance",
                "0.5m",
                "-o",
                photo,
            ],
        );
    }
    let (out, _) = ok(d, &["validate", "--manifest", "s8.json", "view-s12.png"]);
    assert!(
        out.contains("6 markers here carry 12-bit codes, but the manifest's family is 8-bit d2"),
        "{out}"
    );
    let (out, _) = ok(d, &["validate", "--manifest", "s8.json", "view-other.png"]);
    assert!(
        out.contains("6 IDs read here are not on the manifest (7, 8, 9, 10, 11, 12)"),
        "{out}"
    );
    let (json, _) = ok(
        d,
        &[
            "validate",
            "--manifest",
            "s8.json",
            "view-other.png",
            "--format",
            "json",
        ],
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["photos"][0]["notes"].as_array().unwrap().len(), 1);
    // The right manifest: no such note.
    let (out, _) = ok(
        d,
        &["validate", "--manifest", "other.json", "view-other.png"],
    );
    assert!(!out.contains("not on the manifest"), "{out}");
}

#[test]
fn an_unknown_scale_says_where_the_paper_edge_was_looked_for() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The same IDs printed smaller: the page is located by its IDs, but
    // the paper is not where the other manifest's page puts it.
    for (diameter, out) in [("50mm", "big.pdf"), ("30mm", "small.pdf")] {
        ok(
            d,
            &[
                "sheet",
                "--ids",
                "1-6",
                "--diameter",
                diameter,
                "--no-check",
                "-o",
                out,
            ],
        );
    }
    ok(
        d,
        &[
            "simulate",
            "--manifest",
            "small.json",
            "--camera-distance",
            "0.5m",
            "-o",
            "view.png",
        ],
    );
    let (out, _) = ok(d, &["validate", "--manifest", "big.json", "view.png"]);
    let note = out
        .lines()
        .find(|l| l.contains("needs two opposite paper edges"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        note.contains("no paper edge where the manifest's page puts it")
            && note.contains("the photo is of another sheet than this manifest's"),
        "{note}"
    );
    // Each reason is said once, for every side it applies to.
    assert_eq!(note.matches("no paper edge where").count(), 1, "{note}");
}
