//! `whycode ids` through the real binary.

use crate::support::whycode;
use std::path::Path;

fn stdout_of(args: &[&str]) -> String {
    let out = whycode(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty(), "{args:?} wrote to stderr");
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must fail with one line on stderr and nothing on stdout.
fn error_of(args: &[&str]) -> String {
    let out = whycode(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(out.stdout.is_empty(), "{args:?} printed output");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        stderr.lines().count(),
        1,
        "{args:?}: not one line: {stderr}"
    );
    assert!(stderr.starts_with("whycode: error: "), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    stderr
}

const SPEC_VECTOR: [u32; 16] = [
    1, 7, 11, 13, 19, 21, 25, 31, 37, 47, 55, 59, 61, 87, 91, 127,
];

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn table_is_the_default_and_shows_the_spec_vector() {
    let text = stdout_of(&["ids", "--bits", "8", "--distance", "2"]);
    assert_eq!(text, stdout_of(&["ids"]), "defaults are 8 bits, distance 2");
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "# 16 IDs, 8 bits, distance 2: min distance 2, worst self-distance 2"
    );
    assert_eq!(
        lines.next().unwrap().split_whitespace().collect::<Vec<_>>(),
        ["id", "code", "binary", "self_distance"]
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split_whitespace().collect()).collect();
    assert_eq!(rows.len(), 16);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], (k + 1).to_string());
        assert_eq!(row[1], SPEC_VECTOR[k].to_string());
        assert_eq!(row[2], format!("{:08b}", SPEC_VECTOR[k]));
    }
    // Aligned columns: every row as wide as the column header.
    let widths: Vec<usize> = text.lines().skip(1).map(str::len).collect();
    assert!(widths.iter().all(|&w| w == widths[0]), "{text}");
}

#[test]
fn csv_has_the_documented_header() {
    let text = stdout_of(&["ids", "--bits", "8", "--distance", "2", "--format", "csv"]);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("id,code,binary,self_distance"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 16);
    assert_eq!(rows[0], "1,1,00000001,2");
    assert_eq!(rows[15], "16,127,01111111,2");
}

