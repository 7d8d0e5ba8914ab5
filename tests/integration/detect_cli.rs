//! `whycode detect` as a user runs it: the real binary on rendered images.

use crate::support::{marker_photo, stderr, stdout, whycode};
use std::path::{Path, PathBuf};
use std::process::Output;
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::angle::angle_between;

/// A 90 px marker of the 8-bit d = 2 family, ID `id`, turned by `roll`;
/// returns the file and the true (u, v, yaw).
fn marker_png(dir: &Path, name: &str, id: u32, roll: f64) -> (PathBuf, (f64, f64, f64)) {
    let family = Family::generate(8, 2).unwrap();
    let marker = Marker::whycode(8, family.code(id).unwrap(), 50.0);
    let (image, truth) = marker_photo(marker, id, 90.0, roll);
    let path = dir.join(name);
    image.save(&path).unwrap();
    (path, (truth.u, truth.v, truth.yaw))
}

fn json_lines(out: &Output) -> Vec<serde_json::Value> {
    stdout(out)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect()
}

#[test]
fn json_prints_one_object_per_image_with_the_documented_fields() {
    let dir = tempfile::tempdir().unwrap();
    let (path, (u, v, yaw)) = marker_png(dir.path(), "m5.png", 5, 0.7);
    let out = whycode(&[
        "detect",
        "--bits",
        "8",
        "--distance",
        "2",
        "--format",
        "json",
        path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 1);
    let frame = &lines[0];
    assert_eq!(frame["image"], path.to_str().unwrap());
    let side = frame["width"].as_u64().unwrap();
    assert_eq!(frame["height"].as_u64().unwrap(), side);
    assert!(frame["elapsed_ms"].as_f64().unwrap() >= 0.0);
    let markers = frame["markers"].as_array().unwrap();
    assert_eq!(markers.len(), 1, "{frame}");
    let m = &markers[0];
    for key in [
        "id",
        "code",
        "u",
        "v",
        "yaw",
        "axes",
        "confidence",
        "position",
        "rotation",
        "quaternion",
    ] {
        assert!(m.get(key).is_some(), "missing {key}: {m}");
    }
    assert!((m["u"].as_f64().unwrap() - u).abs() < 0.3, "{m}");
    assert!((m["v"].as_f64().unwrap() - v).abs() < 0.3, "{m}");
    assert!((m["axes"][0].as_f64().unwrap() - 45.0).abs() < 1.5, "{m}");
    assert!(m["position"].is_null() && m["rotation"].is_null() && m["quaternion"].is_null());
    assert_eq!(m["id"], 5, "{m}");
    assert_eq!(m["code"], Family::generate(8, 2).unwrap().code(5).unwrap());
    assert!(
        angle_between(m["yaw"].as_f64().unwrap(), yaw) < 0.5f64.to_radians(),
        "{m} vs {yaw}"
    );
    assert!(m["confidence"].as_f64().unwrap() > 0.5);
}

#[test]
fn csv_and_table_formats_list_every_marker() {
    let dir = tempfile::tempdir().unwrap();
    let (a, _) = marker_png(dir.path(), "a.png", 3, 0.0);
    let (b, _) = marker_png(dir.path(), "b.png", 9, 1.0);
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let out = whycode(&["detect", "--format", "csv", a, b]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(
        rows[0],
        "image,id,code,u,v,yaw,axis_major,axis_minor,confidence,x,y,z,qx,qy,qz,qw,bits,unreadable"
    );
    assert_eq!(rows.len(), 3, "{text}");
    assert!(rows[1].starts_with(&format!("{a},3,")), "{text}");
    assert!(rows[2].starts_with(&format!("{b},9,")), "{text}");
    assert!(
        rows[1].ends_with(",,,,,,,8,0"),
        "no pose without a camera, an 8-bit ring, readable: {text}"
    );

    let out = whycode(&["detect", a, b]);
    assert!(out.status.success());
    let text = stdout(&out);
    assert!(text.contains(a) && text.contains(b), "{text}");
    assert!(text.contains("yaw_deg"), "{text}");
}

#[test]
fn a_folder_is_a_sequence_in_name_order_and_bad_frames_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for (k, name) in ["0003.png", "0001.png", "0002.png"].iter().enumerate() {
        marker_png(&frames, name, 7, 0.1 * k as f64);
    }
    std::fs::write(frames.join("0004.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    std::fs::write(frames.join("notes.txt"), "not an image").unwrap();
    let out = whycode(&["detect", "--format", "json", frames.to_str().unwrap()]);
    assert!(!out.status.success(), "a corrupt frame must fail the run");
    let lines = json_lines(&out);
    let names: Vec<String> = lines
        .iter()
        .map(|l| {
            Path::new(l["image"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert_eq!(names, ["0001.png", "0002.png", "0003.png"]);
    for l in &lines {
        assert_eq!(l["markers"][0]["id"], 7, "{l}");
    }
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("whycode: error: ") && err.contains("0004.png"),
        "{err}"
    );
}

#[test]
fn missing_and_corrupt_files_fail_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.png");
    let out = whycode(&["detect", missing.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("nope.png"), "{err}");
    assert!(stdout(&out).is_empty());

    let corrupt = dir.path().join("broken.jpg");
    std::fs::write(&corrupt, [0xff, 0xd8, 0xff, 0xe0, 0, 16, b'J', b'F']).unwrap();
    let out = whycode(&["detect", corrupt.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("whycode: error: ") && err.contains("broken.jpg"),
        "{err}"
    );

    // Bad option values are refused before any work.
    let (good, _) = marker_png(dir.path(), "ok.png", 1, 0.0);
    let good = good.to_str().unwrap();
    for args in [
        &["detect", "--diameter", "abc", good][..],
        &["detect", "--camera", "cam.yaml", good],
        &["detect", "--bits", "8", "--distance", "9", good],
        &["detect", "--legacy", "--bits", "8", good],
    ] {
        let out = whycode(args);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(!stderr(&out).is_empty());
    }
}

#[test]
fn a_failed_run_ends_on_its_error_after_the_closing_note() {
    // A 7-bit marker read under the default 8-bit family earns the note
    // that closes the run; a corrupt second input fails it.
    let dir = tempfile::tempdir().unwrap();
    let family = Family::generate(7, 2).unwrap();
    let marker = Marker::whycode(7, family.code(3).unwrap(), 50.0);
    let (image, _) = marker_photo(marker, 3, 90.0, 0.0);
    let seven = dir.path().join("seven.png");
    image.save(&seven).unwrap();
    let broken = dir.path().join("broken.png");
    std::fs::write(&broken, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let (seven, broken) = (seven.to_str().unwrap(), broken.to_str().unwrap());

    let out = whycode(&["detect", seven, broken]);
    assert!(!out.status.success());
    let err = stderr(&out);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 3, "{err}");
    assert!(lines[0].starts_with("whycode: error: ") && lines[0].contains("broken.png"));
    assert!(lines[1].starts_with("whycode: note: 7-bit codes"), "{err}");
    assert!(
        lines[2].starts_with("whycode: error: the run failed: ") && lines[2].contains("broken.png"),
        "{err}"
    );

    // Two failures: the last line counts them and names the first.
    let out = whycode(&["detect", broken, seven, broken]);
    assert!(!out.status.success());
    let err = stderr(&out);
    let last = err.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("whycode: error: 2 failures, the first: ") && last.contains("broken.png"),
        "{err}"
    );

    // Without a failure the note is the last word, and the run succeeds.
    let out = whycode(&["detect", seven]);
    assert!(out.status.success());
    assert!(stderr(&out).starts_with("whycode: note: 7-bit codes"));
}

#[test]
fn annotate_writes_the_image_with_markers_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let (path, (u, v, _)) = marker_png(dir.path(), "photo.png", 4, 0.4);
    let out_dir = dir.path().join("annotated");
    let out = whycode(&[
        "detect",
        "--annotate",
        out_dir.to_str().unwrap(),
        path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let annotated = image::open(out_dir.join("photo.annotated.png"))
        .unwrap()
        .to_rgb8();
    let original = image::open(&path).unwrap().to_luma8();
    assert_eq!(annotated.dimensions(), original.dimensions());
    // The outline is drawn in colour on the grey image, on the outer edge.
    let coloured = annotated
        .pixels()
        .filter(|p| p.0[0].abs_diff(p.0[1]) > 60 || p.0[1].abs_diff(p.0[2]) > 60)
        .count();
    assert!(coloured > 200, "{coloured} coloured pixels");
    let edge = annotated.get_pixel((u + 45.0).round() as u32, v.round() as u32);
    assert!(edge.0[1] > edge.0[0] && edge.0[1] > edge.0[2], "{edge:?}");
}

#[test]
fn legacy_markers_have_no_id_and_no_yaw() {
    let dir = tempfile::tempdir().unwrap();
    let (image, truth) = marker_photo(Marker::whycon(50.0), 0, 80.0, 0.0);
    let path = dir.path().join("legacy.png");
    image.save(&path).unwrap();
    let out = whycode(&[
        "detect",
        "--legacy",
        "--format",
        "json",
        path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    let m = &lines[0]["markers"][0];
    assert_eq!(m["id"], 0);
    assert!(m["yaw"].is_null() && m["code"].is_null(), "{m}");
    assert!((m["u"].as_f64().unwrap() - truth.u).abs() < 0.3);
}

#[test]
fn legacy_markers_below_the_originals_size_floor_need_min_ink() {
    // 11 px across: a black ring of some 80 pixels, under the original's
    // 100.
    let dir = tempfile::tempdir().unwrap();
    let (image, truth) = marker_photo(Marker::whycon(50.0), 0, 11.0, 0.0);
    let path = dir.path().join("small.png");
    image.save(&path).unwrap();
    let path = path.to_str().unwrap();
    let markers = |extra: &[&str]| {
        let mut args = vec!["detect", "--legacy", "--format", "json", path];
        args.extend_from_slice(extra);
        let out = whycode(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        json_lines(&out)[0]["markers"].as_array().unwrap().clone()
    };
    assert!(markers(&[]).is_empty());
    let found = markers(&["--min-ink", "50"]);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!((found[0]["u"].as_f64().unwrap() - truth.u).abs() < 0.3);
    let out = whycode(&["detect", "--legacy", "--min-ink", "-3", path]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--min-ink"), "{}", stderr(&out));
    let out = whycode(&["detect", "--min-ink", "50", path]);
    assert!(!out.status.success(), "--min-ink without --legacy");
}

#[test]
fn with_a_camera_and_a_diameter_the_pose_is_reported() {
    use nalgebra::Vector3;
    use whycode::camera::Camera;
    use whycode::simulate::{render as simulate, LooseMarker, Placement, Scene, SceneObject};
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera::ideal(640, 480, 70.0);
    let family = Family::generate(8, 2).unwrap();
    let placement = Placement::viewed(Vector3::new(0.05, -0.02, 0.6), 0.5, 0.2, 1.0);
    let marker = Marker::whycode(8, family.code(11).unwrap(), 122.0);
    let mut scene = Scene::new(camera);
    scene
        .objects
        .push(SceneObject::Marker(LooseMarker::new(marker, 11, placement)));
    let (image, truth) = simulate(&scene);
    let path = dir.path().join("view.png");
    image.save(&path).unwrap();
    let yaml = format!(
        "image_width: 640\nimage_height: 480\ncamera_name: test\n\
         camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{fx}, 0, {cx}, 0, {fy}, {cy}, 0, 0, 1]\n\
         distortion_model: plumb_bob\n\
         distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n",
        fx = camera.fx,
        fy = camera.fy,
        cx = camera.cx,
        cy = camera.cy
    );
    let cam_path = dir.path().join("cam.yaml");
    std::fs::write(&cam_path, yaml).unwrap();
    let out = whycode(&[
        "detect",
        "--camera",
        cam_path.to_str().unwrap(),
        "--diameter",
        "122mm",
        "--format",
        "json",
        path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    let m = &lines[0]["markers"][0];
    assert_eq!(m["id"], 11, "{m}");
    let t = &truth.markers[0];
    let position: Vec<f64> = m["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let err = (0..3)
        .map(|i| (position[i] - t.position[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        err < 0.01 * 0.6,
        "position {position:?} vs {:?}",
        t.position
    );
    let q: Vec<f64> = m["quaternion"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let dot: f64 = (0..4).map(|i| q[i] * t.quaternion[i]).sum();
    let angle = 2.0 * dot.abs().min(1.0).acos();
    assert!(
        angle < 2f64.to_radians(),
        "rotation off by {}°",
        angle.to_degrees()
    );
    assert_eq!(m["rotation"].as_array().unwrap().len(), 3);

    // A metre figure without unit is metres; the table shows the position.
    let out = whycode(&[
        "detect",
        "--camera",
        cam_path.to_str().unwrap(),
        "--diameter",
        "0.122",
        path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("position_m"), "{}", stdout(&out));
}

/// The two-fold pose ambiguity on a tilted board under blur and noise: both
/// candidate normals cast the same outer ellipse, and the inner edges'
/// blurred sub-pixel positions once chose the wrong one for 2-4 of 12
/// markers (50-70° off). The ring's radial edges, which run through the
/// marker's true centre, decide. Normals must be within 3° of the truth.
#[test]
fn tilted_board_keeps_the_right_normal_under_blur_and_noise() {
    let dir = tempfile::tempdir().unwrap();
    let camera = dir.path().join("cam.yaml");
    std::fs::write(
        &camera,
        "image_width: 1920\nimage_height: 1080\ncamera_name: sim\n\
         camera_matrix:\n  rows: 3\n  cols: 3\n  data: [1662.77, 0, 959.5, 0, 1662.77, 539.5, 0, 0, 1]\n\
         distortion_model: plumb_bob\n\
         distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n",
    )
    .unwrap();
    let camera = camera.to_str().unwrap();
    for seed in ["1", "2", "3"] {
        let photo = dir.path().join(format!("board-{seed}.png"));
        let photo = photo.to_str().unwrap();
        let out = whycode(&[
            "simulate",
            "--bits",
            "12",
            "--ids",
            "1-12",
            "--diameter",
            "50mm",
            "--tilt",
            "30deg",
            "--blur",
            "2px",
            "--noise",
            "8",
            "--seed",
            seed,
            "--camera",
            camera,
            "-o",
            photo,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(photo.replace(".png", ".json")).unwrap())
                .unwrap();
        let out = whycode(&[
            "detect",
            "--bits",
            "12",
            "--camera",
            camera,
            "--diameter",
            "50mm",
            "--format",
            "json",
            photo,
        ]);
        let found = &json_lines(&out)[0]["markers"];
        let normal = |m: &serde_json::Value| -> [f64; 3] {
            let r = &m["rotation"];
            [0, 1, 2].map(|i| r[i][2].as_f64().unwrap())
        };
        for t in truth["markers"].as_array().unwrap() {
            let d = found
                .as_array()
                .unwrap()
                .iter()
                .find(|d| d["id"] == t["id"])
                .unwrap_or_else(|| panic!("seed {seed}: ID {} not found", t["id"]));
            let (a, b) = (normal(d), normal(t));
            let cos = a
                .iter()
                .zip(&b)
                .map(|(x, y)| x * y)
                .sum::<f64>()
                .clamp(-1.0, 1.0);
            let off = cos.acos().to_degrees();
            assert!(
                off < 3.0,
                "seed {seed}, ID {}: normal {off:.1}° off",
                t["id"]
            );
        }
    }
}

#[test]
fn timings_give_each_frame_its_stages_and_the_run_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for k in 0..3 {
        marker_png(&frames, &format!("f{k}.png"), 5, 0.2 * k as f64);
    }
    let out = whycode(&[
        "detect",
        "--timings",
        "--format",
        "json",
        frames.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 3);
    for frame in &lines {
        let timings = &frame["timings"];
        assert_eq!(timings["frames"], 1, "{frame}");
        let stages = timings["stages_ms"].as_object().unwrap();
        // (serde_json's map sorts the keys; the line has them in stage order.)
        let names: Vec<&str> = stages.keys().map(String::as_str).collect();
        assert_eq!(
            names,
            [
                "describe",
                "fallback",
                "finish",
                "follow",
                "pose",
                "prepare",
                "scan",
                "shade",
                "threshold"
            ]
        );
        let line = serde_json::to_string(frame).unwrap();
        assert!(line.contains("\"timings\""), "{line}");
        let sum: f64 = stages.values().map(|v| v.as_f64().unwrap()).sum();
        let total = timings["total_ms"].as_f64().unwrap();
        // Each figure is rounded to 0.1 µs.
        assert!((sum - total).abs() < 1e-3, "{sum} vs {total}");
        assert_eq!(frame["markers"].as_array().unwrap().len(), 1);
    }
    let err = stderr(&out);
    assert!(err.contains("time per stage:"), "{err}");
    assert!(err.contains("(3 frames)"), "{err}");

    // Without the option neither appears.
    let plain = whycode(&["detect", "--format", "json", frames.to_str().unwrap()]);
    assert!(json_lines(&plain)
        .iter()
        .all(|f| f.get("timings").is_none()));
    assert!(!stderr(&plain).contains("time per stage"));
}
