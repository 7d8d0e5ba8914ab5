//! Regression tests for the defects 650 bad inputs found on the measuring
//! surfaces (calibrate, arena, boards, bags, videos): outputs over files a
//! command reads, outputs lost to a closed pipe, sizes taken on trust,
//! configuration files that are not files, results silently wrong.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::support::{stderr, tool_marker_png, whycode_in};
use whycode::ros::cdr;
use whycode::ros::msg::{CameraInfo, Header, Image, RosType, Time};

fn ok(out: &Output) {
    assert!(out.status.success(), "{}", stderr(out));
}

/// Fails with one line on stderr, nothing on stdout; returns the line.
fn one_line_error(out: &Output) -> String {
    assert!(!out.status.success(), "succeeded: {}", stderr(out));
    assert_eq!(out.status.code(), Some(1), "{}", stderr(out));
    let text = stderr(out);
    assert_eq!(text.lines().count(), 1, "{text}");
    text.trim_end().to_string()
}

/// A sheet of 8-bit IDs 1-4 (`name`.pdf or .png pages and `name`.json).
fn sheet(dir: &Path, output: &str) {
    ok(&whycode_in(
        dir,
        &[
            "sheet",
            "--ids",
            "1-4",
            "--diameter",
            "30mm",
            "--no-check",
            "-o",
            output,
        ],
    ));
}

#[test]
fn calibrate_never_writes_over_the_sheet_its_manifest_lists() {
    let dir = tempfile::tempdir().unwrap();
    sheet(dir.path(), "target.pdf");
    tool_marker_png(dir.path(), "view.png");
    let before = std::fs::read(dir.path().join("target.pdf")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "calibrate",
            "--manifest",
            "target.json",
            "view.png",
            "-o",
            "target.pdf",
        ],
    ));
    assert!(
        line.contains("target.pdf: would overwrite") && line.contains("which this command reads"),
        "{line}"
    );
    assert_eq!(
        std::fs::read(dir.path().join("target.pdf")).unwrap(),
        before
    );
}

#[test]
fn simulate_never_writes_over_the_pages_its_manifest_lists() {
    let dir = tempfile::tempdir().unwrap();
    sheet(dir.path(), "target.pdf");
    let pdf = std::fs::read(dir.path().join("target.pdf")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "simulate",
            "--manifest",
            "target.json",
            "-o",
            "v.png",
            "--truth",
            "target.pdf",
        ],
    ));
    assert!(line.contains("target.pdf: would overwrite"), "{line}");
    assert_eq!(std::fs::read(dir.path().join("target.pdf")).unwrap(), pdf);
    assert!(!dir.path().join("v.png").exists());
    // A sheet of PNG pages: its own page as the image.
    sheet(dir.path(), "pages.png");
    let page = std::fs::read(dir.path().join("pages.png")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "simulate",
            "--manifest",
            "pages.json",
            "-o",
            "pages.png",
            "--truth",
            "t.json",
        ],
    ));
    assert!(line.contains("pages.png: would overwrite"), "{line}");
    assert_eq!(std::fs::read(dir.path().join("pages.png")).unwrap(), page);
}

#[test]
fn arena_never_writes_over_its_family_file() {
    let dir = tempfile::tempdir().unwrap();
    ok(&whycode_in(
        dir.path(),
        &["ids", "--bits", "8", "--format", "json", "-o", "fam.json"],
    ));
    tool_marker_png(dir.path(), "floor.png");
    let before = std::fs::read(dir.path().join("fam.json")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "arena",
            "--family",
            "fam.json",
            "--size",
            "2m,1.5m",
            "floor.png",
            "-o",
            "./fam.json",
        ],
    ));
    assert!(line.contains("would overwrite fam.json"), "{line}");
    assert_eq!(std::fs::read(dir.path().join("fam.json")).unwrap(), before);
}

