//! Bad input through the real binary: exit status 1, one line on stderr
//! naming the problem, and no file left behind. One test per row of the
//! table below: the arguments, then what the message must contain.

use std::path::Path;

use crate::support::whycode_in;

/// Runs whycode in an empty folder, expecting failure; checks the contract
/// and that every `wanted` piece is in the message.
fn refused(args: &[&str], wanted: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(dir.path(), args);
    for piece in wanted {
        assert!(
            err.contains(piece),
            "whycode {args:?}: {err:?} lacks {piece:?}"
        );
    }
}

fn fails(dir: &Path, args: &[&str]) -> String {
    let out = whycode_in(dir, args);
    assert_eq!(out.status.code(), Some(1), "whycode {args:?}");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr:?}");
    assert!(stderr.starts_with("whycode: error: "), "{stderr:?}");
    let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
    assert!(left.is_empty(), "files left behind by {args:?}: {left:?}");
    stderr
}

/// `name: [args] => [pieces of the message]` becomes one test.
macro_rules! refused {
    ($($name:ident: [$($arg:expr),* $(,)?] => [$($want:expr),+ $(,)?];)+) => {
        $(
            #[test]
            fn $name() {
                refused(&[$($arg),*], &[$($want),+]);
            }
        )+
    };
}

refused! {
    marker_id_outside_the_family_names_the_valid_range:
        ["marker", "--bits", "8", "--distance", "2", "--id", "40", "--diameter", "50mm", "-o", "x.pdf"]
        => ["ID 40 is not in the 8-bit distance-2 family (IDs 1-16)"];
    sheet_id_outside_the_family_names_the_valid_range:
        ["sheet", "--bits", "8", "--ids", "1-5,17", "--diameter", "40mm", "-o", "s.pdf"]
        => ["ID 17 is not in the 8-bit distance-2 family (IDs 1-16)"];
    too_large_markers_name_the_largest_that_fits:
        ["sheet", "--bits", "8", "--ids", "1", "--diameter", "250mm", "--template", "a5", "-o", "s.svg"]
        => ["does not fit on the a5 page", "the largest that fits is 101.5 mm"];
    unknown_template_lists_the_known_ones:
        ["sheet", "--bits", "8", "--all", "--diameter", "40mm", "--template", "b5", "-o", "s.pdf"]
        => ["unknown template 'b5'", "a3, a4, a5, legal, letter"];
    missing_template_file_is_named:
        ["sheet", "--bits", "8", "--all", "--diameter", "40mm", "--template", "missing.toml", "-o", "s.pdf"]
        => ["missing.toml"];
    unwritable_marker_path_is_named:
        ["marker", "--bits", "8", "--id", "1", "--diameter", "50mm", "-o", "no/such/dir/m.pdf"]
        => ["no/such/dir/m.pdf"];
    unwritable_sheet_path_is_named:
        ["sheet", "--bits", "8", "--all", "--diameter", "20mm", "-o", "no/such/dir/s.svg"]
        => ["no/such/dir/s"];
    unknown_output_format_is_named:
        ["marker", "--bits", "8", "--id", "1", "--diameter", "50mm", "-o", "m.jpg"]
        => ["unknown output format '.jpg'"];
    too_small_margin_is_refused:
        ["marker", "--bits", "8", "--id", "1", "--diameter", "50mm", "--margin", "2mm", "-o", "m.pdf"]
        => ["too small"];
    id_listed_twice_is_refused:
        ["sheet", "--diameter", "20mm", "-o", "s.pdf", "--bits", "8", "--ids", "1-4,3"]
        => ["ID 3 is listed more than once"];
    id_zero_is_refused:
        ["sheet", "--diameter", "20mm", "-o", "s.pdf", "--bits", "8", "--ids", "0-3"]
        => ["IDs start at 1"];
    id_list_that_is_not_a_list_is_refused:
        ["sheet", "--diameter", "20mm", "-o", "s.pdf", "--bits", "8", "--ids", "x"]
        => ["--ids: 'x' is not an ID or a range like 3-7\n"];
    too_many_markers_at_once_are_refused:
        ["sheet", "--diameter", "20mm", "-o", "s.pdf", "--bits", "24", "--distance", "1", "--all"]
        => ["too many to print at once"];
    unreadable_markers_are_not_written:
        ["marker", "--bits", "24", "--id", "3", "--diameter", "2mm", "-o", "tiny.pdf"]
        => ["self-check failed: ID 3", "could not be read"];
    usage_errors_are_one_line_with_exit_status_1:
        ["marker", "--bogus"]
        => ["unexpected argument '--bogus'", "whycode marker --help"];
}

