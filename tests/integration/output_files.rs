//! What the commands promise about the files they write: never over a
//! file they read, a set of outputs written whole or not at all, no stale
//! pages of an earlier run, no temporary files left behind, and the
//! permissions a user expects.

use crate::support::{stderr, whycode_in};
use std::path::Path;

fn ok(dir: &Path, args: &[&str]) {
    let out = whycode_in(dir, args);
    assert!(
        out.status.success(),
        "whycode {}: {}",
        args.join(" "),
        stderr(&out)
    );
}

fn refused(dir: &Path, args: &[&str], says: &str) {
    let out = whycode_in(dir, args);
    assert_eq!(out.status.code(), Some(1), "whycode {}", args.join(" "));
    let err = stderr(&out);
    assert!(err.contains(says), "whycode {}: {err}", args.join(" "));
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn no_command_writes_over_a_file_it_reads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(d, &["ids", "--format", "json", "-o", "swarm.json"]);
    ok(
        d,
        &["ids", "--bits", "12", "--format", "json", "-o", "fam.json"],
    );
    let family = std::fs::read(d.join("swarm.json")).unwrap();
    // The sheet's default output is swarm.pdf, whose manifest is swarm.json.
    refused(
        d,
        &["sheet", "--family", "swarm.json"],
        "swarm.json: would overwrite swarm.json, which this command reads",
    );
    refused(
        d,
        &[
            "simulate",
            "--family",
            "swarm.json",
            "--ids",
            "1-3",
            "-o",
            "swarm.png",
        ],
        "which this command reads",
    );
    refused(
        d,
        &[
            "ids",
            "--family",
            "fam.json",
            "--format",
            "json",
            "-o",
            "./fam.json",
        ],
        "which this command reads",
    );
    // A family file may have any name, even a marker's.
    ok(d, &["ids", "--format", "json", "-o", "fam.svg"]);
    refused(
        d,
        &[
            "marker",
            "--family",
            "fam.svg",
            "--id",
            "1",
            "--diameter",
            "30mm",
            "-o",
            "fam.svg",
        ],
        "which this command reads",
    );
    ok(
        d,
        &[
            "simulate", "--ids", "1-3", "--size", "320x240", "-o", "v.png",
        ],
    );
    std::fs::write(
        d.join("cam.yaml"),
        "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n",
    )
    .unwrap();
    refused(
        d,
        &[
            "simulate", "--ids", "1-3", "--camera", "cam.yaml", "--truth", "cam.yaml", "-o",
            "c.png",
        ],
        "which this command reads",
    );
    assert_eq!(std::fs::read(d.join("swarm.json")).unwrap(), family);
    assert!(!d.join("swarm.png").exists() && !d.join("c.png").exists());
}

#[test]
fn a_simulated_image_and_its_truth_are_written_together_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("g.json")).unwrap();
    refused(
        d,
        &[
            "simulate", "--ids", "1-3", "--size", "320x240", "-o", "g.png",
        ],
        "g.json: it is a folder",
    );
    assert!(
        !d.join("g.png").exists(),
        "the image was written without its truth"
    );
}

#[test]
fn a_shorter_rerun_of_a_sheet_removes_the_pages_it_no_longer_has() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sheet = |ids: &str| {
        ok(
            d,
            &[
                "sheet",
                "--ids",
                ids,
                "--dpi",
                "30",
                "--no-check",
                "-o",
                "x.png",
            ],
        )
    };
    sheet("1-16");
    assert!(d.join("x-1.png").exists() && d.join("x-2.png").exists());
    sheet("1-4");
    assert!(d.join("x.png").exists());
    assert!(!d.join("x-1.png").exists() && !d.join("x-2.png").exists());
    // A file of that shape that no manifest of this sheet listed stays.
    std::fs::write(d.join("x-7.png"), "mine").unwrap();
    sheet("1-16");
    sheet("1-4");
    assert_eq!(std::fs::read_to_string(d.join("x-7.png")).unwrap(), "mine");
}

#[test]
fn temporary_files_of_a_killed_run_are_swept_and_no_others() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let old = d.join(".whycode-Ab3xY9");
    let fresh = d.join(".whycode-Zz9aa1");
    let other = d.join(".whycode-notes.txt");
    for path in [&old, &fresh, &other] {
        std::fs::write(path, "x").unwrap();
    }
    let an_hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
    for path in [&old, &other] {
        std::fs::File::options()
            .write(true)
            .open(path)
            .unwrap()
            .set_modified(an_hour_ago)
            .unwrap();
    }
    ok(d, &["ids", "-o", "ids.txt"]);
    assert!(!old.exists(), "a stale temporary file of ours was left");
    assert!(
        fresh.exists(),
        "a concurrent run's staging file was removed"
    );
    assert!(other.exists(), "a file not of our pattern was removed");
}

