//! `whycode sheet` end to end: files per format, manifest contents, user
//! templates, and byte-for-byte determinism.

use std::path::Path;

use crate::support::run_ok_in;

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn manifest(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

const SWARM: &[&str] = &[
    "sheet",
    "--bits",
    "8",
    "--distance",
    "2",
    "--ids",
    "1-5,9,12-14",
    "--diameter",
    "40mm",
    "--template",
    "a4",
    "--no-check",
];

#[test]
fn svg_and_png_sheets_write_one_file_per_page_and_a_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = SWARM.to_vec();
    args.extend(["-o", "swarm.svg"]);
    run_ok_in(dir.path(), &args);
    // 8 markers of 40 mm: 12 fit on an A4 page.
    assert_eq!(listing(dir.path()), ["swarm.json", "swarm.svg"]);
    let m = manifest(&dir.path().join("swarm.json"));
    assert_eq!(m["family"], serde_json::json!({"bits": 8, "distance": 2}));
    assert_eq!(m["pages"], 1);
    let ids: Vec<u64> = m["markers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["id"].as_u64().unwrap())
        .collect();
    assert_eq!(ids, [1, 2, 3, 4, 5, 9, 12, 13, 14]);
    let codes: Vec<u64> = m["markers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["code"].as_u64().unwrap())
        .collect();
    assert_eq!(codes, [1, 7, 11, 13, 19, 37, 59, 61, 87]);

    let dir = tempfile::tempdir().unwrap();
    run_ok_in(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "8",
            "--all",
            "--diameter",
            "50mm",
            "--template",
            "a5",
            "--dpi",
            "60",
            "--no-check",
            "-o",
            "set.png",
        ],
    );
    let m = manifest(&dir.path().join("set.json"));
    let pages = m["pages"].as_u64().unwrap();
    assert!(pages > 1);
    let mut expected: Vec<String> = (1..=pages).map(|k| format!("set-{k}.png")).collect();
    expected.push("set.json".into());
    expected.sort();
    assert_eq!(listing(dir.path()), expected);
    let page = image::open(dir.path().join("set-1.png")).unwrap();
    // A5 at 60 dpi.
    assert_eq!((page.width(), page.height()), (350, 496));
}

#[test]
fn same_inputs_give_the_same_bytes() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    for out in ["s.pdf", "s.svg", "s.png"] {
        for dir in [&a, &b] {
            let mut args = SWARM.to_vec();
            args.extend(["--dpi", "50", "-o", out]);
            run_ok_in(dir.path(), &args);
        }
    }
    for dir in [&a, &b] {
        run_ok_in(
            dir.path(),
            &[
                "marker",
                "--bits",
                "12",
                "--id",
                "40",
                "--diameter",
                "3cm",
                "--label",
                "-o",
                "m.pdf",
            ],
        );
    }
    let names = listing(a.path());
    assert_eq!(names, listing(b.path()));
    for name in names {
        let x = std::fs::read(a.path().join(&name)).unwrap();
        let y = std::fs::read(b.path().join(&name)).unwrap();
        assert!(x == y, "{name} differs between runs");
    }
}

#[test]
fn legacy_sheets_and_user_templates() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("square.toml"),
        "page_width = \"120mm\"\npage_height = \"120mm\"\nmargin = \"5mm\"\ngap = \"0mm\"\ncut_guides = true\nscale_bar = \"50mm\"\n",
    )
    .unwrap();
    run_ok_in(
        dir.path(),
        &[
            "sheet",
            "--legacy",
            "--count",
            "5",
            "--diameter",
            "30mm",
            "--template",
            "./square.toml",
            "--no-check",
            "-o",
            "w.pdf",
        ],
    );
    let m = manifest(&dir.path().join("w.json"));
    assert_eq!(m["legacy"], true);
    assert!(m["family"].is_null());
    assert_eq!(m["page_size_mm"], serde_json::json!([120.0, 120.0]));
    assert_eq!(m["template"], "./square.toml");
    let markers = m["markers"].as_array().unwrap();
    assert_eq!(markers.len(), 5);
    assert!(markers.iter().all(|x| x["id"] == 0 && x["code"] == 0));
    for x in markers {
        let (cx, cy) = (x["x_mm"].as_f64().unwrap(), x["y_mm"].as_f64().unwrap());
        // Black disc plus its 0.3 R margin stays inside the 5 mm page margins.
        assert!(cx - 19.5 >= 5.0 - 1e-9 && cx + 19.5 <= 115.0 + 1e-9);
        assert!(cy - 19.5 >= 5.0 - 1e-9);
    }
}

#[test]
fn list_templates_names_the_built_in_pages() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_ok_in(dir.path(), &["sheet", "--list-templates"]);
    for name in ["a3", "a4", "a5", "letter", "legal"] {
        assert!(
            out.lines().any(|l| l.starts_with(name)),
            "{name} missing:\n{out}"
        );
    }
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn without_options_the_whole_default_family_goes_to_swarm_pdf() {
    let dir = tempfile::tempdir().unwrap();
    run_ok_in(dir.path(), &["sheet"]);
    assert_eq!(listing(dir.path()), ["swarm.json", "swarm.pdf"]);
    let m = manifest(&dir.path().join("swarm.json"));
    assert_eq!(m["family"], serde_json::json!({"bits": 8, "distance": 2}));
    let markers = m["markers"].as_array().unwrap();
    let ids: Vec<u64> = markers.iter().map(|k| k["id"].as_u64().unwrap()).collect();
    assert_eq!(ids, (1..=16).collect::<Vec<u64>>());
    assert!(markers.iter().all(|k| k["diameter_mm"] == 40.0));
    assert_eq!(m["page_size_mm"], serde_json::json!([210.0, 297.0]));
}
