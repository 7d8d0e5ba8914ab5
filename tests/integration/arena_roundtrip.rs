//! Arena coordinates on simulated photos: a 2 m × 1.5 m floor seen from
//! 2.5 m through a distorting lens (`whycode arena`, then `detect
//! --arena`), markers on the floor and raised on robots, the lens-blind
//! plane mapping, and each refusal in one line.

use std::path::{Path, PathBuf};

use crate::support::{run_err, run_ok};
use whycode::arena::{Arena, ArenaError, Corners};
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode_testkit::arena::{self, Robot};

/// Per robot: position error (m) and heading error (degrees) of the JSON
/// line `out` against `robots`; panics naming a robot not located.
fn errors(out: &str, robots: &[Robot]) -> Vec<(f64, f64)> {
    let frame: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let markers = frame["markers"].as_array().unwrap();
    robots
        .iter()
        .map(|r| {
            let m = markers
                .iter()
                .find(|m| m["id"] == r.id)
                .unwrap_or_else(|| panic!("robot {} not found: {out}", r.id));
            let a = &m["arena"];
            let (x, y) = (a["x"].as_f64().unwrap(), a["y"].as_f64().unwrap());
            let yaw = a["yaw"].as_f64().unwrap();
            let turn = (yaw - r.yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            (
                (x - r.position.x).hypot(y - r.position.y),
                turn.abs().to_degrees(),
            )
        })
        .collect()
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn worst(values: &[f64]) -> f64 {
    values.iter().copied().fold(0.0, f64::max)
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A ceiling camera's photo of `robots` on the arena in a fresh folder,
/// and the camera's calibration file beside it.
fn photographed(robots: &[Robot], seed: u64) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let lens = arena::lens();
    let photo = dir.path().join("floor.png");
    arena::view(&lens, robots, seed).save(&photo).unwrap();
    let camera = dir.path().join("camera.yaml");
    std::fs::write(&camera, lens.to_ros_yaml("ceiling")).unwrap();
    (dir, photo, camera)
}

/// The photo, and the arena file `whycode arena` measures from it (corners
/// by ID, through the lens, `size` as typed).
struct Scene {
    dir: tempfile::TempDir,
    photo: PathBuf,
    arena_file: PathBuf,
}

fn measured_scene(robots: &[Robot], seed: u64, size: &str) -> Scene {
    let (dir, photo, camera) = photographed(robots, seed);
    let arena_file = dir.path().join("arena.yaml");
    run_ok(&[
        "arena",
        "--ids",
        "1,2,3,4",
        "--size",
        size,
        "--camera",
        path(&camera),
        path(&photo),
        "-o",
        path(&arena_file),
    ]);
    Scene {
        dir,
        photo,
        arena_file,
    }
}

#[test]
fn robots_are_placed_on_the_floor_through_a_distorting_lens() {
    let robots = arena::robots(12, 0.0, 1);
    let Scene {
        dir,
        photo,
        arena_file,
        ..
    } = measured_scene(&robots, 1, "2m,1.5m");
    let out = run_ok(&[
        "detect",
        "--arena",
        path(&arena_file),
        "--diameter",
        "80mm",
        "--format",
        "json",
        path(&photo),
    ]);
    let found = errors(&out, &robots);
    let position: Vec<f64> = found.iter().map(|e| e.0).collect();
    let yaw: Vec<f64> = found.iter().map(|e| e.1).collect();
    // Loose bounds (the example measures the figures): ignoring the lens
    // puts markers ~10 mm off.
    assert!(median(position.clone()) < 1e-3, "{found:?}");
    assert!(worst(&position) < 3e-3, "{found:?}");
    assert!(median(yaw) < 0.5, "{found:?}");

    // The same photo without the camera: a homography ignores the lens,
    // and the markers near the edges show it.
    let plane_file = dir.path().join("plane.yaml");
    run_ok(&[
        "arena",
        "--size",
        "2m,1.5m",
        path(&photo),
        "-o",
        path(&plane_file),
    ]);
    let plane = Arena::load(&plane_file).unwrap();
    assert_eq!(plane.ids, arena::CORNER_IDS, "outermost markers, in order");
    let out = run_ok(&[
        "detect",
        "--arena",
        path(&plane_file),
        "--format",
        "json",
        path(&photo),
    ]);
    let lens_blind: Vec<f64> = errors(&out, &robots).iter().map(|e| e.0).collect();
    assert!(worst(&lens_blind) > 5e-3, "{lens_blind:?}");
}

#[test]
fn a_calibrated_arena_places_markers_without_a_diameter() {
    let robots = arena::robots(12, 0.12, 3);
    let scene = measured_scene(&robots, 3, "2m,1.5m");
    let json = |extra: &[&str]| {
        let mut args = vec![
            "detect",
            "--arena",
            path(&scene.arena_file),
            "--marker-height",
            "12cm",
            "--format",
            "json",
        ];
        args.extend_from_slice(extra);
        args.push(path(&scene.photo));
        run_ok(&args)
    };
    let without = json(&[]);
    let placed: Vec<(f64, f64)> = errors(&without, &robots);
    let position: Vec<f64> = placed.iter().map(|e| e.0).collect();
    assert!(worst(&position) < 3e-3, "{placed:?}");
    assert!(
        median(placed.iter().map(|e| e.1).collect()) < 0.5,
        "{placed:?}"
    );
    // No diameter, no pose; the same places as with one, to a fraction of
    // a millimetre.
    let frame: serde_json::Value = serde_json::from_str(without.trim()).unwrap();
    assert!(frame["markers"][0]["position"].is_null(), "{without}");
    let with: Vec<f64> = errors(&json(&["--diameter", "80mm"]), &robots)
        .iter()
        .map(|e| e.0)
        .collect();
    for (a, b) in position.iter().zip(&with) {
        assert!((a - b).abs() < 1e-3, "{position:?} against {with:?}");
    }
}

#[test]
fn markers_raised_on_robots_are_placed_at_their_height() {
    let robots = arena::robots(8, 0.12, 2);
    let Scene {
        dir: _dir,
        photo,
        arena_file,
    } = measured_scene(&robots, 2, "2000mm,1500mm");
    let json = |height: &str| {
        run_ok(&[
            "detect",
            "--arena",
            path(&arena_file),
            "--marker-height",
            height,
            "--diameter",
            "8cm",
            "--format",
            "json",
            path(&photo),
        ])
    };
    let raised: Vec<f64> = errors(&json("12cm"), &robots).iter().map(|e| e.0).collect();
    assert!(worst(&raised) < 3e-3, "{raised:?}");
    // Taken for markers on the floor, they land where their rays meet it:
    // 5 % further out from under the camera.
    let floor: Vec<f64> = errors(&json("0"), &robots).iter().map(|e| e.0).collect();
    assert!(median(floor) > 0.01);
}

#[test]
fn csv_and_table_carry_the_arena_columns_only_with_an_arena() {
    let robots = arena::robots(6, 0.0, 6);
    let scene = measured_scene(&robots, 6, "2m,1.5m");
    let detect = |extra: &[&str], format: &str| {
        let mut args = vec!["detect", "--format", format];
        args.extend_from_slice(extra);
        args.push(path(&scene.photo));
        run_ok(&args)
    };
    // An arena measured through the lens places markers by their poses.
    let with_arena = ["--arena", path(&scene.arena_file), "--diameter", "80mm"];
    let csv = detect(&with_arena, "csv");
    let json: serde_json::Value = serde_json::from_str(detect(&with_arena, "json").trim()).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[header.len() - 4..],
        ["arena_x", "arena_y", "arena_z", "arena_yaw"]
    );
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let markers = json["markers"].as_array().unwrap();
    assert_eq!(rows.len(), markers.len());
    // Row by row the CSV says what the JSON says (both in the detector's
    // order), and every robot is placed.
    for (row, marker) in rows.iter().zip(markers) {
        assert_eq!(row.len(), header.len(), "{row:?}");
        assert_eq!(row[column("id")], marker["id"].to_string());
        for name in ["x", "y", "z", "yaw"] {
            let cell: f64 = row[column(&format!("arena_{name}"))].parse().unwrap();
            assert_eq!(cell, marker["arena"][name].as_f64().unwrap(), "{row:?}");
        }
    }
    for r in &robots {
        let row = rows
            .iter()
            .find(|row| row[column("id")] == r.id.to_string())
            .unwrap();
        let x: f64 = row[column("arena_x")].parse().unwrap();
        let y: f64 = row[column("arena_y")].parse().unwrap();
        assert!((x - r.position.x).hypot(y - r.position.y) < 3e-3, "{row:?}");
    }
    let table = detect(&with_arena, "table");
    assert!(table.contains("arena_m (x, y, z), yaw_deg"), "{table}");

    // Without --arena: the columns of every earlier release.
    let plain = detect(&[], "csv");
    assert_eq!(
        plain.lines().next().unwrap(),
        whycode::session::report::CSV_HEADER
    );
    assert!(plain.lines().all(|l| l.split(',').count() == 18), "{plain}");
    assert!(!detect(&[], "table").contains("arena"));
}

#[test]
fn without_a_lens_the_plane_mapping_removes_the_perspective_bias() {
    // An ideal camera: the homography is then exact, and mapping each
    // marker's outline back to the floor finds the circle's centre
    // (mapping the ellipse's centre would be off by the perspective bias).
    let mut lens = arena::lens();
    lens.distortion = [0.0; 5];
    let robots = arena::robots(12, 0.0, 3);
    let image = arena::view(&lens, &robots, 3);
    let mut detector = Detector::new(DetectorConfig {
        target: Target::WhyCode(arena::family()),
        ..DetectorConfig::default()
    });
    let found = detector.detect(&image);
    let plane = measured_without_camera(&found, &image).unwrap();
    for r in &robots {
        let d = found.iter().find(|d| d.id == r.id).unwrap();
        let at = plane
            .locate(d, None, (image.width(), image.height()))
            .unwrap();
        let error = (at.x - r.position.x).hypot(at.y - r.position.y);
        assert!(error < 1.5e-3, "robot {}: {error} m off", r.id);
    }
}

#[test]
fn each_refusal_is_one_line() {
    let (dir, photo, camera) = photographed(&arena::robots(3, 0.0, 4), 4);
    let out = dir.path().join("arena.yaml");
    let arena_cmd = |ids: &str, size: &str| {
        run_err(&[
            "arena",
            "--ids",
            ids,
            "--size",
            size,
            "--camera",
            path(&camera),
            path(&photo),
            "-o",
            path(&out),
        ])
    };
    let unseen = arena_cmd("1,2,3,99", "2m,1.5m");
    assert!(
        unseen.contains("corner ID 99 is not among the markers found (1, 2, 3, 4, 5, 6, 7)"),
        "{unseen}"
    );
    let swapped = arena_cmd("1,2,3,4", "1.5m,2m");
    assert!(
        swapped.contains("not a 1.500 m x 2.000 m rectangle"),
        "{swapped}"
    );
    let clockwise = arena_cmd("1,4,3,2", "1.5m,2m");
    assert!(clockwise.contains("clockwise"), "{clockwise}");
    let twice = arena_cmd("1,2,1,4", "2m,1.5m");
    assert!(twice.contains("ID 1 is given for two corners"), "{twice}");
    assert!(!out.exists(), "nothing written");
    let junk = dir.path().join("junk.yaml");
    std::fs::write(&junk, "size: [2, 1.5]\n").unwrap();
    let refused = run_err(&["detect", "--arena", path(&junk), path(&photo)]);
    assert!(
        refused.contains(&format!("{}: not an arena file", junk.display())),
        "{refused}"
    );
}

#[test]
fn a_corner_id_on_two_markers_is_refused() {
    let lens = arena::lens();
    let mut robots = arena::robots(2, 0.0, 5);
    robots[1].id = 3;
    let image = arena::view(&lens, &robots, 5);
    let found = Detector::new(DetectorConfig {
        target: Target::WhyCode(arena::family()),
        ..DetectorConfig::default()
    })
    .detect(&image);
    let err = measured_without_camera(&found, &image).unwrap_err();
    assert_eq!(err, ArenaError::SeenTwice { id: 3, count: 2 });
    assert_eq!(
        err.to_string(),
        "corner ID 3 was found on 2 markers: a corner's ID must be on one marker only"
    );
}

/// The test arena measured from one photo's detections by its corner IDs,
/// on the floor, without a camera (a plane-to-image mapping).
fn measured_without_camera(
    found: &[whycode::detect::Detection],
    image: &image::GrayImage,
) -> Result<Arena, ArenaError> {
    Arena::measure(
        Corners::Ids(arena::CORNER_IDS),
        arena::SIZE_M,
        0.0,
        None,
        found,
        (image.width(), image.height()),
    )
}
