//! `whycode detect` as a user runs it: the real binary on rendered images.

mod ring_support;

use ring_support::{render, render_marker, View};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use whycode::family::Family;
use whycode::geometry::Marker;

fn whycode(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_whycode"))
        .args(args)
        .output()
        .expect("run whycode")
}

fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8(out.stderr.clone()).unwrap()
}

/// A 90 px marker of the 8-bit d = 2 family, ID `id`, turned visually CCW
/// by `rotation`; returns the file and the true (u, v, yaw).
fn marker_png(dir: &Path, name: &str, id: u32, rotation: f64) -> (PathBuf, (f64, f64, f64)) {
    let family = Family::generate(8, 2).unwrap();
    let mut view = View::new(8, family.code(id).unwrap(), 90.0, rotation);
    view.gaussian_blur = 0.6;
    let r = render(&view);
    let path = dir.join(name);
    r.image.save(&path).unwrap();
    (path, (r.ellipse.u, r.ellipse.v, r.yaw))
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
    let yaw_err = (m["yaw"].as_f64().unwrap() - yaw).rem_euclid(std::f64::consts::TAU);
    assert!(
        yaw_err.min(std::f64::consts::TAU - yaw_err) < 0.5f64.to_radians(),
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
        "image,id,code,u,v,yaw,axis_major,axis_minor,confidence,x,y,z,qx,qy,qz,qw"
    );
    assert_eq!(rows.len(), 3, "{text}");
    assert!(rows[1].starts_with(&format!("{a},3,")), "{text}");
    assert!(rows[2].starts_with(&format!("{b},9,")), "{text}");
    assert!(
        rows[1].ends_with(",,,,,,,"),
        "no pose without a camera: {text}"
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
    let annotated = image::open(out_dir.join("photo.png")).unwrap().to_rgb8();
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
    let view = View::new(8, 1, 80.0, 0.0);
    let r = render_marker(&view, &Marker::whycon(80.0));
    let path = dir.path().join("legacy.png");
    r.image.save(&path).unwrap();
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
    assert!((m["u"].as_f64().unwrap() - r.ellipse.u).abs() < 0.3);
}