/// Runs whycode in `dir`; returns the exit code, stdout and stderr.
fn run(dir: &Path, args: &[&str]) -> (Option<i32>, Vec<u8>, String) {
    let out = whycode_in(dir, args);
    (
        out.status.code(),
        out.stdout,
        String::from_utf8(out.stderr).unwrap(),
    )
}

#[test]
fn usage_errors_name_the_arguments_and_the_valid_values() {
    let dir = tempfile::tempdir().unwrap();
    // Missing arguments: every one is named, still on one line.
    let err = fails(dir.path(), &["marker", "-o", "x.pdf"]);
    assert!(
        err.contains("required arguments were not provided: --diameter <DIAMETER>, --id <ID>"),
        "{err}"
    );
    // Conflicts name both sides, however many there are.
    let err = fails(
        dir.path(),
        &[
            "sheet", "--legacy", "--count", "3", "--bits", "8", "--ids", "1", "-o", "x.pdf",
        ],
    );
    assert!(
        err.contains("'--legacy' cannot be used with: --bits <BITS>, --ids <IDS>"),
        "{err}"
    );
    // An unknown value lists the known ones.
    let err = fails(dir.path(), &["detect", "--format", "xml", "x.png"]);
    assert!(err.contains("[possible values: table, csv, json]"), "{err}");
    let err = fails(dir.path(), &["sheet", "--legacy"]);
    assert!(err.contains("not provided: --count <COUNT>"), "{err}");
}

