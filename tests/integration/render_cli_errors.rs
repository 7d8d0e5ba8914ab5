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