/// Writes a bag of `messages` (topic, schema name, CDR bytes) with the
/// same MCAP writer the library uses for its detections bag.
fn write_bag(path: &Path, messages: &[(&str, String, Vec<u8>)]) {
    let mut writer = mcap::WriteOptions::new()
        .profile("ros2")
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let mut channels: BTreeMap<String, u16> = BTreeMap::new();
    for (k, (topic, schema, data)) in messages.iter().enumerate() {
        let channel = match channels.get(*topic) {
            Some(&c) => c,
            None => {
                let s = writer.add_schema(schema, "ros2msg", b"").unwrap();
                let c = writer
                    .add_channel(s, topic, "cdr", &BTreeMap::new())
                    .unwrap();
                channels.insert(topic.to_string(), c);
                c
            }
        };
        let time = 1_000_000_000 + k as u64 * 33_000_000;
        writer
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: k as u32,
                    log_time: time,
                    publish_time: time,
                },
                data,
            )
            .unwrap();
    }
    writer.finish().unwrap();
    std::fs::write(path, writer.into_inner().into_inner()).unwrap();
}

fn header(k: usize) -> Header {
    Header {
        stamp: Time {
            sec: 1 + k as i32,
            nanosec: 0,
        },
        frame_id: "cam".into(),
    }
}

/// A mono8 Image message of the marker photo in `dir`.
fn marker_frame(dir: &Path, k: usize) -> (&'static str, String, Vec<u8>) {
    let image = whycode::load_gray(&dir.join("view.png")).unwrap();
    let message = Image {
        header: header(k),
        height: image.height(),
        width: image.width(),
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: image.width(),
        data: image.into_raw(),
    };
    (
        "/cam/image_raw",
        Image::schema_name(),
        cdr::encode(&message),
    )
}