#[cfg(unix)]
#[test]
fn new_files_honour_the_umask_and_replaced_ones_keep_their_mode() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shared = d.join("shared.txt");
    std::fs::write(&shared, "old").unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o666)).unwrap();
    let bin = env!("CARGO_BIN_EXE_whycode");
    let script = format!("umask 077; '{bin}' ids -o private.txt && '{bin}' ids -o shared.txt");
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(script)
        .current_dir(d)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&d.join("private.txt")), 0o600);
    assert_eq!(mode(&shared), 0o666);
}

/// A run killed between renaming its PDF and its manifest into place (or
/// any other way a PDF and a manifest of different runs end up together)
/// is told by the digests the manifest keeps of its pages: the commands
/// that read the manifest warn, naming the file.
#[test]
fn a_manifest_knows_its_pages_and_tells_a_mixed_set() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sheet = |ids: &str, out: &str| ok(d, &["sheet", "--ids", ids, "--no-check", "-o", out]);
    sheet("1-4", "x.pdf");
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("x.json")).unwrap()).unwrap();
    let pdf = std::fs::read(d.join("x.pdf")).unwrap();
    assert_eq!(manifest["files"][0]["file"], "x.pdf");
    assert_eq!(
        manifest["files"][0]["sha256"],
        whycode::fileset::sha256_hex(&pdf).as_str()
    );
    ok(d, &["simulate", "--manifest", "x.json", "-o", "photo.png"]);
    let clean = whycode_in(d, &["validate", "--manifest", "x.json", "photo.png"]);
    assert!(!stderr(&clean).contains("warning"), "{}", stderr(&clean));

    // What a kill between the renames leaves: the new run's PDF beside the
    // old run's manifest.
    sheet("5-8", "y.pdf");
    std::fs::copy(d.join("y.pdf"), d.join("x.pdf")).unwrap();
    for args in [
        &["validate", "--manifest", "x.json", "photo.png"][..],
        &["simulate", "--manifest", "x.json", "-o", "again.png"][..],
    ] {
        let out = whycode_in(d, args);
        let err = stderr(&out);
        assert!(
            err.contains("warning: x.json: x.pdf beside it is not the file it was written with"),
            "whycode {}: {err}",
            args.join(" ")
        );
    }
    // A PDF moved away (to the printer) is not a mismatch.
    std::fs::remove_file(d.join("x.pdf")).unwrap();
    let moved = whycode_in(d, &["validate", "--manifest", "x.json", "photo.png"]);
    assert!(!stderr(&moved).contains("warning"), "{}", stderr(&moved));
}

/// Concurrent runs writing one sheet leave one run's PDF with that run's
/// manifest (the folder lock), as the manifest's digest proves.
#[test]
fn concurrent_sheets_to_one_path_leave_a_matching_set() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for _round in 0..3 {
        let runs: Vec<_> = ["1-4", "5-8", "9-12", "13-16"]
            .iter()
            .map(|ids| {
                std::process::Command::new(env!("CARGO_BIN_EXE_whycode"))
                    .current_dir(d)
                    .args(["sheet", "--ids", ids, "--no-check", "-o", "x.pdf"])
                    .stderr(std::process::Stdio::null())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for mut run in runs {
            assert!(run.wait().unwrap().success());
        }
        let manifest: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join("x.json")).unwrap()).unwrap();
        let pdf = std::fs::read(d.join("x.pdf")).unwrap();
        assert_eq!(
            manifest["files"][0]["sha256"],
            whycode::fileset::sha256_hex(&pdf).as_str(),
            "the PDF and the manifest come from different runs"
        );
    }
}

/// A simulated image's truth names the image it was written with.
#[test]
fn a_ground_truth_names_its_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(d, &["simulate", "--ids", "1-3", "-o", "view.png"]);
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("view.json")).unwrap()).unwrap();
    let image = std::fs::read(d.join("view.png")).unwrap();
    assert_eq!(truth["files"][0]["file"], "view.png");
    assert_eq!(
        truth["files"][0]["sha256"],
        whycode::fileset::sha256_hex(&image).as_str()
    );
}