#[test]
fn negative_and_scientific_numbers_reach_the_range_checks() {
    let dir = tempfile::tempdir().unwrap();
    let marker = |extra: &[&'static str]| {
        let mut args = vec!["marker", "--id", "5", "-o", "m.png"];
        args.extend_from_slice(extra);
        args
    };
    let err = fails(dir.path(), &marker(&["--diameter", "-5mm"]));
    assert!(err.contains("'-5mm' must be a positive length"), "{err}");
    let err = fails(
        dir.path(),
        &marker(&["--diameter", "50mm", "--dpi", "-300"]),
    );
    assert!(err.contains("-300 dpi is outside 10 to 1200 dpi"), "{err}");
    // A huge number is echoed as typed, not as 309 digits.
    let err = fails(
        dir.path(),
        &marker(&["--diameter", "50mm", "--dpi", "1e308"]),
    );
    assert!(err.contains("1e308 dpi is outside 10 to 1200 dpi"), "{err}");
    assert!(err.len() < 200, "{err}");
    let err = fails(
        dir.path(),
        &["marker", "--id", "-5", "--diameter", "5mm", "-o", "m.pdf"],
    );
    assert!(err.contains("'-5' is not a whole number"), "{err}");
    // Scientific notation is a number like any other.
    let (code, _, err) = run(
        dir.path(),
        &[
            "marker",
            "--id",
            "5",
            "--diameter",
            "5e1mm",
            "-o",
            "sci.svg",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    let (code, _, err) = run(
        dir.path(),
        &[
            "marker",
            "--id",
            "5",
            "--diameter",
            "50mm",
            "-o",
            "plain.svg",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(
        std::fs::read(dir.path().join("sci.svg")).unwrap(),
        std::fs::read(dir.path().join("plain.svg")).unwrap()
    );
}

#[test]
fn every_subcommand_takes_the_family_flags_the_same_way() {
    let dir = tempfile::tempdir().unwrap();
    // --bits defaults to 8 and --distance to 2 for marker as for the others.
    for (name, family) in [
        ("default.svg", &[][..]),
        ("spelled.svg", &["--bits", "8", "--distance", "2"][..]),
        ("short.svg", &["-b", "8", "-d", "2"][..]),
    ] {
        let mut args = vec!["marker", "--id", "5", "--diameter", "30mm", "-o", name];
        args.extend_from_slice(family);
        let (code, _, err) = run(dir.path(), &args);
        assert_eq!(code, Some(0), "{args:?}: {err}");
    }
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert_eq!(read("default.svg"), read("spelled.svg"));
    assert_eq!(read("default.svg"), read("short.svg"));
    // A family file works wherever --bits and --distance do.
    let (code, family, err) = run(dir.path(), &["ids", "-b", "8", "-f", "json"]);
    assert_eq!(code, Some(0), "{err}");
    std::fs::write(dir.path().join("lab.json"), family).unwrap();
    let args = [
        "marker",
        "--family",
        "lab.json",
        "--id",
        "5",
        "--diameter",
        "30mm",
        "-o",
        "file.svg",
    ];
    let (code, _, err) = run(dir.path(), &args);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(read("default.svg"), read("file.svg"));
    // One --dpi rule for marker and sheet.
    let sub = tempfile::tempdir().unwrap();
    for args in [
        &[
            "marker",
            "--id",
            "1",
            "--diameter",
            "30mm",
            "--dpi",
            "2400",
            "-o",
            "m.png",
        ][..],
        &["sheet", "--ids", "1", "--dpi", "2400", "-o", "s.png"][..],
    ] {
        let err = fails(sub.path(), args);
        assert!(err.contains("outside 10 to 1200 dpi"), "{args:?}: {err}");
    }
    // --distance is the Hamming distance: a length is refused outside simulate.
    let err = fails(sub.path(), &["detect", "--distance", "0.8m", "x.png"]);
    assert!(
        err.contains("--distance is the family's Hamming distance"),
        "{err}"
    );
}

#[test]
fn angles_need_a_unit_like_lengths() {
    let dir = tempfile::tempdir().unwrap();
    let err = fails(
        dir.path(),
        &["simulate", "--ids", "1", "--tilt", "30", "-o", "v.png"],
    );
    assert!(
        err.contains("'30' has no unit (write e.g. 30deg or 30rad)"),
        "{err}"
    );
    let err = fails(
        dir.path(),
        &["marker", "--id", "1", "--diameter", "30", "-o", "m.pdf"],
    );
    assert!(err.contains("'30' has no unit"), "{err}");
}

#[test]
fn no_subcommand_is_a_usage_failure_not_a_validation_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, err) = run(dir.path(), &[]);
    assert_eq!(code, Some(1));
    assert!(err.contains("Usage: whycode <COMMAND>"), "{err}");
    let (code, help, _) = run(dir.path(), &["--help"]);
    assert_eq!(code, Some(0));
    assert!(String::from_utf8(help).unwrap().contains("Commands:"));
}

#[test]
fn simulate_keeps_the_old_spellings_for_one_release_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |distance: &[&'static str], out: &'static str| {
        let mut args = vec![
            "simulate", "--bits", "8", "--ids", "1-3", "--size", "320x240", "-o", out,
        ];
        args.extend_from_slice(distance);
        let (code, _, err) = run(dir.path(), &args);
        assert_eq!(code, Some(0), "{args:?}: {err}");
        (err, std::fs::read(dir.path().join(out)).unwrap())
    };
    let (err, new) = scene(&["--distance", "2", "--camera-distance", "0.8m"], "new.png");
    assert!(!err.contains("note"), "{err}");
    let (err, old) = scene(&["--hamming", "2", "--distance", "0.8m"], "old.png");
    assert!(
        err.contains("note: --distance 0.8m reads as the camera distance"),
        "{err}"
    );
    assert!(err.contains("note: --hamming is now --distance"), "{err}");
    assert_eq!(new, old);
    let err = fails(
        tempfile::tempdir().unwrap().path(),
        &[
            "simulate",
            "--ids",
            "1",
            "--hamming",
            "2",
            "--distance",
            "3",
            "-o",
            "v.png",
        ],
    );
    assert!(err.contains("give the family once"), "{err}");
}