fn camera_info(k: usize, width: u32, height: u32, d: Vec<f64>) -> (&'static str, String, Vec<u8>) {
    let f = 400.0;
    let (cx, cy) = (f64::from(width) / 2.0, f64::from(height) / 2.0);
    let message = CameraInfo {
        header: header(k),
        height,
        width,
        distortion_model: "plumb_bob".into(),
        d,
        k: [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        ..CameraInfo::default()
    };
    (
        "/cam/camera_info",
        CameraInfo::schema_name(),
        cdr::encode(&message),
    )
}

#[test]
fn a_bag_output_is_written_when_the_reader_of_stdout_goes_away() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let frames: Vec<_> = (0..6).map(|k| marker_frame(dir.path(), k)).collect();
    write_bag(&dir.path().join("big.mcap"), &frames);
    // `| head -c1`: the reader is gone before the first line is written.
    let mut child = Command::new(env!("CARGO_BIN_EXE_whycode"))
        .current_dir(dir.path())
        .args([
            "detect",
            "--bits",
            "8",
            "--format",
            "json",
            "--output",
            "found.mcap",
            "big.mcap",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    ok(&out);
    let bag = dir.path().join("found.mcap");
    assert!(bag.is_file(), "no bag written: {}", stderr(&out));
    assert!(
        stderr(&out).contains("wrote the detections to found.mcap"),
        "{}",
        stderr(&out)
    );
}

#[cfg(unix)]
#[test]
fn a_bag_message_declaring_more_bytes_than_it_holds_allocates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut message = cdr::encode(&Image {
        header: header(0),
        height: 2,
        width: 2,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: 2,
        data: vec![0; 4],
    });
    // The data's length word: 4 GB, in front of 4 bytes.
    let at = message.len() - 8;
    message[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    write_bag(
        &dir.path().join("bad.mcap"),
        &[("/cam/image_raw", Image::schema_name(), message)],
    );
    // Under a 3 GB address-space limit a 4 GB allocation aborts the process.
    let out = Command::new("sh")
        .current_dir(dir.path())
        .arg("-c")
        .arg(format!(
            "ulimit -v 3000000 && exec {} detect bad.mcap",
            env!("CARGO_BIN_EXE_whycode")
        ))
        .output()
        .unwrap();
    let line = one_line_error(&out);
    assert_eq!(
        line,
        "whycode: error: bad.mcap: /cam/image_raw, message 0: message declares a byte array \
         of 4294967295 bytes, but only 4 bytes follow"
    );
}

/// Runs whycode in `dir`, killed after 20 s (a read of a FIFO with no
/// writer would block forever).
fn whycode_bounded(dir: &Path, args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_whycode"))
        .current_dir(dir)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(20) {
            child.kill().unwrap();
            panic!("whycode {args:?} still running after 20 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[cfg(unix)]
#[test]
fn configuration_files_that_are_not_files_or_too_large_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let made = Command::new("mkfifo")
        .arg(dir.path().join("fifo"))
        .status()
        .unwrap();
    assert!(made.success());
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    let huge = std::fs::File::create(dir.path().join("huge.json")).unwrap();
    huge.set_len(300 << 20).unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "calibrate",
                "--manifest",
                "/dev/zero",
                "view.png",
                "-o",
                "c.yaml",
            ],
            "/dev/zero: is a device, not a file: give the sheet manifest itself",
        ),
        (
            vec!["detect", "--family", "fifo", "view.png"],
            "fifo: is a FIFO (named pipe), not a file: give the family file itself",
        ),
        (
            vec![
                "detect",
                "--camera",
                "fifo",
                "--diameter",
                "20mm",
                "view.png",
            ],
            "fifo: is a FIFO (named pipe), not a file: give the camera calibration itself",
        ),
        (
            vec!["detect", "--arena", "folder", "view.png"],
            "folder: is a folder, not a file: give the arena file itself",
        ),
        (
            vec![
                "detect",
                "--board",
                "/dev/zero",
                "--camera",
                "fifo",
                "view.png",
            ],
            "fifo: is a FIFO",
        ),
        (
            vec!["sheet", "--template", "./fifo", "-o", "s.pdf"],
            "fifo: is a FIFO (named pipe), not a file: give the template itself",
        ),
        (
            vec!["validate", "--manifest", "huge.json", "view.png"],
            "huge.json: is 300 MB, more than any sheet manifest (256 MB)",
        ),
        (
            vec!["detect", "fifo"],
            "fifo: is a FIFO (named pipe), not a file: give the image itself",
        ),
    ];
    for (args, expected) in cases {
        let out = whycode_bounded(dir.path(), &args);
        let line = one_line_error(&out);
        assert!(line.contains(expected), "{args:?}: {line}");
    }
    // A recording that is a FIFO: ffmpeg or the bag reader would wait on it.
    for name in ["run.mcap", "run.mp4"] {
        let made = Command::new("mkfifo")
            .arg(dir.path().join(name))
            .status()
            .unwrap();
        assert!(made.success());
        let line = one_line_error(&whycode_bounded(dir.path(), &["detect", name]));
        assert!(
            line.ends_with(&format!(
                "{name}: is a FIFO (named pipe), not a file: give the recording itself"
            )),
            "{line}"
        );
    }
}

#[test]
fn a_truncated_video_ends_with_one_line_not_success() {
    let dir = tempfile::tempdir().unwrap();
    for (name, codec) in [
        (
            "v.mp4",
            &[
                "-c:v",
                "libx264",
                "-pix_fmt",
                "yuv420p",
                "-movflags",
                "+faststart",
            ][..],
        ),
        ("v.mkv", &["-c:v", "libx264", "-pix_fmt", "yuv420p"][..]),
        ("v.avi", &["-c:v", "mjpeg"][..]),
    ] {
        let path = dir.path().join(name);
        let made = Command::new("ffmpeg")
            .args(["-hide_banner", "-loglevel", "error", "-y", "-f", "lavfi"])
            .args(["-i", "testsrc=size=320x240:rate=10", "-t", "3"])
            .args(codec)
            .arg(&path)
            .output()
            .expect("ffmpeg runs (apt-get install ffmpeg)");
        assert!(made.status.success(), "{}", stderr(&made));
        ok(&whycode_in(dir.path(), &["detect", name]));
        let whole = std::fs::read(&path).unwrap();
        let cut = format!("cut-{name}");
        std::fs::write(dir.path().join(&cut), &whole[..whole.len() * 6 / 10]).unwrap();
        let out = whycode_in(dir.path(), &["detect", "--format", "json", &cut]);
        assert_eq!(out.status.code(), Some(1), "{cut}: {}", stderr(&out));
        let text = stderr(&out);
        let last = text.lines().last().unwrap_or_default();
        assert!(
            last.starts_with(&format!(
                "whycode: error: {cut}: truncated or damaged video"
            )),
            "{text}"
        );
        // The frames before the damage were read and printed.
        assert!(
            crate::support::stdout(&out).lines().count() > 3,
            "{cut}: no frames"
        );
    }
}

#[test]
fn a_bag_camera_info_no_lens_gives_is_refused_and_said() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let (w, h) = image::image_dimensions(dir.path().join("view.png")).unwrap();
    let mut messages = vec![camera_info(0, w, h, vec![1e30, 0.0, 0.0, 0.0, 0.0])];
    messages.extend((0..3).map(|k| marker_frame(dir.path(), k)));
    write_bag(&dir.path().join("run.mcap"), &messages);
    let out = whycode_in(
        dir.path(),
        &[
            "detect",
            "--bits",
            "8",
            "--diameter",
            "20mm",
            "--format",
            "json",
            "run.mcap",
        ],
    );
    ok(&out);
    let text = stderr(&out);
    assert!(
        text.contains("run.mcap: refused 1 camera_info message (first: camera_info is not a real lens: distortion_coefficients [1e30"),
        "{text}"
    );
    for line in crate::support::stdout(&out).lines() {
        let frame: serde_json::Value = serde_json::from_str(line).unwrap();
        assert!(frame["markers"][0]["position"].is_null(), "{line}");
    }
    // The same check as a --camera file: fx = 1e308 is no lens either.
    let mut info = CameraInfo {
        width: 640,
        height: 480,
        k: [1e308, 0.0, 320.0, 0.0, 1e308, 240.0, 0.0, 0.0, 1.0],
        ..CameraInfo::default()
    };
    let err = info.camera(false).unwrap_err().to_string();
    assert!(err.contains("fx = 1e308"), "{err}");
    info.k[0] = f64::NAN;
    assert!(info.camera(false).is_err());
}