#[test]
fn json_is_the_family_file_and_loads_back() {
    let text = stdout_of(&["ids", "--bits", "12", "--distance", "3", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["format"], "whycode-family");
    assert_eq!(v["version"], 1);
    assert_eq!(v["bits"], 12);
    assert_eq!(v["distance"], 3);
    assert_eq!(v["count"], 16);
    assert!(v["min_distance"].as_u64().unwrap() >= 3);
    assert!(v["min_self_distance"].as_u64().is_some());
    let codes = v["codes"].as_array().unwrap();
    assert_eq!(codes.len(), 16);
    assert_eq!(codes[0]["id"], 1);
    assert_eq!(codes[0]["binary"], "000000000001");
    let family = whycode::family::Family::from_json(&text).unwrap();
    assert_eq!(family, whycode::family::Family::generate(12, 3).unwrap());
}

#[test]
fn output_file_is_written_and_read_back_with_family() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("family.json");
    let p = path.to_str().unwrap();
    let out = whycode(&[
        "ids", "--bits", "10", "-d", "3", "--format", "json", "-o", p,
    ]);
    assert!(out.status.success());
    assert!(out.stdout.is_empty());
    assert_eq!(files_in(dir.path()), ["family.json"]);
    let written = std::fs::read_to_string(&path).unwrap();
    assert_eq!(
        written,
        stdout_of(&["ids", "--bits", "10", "-d", "3", "--format", "json"])
    );
    // The saved family shows the same table as the generated one.
    assert_eq!(
        stdout_of(&["ids", "--family", p]),
        stdout_of(&["ids", "--bits", "10", "--distance", "3"])
    );
    // Table and csv can go to files too.
    let csv = dir.path().join("ids.csv");
    let out = whycode(&["ids", "--format", "csv", "-o", csv.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(std::fs::read_to_string(&csv)
        .unwrap()
        .starts_with("id,code,binary,self_distance\n"));
}

#[test]
fn counts_reproduce_the_spec_table() {
    let text = stdout_of(&["ids", "--counts", "--bits", "4..16:2", "--distance", "1..4"]);
    assert_eq!(
        text,
        stdout_of(&["ids", "--counts"]),
        "defaults are the spec's ranges"
    );
    let rows: Vec<Vec<&str>> = text
        .lines()
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(
        rows[0],
        ["d", "\\", "n", "4", "6", "8", "10", "12", "14", "16"]
    );
    assert_eq!(rows[1], ["1", "3", "9", "30", "99", "335", "1161", "4080"]);
    assert_eq!(rows[2], ["2", "2", "5", "16", "51", "170", "585", "2048"]);
    assert_eq!(rows[3], ["3", "1", "2", "3", "7", "16", "48", "125"]);
    assert_eq!(rows[4], ["4", "1", "2", "2", "5", "10", "24", "69"]);
    assert_eq!(rows.len(), 5);
}

#[test]
fn counts_take_every_value_of_a_range_and_mark_impossible_cells() {
    let text = stdout_of(&["ids", "--counts", "--bits", "2..=4", "--distance", "1..3"]);
    let rows: Vec<Vec<&str>> = text
        .lines()
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(rows[0][3..], ["2", "3", "4"]);
    assert_eq!(rows[3], ["3", "-", "1", "1"]);
    let csv = stdout_of(&[
        "ids", "--counts", "--bits", "4,6", "-d", "1", "--format", "csv",
    ]);
    assert_eq!(csv, "bits,distance,count\n4,1,3\n6,1,9\n");
    let json = stdout_of(&[
        "ids", "--counts", "--bits", "4..6:2", "-d", "3..5", "--format", "json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["format"], "whycode-counts");
    assert_eq!(v["bits"], serde_json::json!([4, 6]));
    assert_eq!(v["counts"], serde_json::json!([[1, 2], [1, 2], [null, 1]]));
}

#[test]
fn bad_input_gets_one_line_and_a_failure() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["ids", "--bits", "0"],
            "bits must be between 2 and 24, got 0",
        ),
        (
            &["ids", "--bits", "1"],
            "bits must be between 2 and 24, got 1",
        ),
        (
            &["ids", "--bits", "25"],
            "bits must be between 2 and 24, got 25",
        ),
        (&["ids", "--bits", "eight"], "'eight' is not a whole number"),
        (&["ids", "--bits", "4..8"], "lists need --counts"),
        (
            &["ids", "--distance", "0"],
            "distance must be between 1 and the bit count 8, got 0",
        ),
        (
            &["ids", "--bits", "6", "--distance", "7"],
            "distance must be between 1 and the bit count 6, got 7",
        ),
        (&["ids", "--distance", "-2"], "'-2' is not a whole number"),
        (
            &["ids", "--format", "xml"],
            "invalid value 'xml' for '--format <FORMAT>' [possible values: table, csv, json]",
        ),
        (
            &["ids", "--counts", "--bits", "4.."],
            "'4..' is not a number or range",
        ),
        (
            &["ids", "--counts", "--bits", "..8"],
            "'..8' is not a number or range",
        ),
        (
            &["ids", "--counts", "--bits", "4-8"],
            "'4-8' is not a number or range",
        ),
        (
            &["ids", "--counts", "--bits", "8..4"],
            "range '8..4' is empty",
        ),
        (&["ids", "--counts", "--bits", "4..8:0"], "step 0"),
        (
            &["ids", "--counts", "--bits", "1..4"],
            "--bits: 1 is outside 2..24",
        ),
        (
            &["ids", "--counts", "--bits", "20..30"],
            "--bits: range '20..30' goes past 24",
        ),
        (
            &["ids", "--counts", "--distance", "1..4294967295"],
            "--distance: range '1..4294967295' goes past 24",
        ),
        (&["ids", "--bits", "4294967296"], "far above 24"),
        (&["ids", "--bogus"], "unexpected argument '--bogus'"),
        (&["ids", "--bits"], "a value is required for '--bits"),
        (&["idz"], "unrecognized subcommand 'idz'"),
        (
            &["ids", "--counts", "--bits", "4..8", "--distance", "0..2"],
            "--distance: 0 is outside 1..8",
        ),
        (
            &["ids", "--counts", "--bits", "4..8", "--distance", "9"],
            "--distance: 9 is outside 1..8",
        ),
        (
            &["ids", "--family", "/nonexistent/family.json"],
            "/nonexistent/family.json: ",
        ),
        (
            &["ids", "-o", "/nonexistent/dir/ids.txt"],
            "cannot write /nonexistent/dir/ids.txt",
        ),
    ];
    for (args, expected) in cases {
        let err = error_of(args);
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

#[test]
fn failures_leave_no_file_behind() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.json");
    let t = target.to_str().unwrap();
    for args in [
        vec!["ids", "--bits", "1", "-o", t],
        vec!["ids", "--distance", "9", "-o", t],
        vec!["ids", "--counts", "--bits", "4..", "-o", t],
        vec!["ids", "--format", "yaml", "-o", t],
    ] {
        error_of(&args);
        assert!(files_in(dir.path()).is_empty(), "{args:?} left files");
    }
    // An output path that is a folder cannot be replaced: no stray temp file.
    let folder = dir.path().join("folder");
    std::fs::create_dir(&folder).unwrap();
    error_of(&["ids", "-o", folder.to_str().unwrap()]);
    assert_eq!(files_in(dir.path()), ["folder"]);
    assert!(files_in(&folder).is_empty());
    // A failed run keeps the previous file intact.
    std::fs::write(&target, "previous").unwrap();
    error_of(&["ids", "--bits", "30", "-o", t]);
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "previous");
}

#[test]
fn broken_family_files_are_refused_with_the_file_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lab.json");
    let p = path.to_str().unwrap();
    let text = stdout_of(&["ids", "--bits", "8", "--format", "json"]);
    // Replace code 7 by 3: at distance 1 from code 1.
    let tampered = text.replace(
        "{\"id\": 2, \"code\": 7, \"binary\": \"00000111\", \"self_distance\": 2}",
        "{\"id\": 2, \"code\": 3}",
    );
    assert_ne!(tampered, text);
    std::fs::write(&path, tampered).unwrap();
    let err = error_of(&["ids", "--family", p]);
    assert!(
        err.contains(&format!("{p}: IDs 1 and 2 are at cyclic distance 1")),
        "{err}"
    );
    std::fs::write(&path, "not json").unwrap();
    let err = error_of(&["ids", "--family", p]);
    assert!(err.contains(&format!("{p}: not valid JSON")), "{err}");
    let err = error_of(&["ids", "--family", p, "--bits", "8"]);
    assert!(err.contains("drop --bits"), "{err}");
}
