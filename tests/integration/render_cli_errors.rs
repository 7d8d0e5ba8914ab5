//! Bad input through the real binary: non-zero exit, one line on stderr
//! naming the problem, and no file left behind.

use std::path::Path;
use std::process::Command;

/// Runs whycode in `dir`, expecting failure; returns its stderr.
fn fails(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_whycode"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(!out.status.success(), "whycode {args:?} succeeded");
    assert_eq!(out.status.code(), Some(1), "whycode {args:?}");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr:?}");
    assert!(stderr.starts_with("whycode: error: "), "{stderr:?}");
    let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
    assert!(left.is_empty(), "files left behind by {args:?}: {left:?}");
    stderr
}

#[test]
fn id_outside_the_family_names_the_valid_range() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &[
            "marker",
            "--bits",
            "8",
            "--distance",
            "2",
            "--id",
            "40",
            "--diameter",
            "50mm",
            "-o",
            "x.pdf",
        ],
    );
    assert!(
        err.contains("ID 40 is not in the 8-bit distance-2 family (IDs 1-16)"),
        "{err}"
    );
    let err = fails(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--ids",
            "1-5,17",
            "--diameter",
            "40mm",
            "-o",
            "s.pdf",
        ],
    );
    assert!(
        err.contains("ID 17 is not in the 8-bit distance-2 family (IDs 1-16)"),
        "{err}"
    );
}

#[test]
fn too_large_markers_name_the_largest_that_fits() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--ids",
            "1",
            "--diameter",
            "250mm",
            "--template",
            "a5",
            "-o",
            "s.svg",
        ],
    );
    assert!(err.contains("does not fit on the a5 page"), "{err}");
    assert!(err.contains("the largest that fits is 101.5 mm"), "{err}");
}

#[test]
fn unknown_template_lists_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--all",
            "--diameter",
            "40mm",
            "--template",
            "b5",
            "-o",
            "s.pdf",
        ],
    );
    assert!(err.contains("unknown template 'b5'"), "{err}");
    assert!(err.contains("a3, a4, a5, legal, letter"), "{err}");
    let err = fails(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--all",
            "--diameter",
            "40mm",
            "--template",
            "missing.toml",
            "-o",
            "s.pdf",
        ],
    );
    assert!(err.contains("missing.toml"), "{err}");
}

#[test]
fn unwritable_paths_and_unknown_formats_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "1",
            "--diameter",
            "50mm",
            "-o",
            "no/such/dir/m.pdf",
        ],
    );
    assert!(err.contains("no/such/dir/m.pdf"), "{err}");
    let err = fails(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--all",
            "--diameter",
            "20mm",
            "-o",
            "no/such/dir/s.svg",
        ],
    );
    assert!(err.contains("no/such/dir/s"), "{err}");
    let err = fails(
        dir.path(),
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "1",
            "--diameter",
            "50mm",
            "-o",
            "m.jpg",
        ],
    );
    assert!(err.contains("unknown output format '.jpg'"), "{err}");
    let err = fails(
        dir.path(),
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "1",
            "--diameter",
            "50mm",
            "--margin",
            "2mm",
            "-o",
            "m.pdf",
        ],
    );
    assert!(err.contains("too small"), "{err}");
}

#[test]
fn id_lists_that_would_print_a_marker_twice_or_too_many_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = |ids: &[&str]| {
        let mut args = vec!["sheet", "--diameter", "20mm", "-o", "s.pdf"];
        args.extend_from_slice(ids);
        fails(dir.path(), &args)
    };
    let err = sheet(&["--bits", "8", "--ids", "1-4,3"]);
    assert!(err.contains("ID 3 is listed more than once"), "{err}");
    let err = sheet(&["--bits", "8", "--ids", "0-3"]);
    assert!(err.contains("IDs start at 1"), "{err}");
    let err = sheet(&["--bits", "8", "--ids", "x"]);
    assert!(
        err.ends_with("--ids: 'x' is not an ID or a range like 3-7\n"),
        "{err}"
    );
    let err = sheet(&["--bits", "24", "--distance", "1", "--all"]);
    assert!(err.contains("too many to print at once"), "{err}");
}

#[test]
fn unreadable_markers_are_not_written() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &[
            "marker",
            "--bits",
            "24",
            "--id",
            "3",
            "--diameter",
            "2mm",
            "-o",
            "tiny.pdf",
        ],
    );
    assert!(err.contains("self-check failed: ID 3"), "{err}");
    assert!(err.contains("could not be read"), "{err}");
}

#[test]
fn usage_errors_are_one_line_with_exit_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(dir.path(), &["marker", "--bogus"]);
    assert!(
        err.contains("unexpected argument '--bogus'") && err.contains("whycode marker --help"),
        "{err}"
    );
}