/// An arena file measured with a camera looking straight down from 2.5 m
/// onto a 2 m x 1.5 m floor; `camera` and `marker_height` as given.
fn arena_yaml(camera: &str, marker_height: f64) -> String {
    format!(
        "format: whycode-arena\nversion: 1\nids: [1, 2, 3, 4]\nsize: [2.0, 1.5]\n\
         marker_height: {marker_height}\ncorner_error: 0.001\ncamera: {camera}\n\
         floor:\n  rotation: [[1, 0, 0], [0, -1, 0], [0, 0, -1]]\n  translation: [-1.0, 0.75, 2.5]\n"
    )
}

const SANE_CAMERA: &str =
    "{fx: 400, fy: 400, cx: 239.5, cy: 239.5, distortion: [0, 0, 0, 0, 0], width: 480, height: 480}";

#[test]
fn arena_files_get_the_camera_checks_and_heights_below_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    std::fs::write(dir.path().join("sane.yaml"), arena_yaml(SANE_CAMERA, 0.0)).unwrap();
    ok(&whycode_in(
        dir.path(),
        &["detect", "--bits", "8", "--arena", "sane.yaml", "view.png"],
    ));
    let wild = SANE_CAMERA.replace("fx: 400", "fx: 1e308");
    std::fs::write(dir.path().join("wild.yaml"), arena_yaml(&wild, 0.0)).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &["detect", "--bits", "8", "--arena", "wild.yaml", "view.png"],
    ));
    assert!(
        line.contains("wild.yaml: camera: camera_matrix: fx = 1e308"),
        "{line}"
    );
    let arena = whycode::arena::Arena::parse(&arena_yaml(&wild, 0.0))
        .unwrap_err()
        .to_string();
    assert!(arena.contains("fx = 1e308"), "{arena}");
    // Markers above the camera can never be placed: refused, in the file
    // and on the command line.
    std::fs::write(dir.path().join("high.yaml"), arena_yaml(SANE_CAMERA, 3.0)).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &["detect", "--bits", "8", "--arena", "high.yaml", "view.png"],
    ));
    assert!(
        line.contains(
            "high.yaml: marker_height: 3 m is at or above the camera, which is 2.500 m above"
        ),
        "{line}"
    );
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "detect",
            "--bits",
            "8",
            "--arena",
            "sane.yaml",
            "--marker-height",
            "2.6m",
            "view.png",
        ],
    ));
    assert!(
        line.contains("--marker-height: 2.6 m is at or above the camera"),
        "{line}"
    );
}

#[test]
fn a_camera_less_arena_refuses_frames_of_another_shape() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let yaml = "format: whycode-arena\nversion: 1\nids: [1, 2, 3, 4]\nsize: [2.0, 1.5]\n\
                marker_height: 0.0\ncorner_error: 0.0\nimage_to_floor:\n  width: 640\n  \
                height: 480\n  floor_to_image: [[300, 0, 20], [0, -300, 460], [0, 0, 1]]\n";
    std::fs::write(dir.path().join("plane.yaml"), yaml).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &["detect", "--bits", "8", "--arena", "plane.yaml", "view.png"],
    ));
    assert!(
        line.contains(
            "view.png: the arena was measured without a camera on 640x480 frames and cannot map"
        ),
        "{line}"
    );
}

#[test]
fn arena_corners_in_a_line_are_refused_as_such() {
    use whycode::simulate::{self, LooseMarker, Placement, Scene, SceneObject};
    let dir = tempfile::tempdir().unwrap();
    let camera = whycode::Camera::ideal(1280, 720, 60.0);
    let family = whycode::Family::generate(8, 2).unwrap();
    let mut scene = Scene::new(camera);
    for (k, id) in [1u32, 2, 3, 4].into_iter().enumerate() {
        let marker = whycode::Marker::whycode(8, family.code(id).unwrap(), 50.0);
        let u = 200.0 + 280.0 * k as f64;
        let placement = Placement::at_pixel(&camera, &marker, (u, 360.0), 90.0, 0.0, 0.0, 0.0);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    }
    simulate::render(&scene)
        .0
        .save(dir.path().join("row.png"))
        .unwrap();
    std::fs::write(dir.path().join("cam.yaml"), camera.to_ros_yaml("c")).unwrap();
    // Without a camera the map would put every marker on one point; with
    // one the fit failed as "clockwise".
    for extra in [&[][..], &["--camera", "cam.yaml"][..]] {
        let mut args = vec![
            "arena", "--bits", "8", "--size", "2m,1.5m", "--ids", "1,2,3,4",
        ];
        args.extend_from_slice(extra);
        args.extend(["row.png", "-o", "a.yaml"]);
        let line = one_line_error(&whycode_in(dir.path(), &args));
        assert!(line.contains("lie on one line in the image"), "{line}");
        assert!(!dir.path().join("a.yaml").exists());
    }
}

#[test]
fn board_names_must_be_frame_names_of_their_own() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    std::fs::write(
        dir.path().join("cam.yaml"),
        whycode::Camera::ideal(300, 300, 60.0).to_ros_yaml("c"),
    )
    .unwrap();
    let bundle = |name: &str| {
        format!("bundles:\n  - name: {name}\n    layout:\n      - {{id: 4, diameter: 0.02, x: 0, y: 0, z: 0}}\n")
    };
    for (name, problem) in [
        ("''", "cannot be empty"),
        ("whycode_2", "is the /tf frame of a marker"),
        ("arena", "is the /tf frame of the arena"),
        ("a/b", "holds '/'"),
        ("\"a\\nb\"", "holds '\\n'"),
    ] {
        std::fs::write(dir.path().join("b.yaml"), bundle(name)).unwrap();
        let line = one_line_error(&whycode_in(
            dir.path(),
            &[
                "detect", "--bits", "8", "--camera", "cam.yaml", "--board", "b.yaml", "view.png",
            ],
        ));
        assert!(
            line.contains("b.yaml") && line.contains(problem),
            "{name}: {line}"
        );
    }
    std::fs::write(dir.path().join("b.yaml"), bundle("rig")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "detect", "--bits", "8", "--camera", "cam.yaml", "--board", "b.yaml", "--board",
            "./b.yaml", "view.png",
        ],
    ));
    assert!(line.contains("two boards are named \"rig\""), "{line}");
}

#[test]
fn a_board_sheet_of_another_family_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    std::fs::write(
        dir.path().join("cam.yaml"),
        whycode::Camera::ideal(300, 300, 60.0).to_ros_yaml("c"),
    )
    .unwrap();
    ok(&whycode_in(
        dir.path(),
        &[
            "sheet",
            "--bits",
            "10",
            "--ids",
            "1-4",
            "--diameter",
            "30mm",
            "--no-check",
            "-o",
            "ten.pdf",
        ],
    ));
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "detect", "--bits", "8", "--camera", "cam.yaml", "--board", "ten.json", "view.png",
        ],
    ));
    assert!(
        line.contains("--board: ten: ID 1 is printed as the 10-bit code 1, which the family detected (8 bits, distance 2) has 8 bits")
            && line.contains("detect with the family the sheet was printed in"),
        "{line}"
    );
    // In its own family the sheet is a board.
    ok(&whycode_in(
        dir.path(),
        &[
            "detect", "--bits", "10", "--camera", "cam.yaml", "--board", "ten.json", "view.png",
        ],
    ));
}

#[test]
fn calibrate_counts_a_photo_once_and_names_photos_of_another_sheet() {
    let dir = tempfile::tempdir().unwrap();
    sheet(dir.path(), "target.pdf");
    tool_marker_png(dir.path(), "view.png");
    std::fs::copy(dir.path().join("view.png"), dir.path().join("copy.png")).unwrap();
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "calibrate",
            "--manifest",
            "target.json",
            "view.png",
            "copy.png",
            "-o",
            "c.yaml",
        ],
    ));
    assert!(
        line.contains("copy.png is the same photo as view.png: each view counts once"),
        "{line}"
    );
    // A photo of a marker the sheet does not have is named, with what it shows.
    ok(&whycode_in(
        dir.path(),
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "9",
            "--diameter",
            "20mm",
            "--dpi",
            "150",
            "-o",
            "other.png",
        ],
    ));
    let line = one_line_error(&whycode_in(
        dir.path(),
        &[
            "calibrate",
            "--manifest",
            "target.json",
            "other.png",
            "-o",
            "c.yaml",
        ],
    ));
    assert!(
        line.contains("only 0 usable views (3 needed): other.png (none of this sheet's markers: 1 of other IDs"),
        "{line}"
    );
}

#[test]
fn clearer_errors_for_recordings_and_annotations() {
    let dir = tempfile::tempdir().unwrap();
    tool_marker_png(dir.path(), "view.png");
    let line = one_line_error(&whycode_in(
        dir.path(),
        &["detect", "--annotate", "x.mp4", "view.png"],
    ));
    assert!(
        line.contains("--annotate x.mp4: an annotated video is made from a bag or video"),
        "{line}"
    );
    assert!(
        !dir.path().join("x.mp4").exists(),
        "a folder named x.mp4 was made"
    );
    // Sound only.
    let made = Command::new("ffmpeg")
        .current_dir(dir.path())
        .args([
            "-hide_banner",
            "-loglevel",
            "error",
            "-f",
            "lavfi",
            "-i",
            "sine=d=1",
            "sound.mp4",
        ])
        .output()
        .expect("ffmpeg runs");
    assert!(made.status.success(), "{}", stderr(&made));
    let line = one_line_error(&whycode_in(dir.path(), &["detect", "sound.mp4"]));
    assert_eq!(
        line,
        "whycode: error: sound.mp4: holds no video stream (sound only?)"
    );
    // An encoding name holding a NUL and a line break is shown escaped.
    let message = Image {
        header: header(0),
        height: 2,
        width: 2,
        encoding: "mono8\0\nx".into(),
        is_bigendian: 0,
        step: 2,
        data: vec![0; 4],
    };
    write_bag(
        &dir.path().join("odd.mcap"),
        &[(
            "/cam/image_raw",
            Image::schema_name(),
            cdr::encode(&message),
        )],
    );
    let line = one_line_error(&whycode_in(dir.path(), &["detect", "odd.mcap"]));
    assert!(
        line.contains("encoding 'mono8\\0\\nx' is not read"),
        "{line}"
    );
}
