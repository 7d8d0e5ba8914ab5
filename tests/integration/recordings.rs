//! Recorded runs: a simulated sequence written to MCAP by an independent
//! writer (PyPI's mcap-ros2-support) and to MJPG and H.264 videos by
//! ffmpeg, read back by `whycode detect` as one tracked stream: every frame,
//! the IDs in each, the stamps; the detections bag read back by the same
//! independent reader; and bad recordings refused in one line.

use crate::support::recordings::{
    assert_ids, camera, ids, lines, read_bag, sequence, write_bag, write_video, FRAMES, SIZE,
    VISIT, VISITOR,
};
use crate::support::{stderr, stdout, whycode_in};
use serde_json::{json, Value};
use std::path::Path;

/// Stamps far from zero and not on round numbers, as a robot's clock gives.
fn stamp(k: usize) -> i64 {
    1_700_000_000_123_456_789 + k as i64 * 33_366_667
}

fn image_message(dir: &Path, topic: &str, k: usize, encoding: &str) -> Value {
    let (image, _) = &sequence()[k];
    let (w, h) = SIZE;
    let (data, step): (Vec<u8>, u32) = match encoding {
        "mono8" => (image.as_raw().clone(), w),
        // Grey in colour: the conversion gives the grey back.
        "bgr8" => (
            image.as_raw().iter().flat_map(|&g| [g, g, g]).collect(),
            3 * w,
        ),
        // An encoding nobody reads: its bytes do not matter.
        _ => (vec![0; (w * h) as usize], w),
    };
    let file = dir.join(format!("{}-{k}.bin", topic.replace('/', "_")));
    std::fs::write(&file, data).unwrap();
    json!({
        "topic": topic, "type": "sensor_msgs/msg/Image", "log_time": stamp(k) + 1000,
        "stamp_ns": stamp(k), "frame_id": "cam_optical", "height": h, "width": w,
        "encoding": encoding, "is_bigendian": 0, "step": step, "data_file": file,
    })
}

fn compressed_message(dir: &Path, topic: &str, k: usize, bytes: Vec<u8>) -> Value {
    let file = dir.join(format!("{}-{k}.jpg", topic.replace('/', "_")));
    std::fs::write(&file, bytes).unwrap();
    json!({
        "topic": topic, "type": "sensor_msgs/msg/CompressedImage", "log_time": stamp(k) + 2000,
        "stamp_ns": stamp(k), "format": "jpeg", "data_file": file,
    })
}

fn camera_info(k: usize) -> Value {
    let c = camera();
    json!({
        "topic": "/cam/camera_info", "type": "sensor_msgs/msg/CameraInfo",
        "log_time": stamp(k), "stamp_ns": stamp(k), "height": SIZE.1, "width": SIZE.0,
        "k": [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
        "p": [c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0],
    })
}

/// The sequence on /cam/image_raw (mono8 and bgr8 frames in turn), its
/// camera_info, the same frames as JPEG on /cam/image_raw/compressed with
/// one that does not decode, and a string topic.
fn write_swarm_bag(dir: &Path) -> std::path::PathBuf {
    let mut messages = Vec::new();
    for k in 0..FRAMES {
        messages.push(camera_info(k));
        let encoding = if k % 2 == 0 { "mono8" } else { "bgr8" };
        messages.push(image_message(dir, "/cam/image_raw", k, encoding));
        let jpeg =
            whycode::image_io::encode_image(Path::new("f.jpg"), &sequence()[k].0, 95).unwrap();
        messages.push(compressed_message(
            dir,
            "/cam/image_raw/compressed",
            k,
            jpeg,
        ));
        if k == 5 {
            messages.push(compressed_message(
                dir,
                "/cam/image_raw/compressed",
                99,
                b"not a jpeg".to_vec(),
            ));
        }
    }
    messages.push(json!({"topic": "/chatter", "type": "std_msgs/msg/String", "log_time": stamp(0), "data": "hi"}));
    let path = dir.join("swarm.mcap");
    write_bag(&path, &messages);
    path
}

#[test]
fn a_bag_is_read_as_one_stream_and_its_detections_written_as_the_node_would() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_swarm_bag(d);

    // Two image topics: the error names them.
    let out = whycode_in(d, &["detect", "--format", "json", "swarm.mcap"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("swarm.mcap") && err.contains("/cam/image_raw/compressed"),
        "{err}"
    );

    let out = whycode_in(
        d,
        &[
            "detect",
            "--format",
            "json",
            "--topic",
            "/cam/image_raw",
            "--diameter",
            "40mm",
            "--output",
            "found.mcap",
            "swarm.mcap",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let frames = lines(&stdout(&out));
    assert_eq!(frames.len(), FRAMES);
    for (k, line) in frames.iter().enumerate() {
        assert_eq!(line["frame"], k as u64);
        assert_eq!(line["stamp_ns"], stamp(k));
        assert_eq!(line["topic"], "/cam/image_raw");
        assert_ids(k, &ids(line), "/cam/image_raw");
        // camera_info gave the camera: every marker has a pose.
        for marker in line["markers"].as_array().unwrap() {
            assert!(marker["position"][2].as_f64().unwrap() > 0.0, "{marker}");
        }
    }
    let summary = stderr(&out);
    assert!(
        summary.contains(&format!("read {FRAMES} frames")),
        "{summary}"
    );
    let went = format!("IDs that came and went: {VISITOR} (frames ");
    assert!(summary.contains(&went), "{summary}");
    assert!(
        summary.contains(&format!(" to {}, in ", VISIT.end())),
        "{summary}"
    );

    // The detections bag, read by the independent reader: a marker array
    // per frame and the transforms, stamped like the images.
    let messages = read_bag(&d.join("found.mcap"));
    let arrays: Vec<&Value> = messages
        .iter()
        .filter(|m| m["topic"] == "/whycode/markers")
        .collect();
    let tf: Vec<&Value> = messages.iter().filter(|m| m["topic"] == "/tf").collect();
    assert_eq!(arrays.len(), FRAMES);
    assert_eq!(tf.len(), FRAMES);
    for (k, array) in arrays.iter().enumerate() {
        assert_eq!(array["schema"], "whycode_msgs/msg/MarkerArray");
        assert_eq!(array["log_time"], stamp(k));
        let header = &array["message"]["header"];
        assert_eq!(
            header["stamp"]["sec"].as_i64().unwrap() * 1_000_000_000
                + header["stamp"]["nanosec"].as_i64().unwrap(),
            stamp(k)
        );
        assert_eq!(header["frame_id"], "cam_optical");
        // The same markers as the JSON line of the frame.
        let mut found: Vec<u32> = array["message"]["markers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["id"].as_u64().unwrap() as u32)
            .collect();
        found.sort_unstable();
        assert_eq!(found, ids(&frames[k]));
        let mut children: Vec<String> = tf[k]["message"]["transforms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t["child_frame_id"].as_str().unwrap().to_string())
            .collect();
        children.sort();
        let expected: Vec<String> = found.iter().map(|id| format!("whycode_{id}")).collect();
        assert_eq!(children, expected);
        assert_eq!(tf[k]["schema"], "tf2_msgs/msg/TFMessage");
    }

    // A board needs no --camera or --diameter from a bag: its camera_info
    // gives the camera, the board's markers their diameter. A one-marker
    // bundle's pose is that marker's (smoothed over the frames).
    let id = ids(&frames[0])
        .into_iter()
        .find(|&id| id != VISITOR)
        .unwrap();
    std::fs::write(
        d.join("one.yaml"),
        format!(
            "bundles:\n  - name: one\n    layout:\n      - {{id: {id}, diameter: 0.04, x: 0, y: 0, z: 0, qw: 1, qx: 0, qy: 0, qz: 0}}\n"
        ),
    )
    .unwrap();
    let out = whycode_in(
        d,
        &[
            "detect",
            "--format",
            "json",
            "--topic",
            "/cam/image_raw",
            "--board",
            "one.yaml",
            "swarm.mcap",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for (line, posed) in lines(&stdout(&out)).iter().zip(&frames) {
        let board = &line["boards"][0];
        assert_eq!(board["name"], "one", "{line}");
        assert_eq!(board["used"], json!([id]), "{line}");
        let marker = posed["markers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["id"] == id)
            .unwrap();
        let distance = |v: &Value| {
            (0..3)
                .map(|i| v[i].as_f64().unwrap().powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let (b, m) = (distance(&board["position"]), distance(&marker["position"]));
        assert!((b - m).abs() < 0.02 * m, "board at {b} m, marker at {m} m");
    }
    // Without a bag's camera_info, a board still needs --camera.
    std::fs::write(d.join("still.png"), b"").unwrap();
    let out = whycode_in(d, &["detect", "--board", "one.yaml", "still.png"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("--board") && err.contains("camera"), "{err}");

    // The compressed topic: the frame that does not decode is skipped and
    // counted, the stream goes on.
    let out = whycode_in(
        d,
        &[
            "detect",
            "--format",
            "json",
            "--topic",
            "/cam/image_raw/compressed",
            "swarm.mcap",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let frames = lines(&stdout(&out));
    assert_eq!(frames.len(), FRAMES);
    for line in &frames {
        let k = line["frame"].as_u64().unwrap() as usize;
        let k = if k > 6 { k - 1 } else { k };
        assert_ids(k, &ids(line), "/cam/image_raw/compressed");
    }
    assert!(
        stderr(&out).contains("skipped 1 that did not decode"),
        "{}",
        stderr(&out)
    );

    // Thinned and cut: every 3rd frame from the 2nd to the 9th.
    let out = whycode_in(
        d,
        &[
            "detect",
            "--format",
            "json",
            "--topic",
            "/cam/image_raw",
            "--every",
            "3",
            "--start",
            "0.05",
            "--end",
            "0.28",
            "swarm.mcap",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let stamps: Vec<i64> = lines(&stdout(&out))
        .iter()
        .map(|l| l["stamp_ns"].as_i64().unwrap())
        .collect();
    assert_eq!(stamps, [stamp(2), stamp(5), stamp(8)]);
}

#[test]
fn bad_bags_are_refused_in_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let full = write_swarm_bag(d);
    let bytes = std::fs::read(&full).unwrap();
    std::fs::write(d.join("cut.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let mut flipped = bytes.clone();
    for b in &mut flipped[bytes.len() / 3..bytes.len() / 3 + 64] {
        *b ^= 0x5a;
    }
    std::fs::write(d.join("flipped.mcap"), flipped).unwrap();
    write_bag(&d.join("infos.mcap"), &[camera_info(0), camera_info(1)]);
    write_bag(
        &d.join("bayer.mcap"),
        &[image_message(d, "/cam/image_raw", 0, "bayer_rggb8")],
    );
    for (bag, words) in [
        ("cut.mcap", "truncated or corrupt"),
        ("flipped.mcap", ""),
        ("infos.mcap", "no image topic"),
        ("bayer.mcap", "bayer_rggb8"),
    ] {
        let out = whycode_in(
            d,
            &[
                "detect",
                "--format",
                "json",
                "--topic",
                "/cam/image_raw",
                bag,
            ],
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{bag}: {err}");
        assert_eq!(err.lines().count(), 1, "{bag}: {err}");
        assert!(err.contains(bag), "{bag}: {err}");
        assert!(err.contains(words), "{bag}: {err}");
        assert!(!d.join("found.mcap").exists());
    }
}

#[test]
fn videos_are_read_with_their_presentation_times() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_video(d, "run.avi", 10, &["-c:v", "mjpeg", "-q:v", "2"]);
    write_video(
        d,
        "run.mp4",
        10,
        &["-c:v", "libx264", "-crf", "12", "-pix_fmt", "yuv420p"],
    );
    for video in ["run.avi", "run.mp4"] {
        let out = whycode_in(
            d,
            &[
                "detect",
                "--format",
                "json",
                "--annotate",
                "seen.mp4",
                video,
            ],
        );
        assert!(out.status.success(), "{video}: {}", stderr(&out));
        let frames = lines(&stdout(&out));
        assert_eq!(frames.len(), FRAMES, "{video}");
        for (k, line) in frames.iter().enumerate() {
            assert_eq!(line["frame"], k as u64);
            assert_eq!(line["stamp_ns"], k as i64 * 100_000_000, "{video}");
            assert!(line.get("topic").is_none());
            assert_ids(k, &ids(line), video);
        }
        // The annotated video has every frame.
        let probe = std::process::Command::new("ffprobe")
            .args([
                "-v",
                "error",
                "-count_frames",
                "-select_streams",
                "v:0",
                "-show_entries",
                "stream=nb_read_frames,width,height",
                "-of",
                "csv=p=0",
            ])
            .arg(d.join("seen.mp4"))
            .output()
            .unwrap();
        assert_eq!(
            String::from_utf8_lossy(&probe.stdout).trim(),
            format!("{},{},{FRAMES}", SIZE.0, SIZE.1)
        );
    }
    let out = whycode_in(
        d,
        &[
            "detect", "--format", "json", "--every", "3", "--start", "0.3", "--end", "0.85",
            "run.mp4",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let got: Vec<(u64, i64)> = lines(&stdout(&out))
        .iter()
        .map(|l| {
            (
                l["frame"].as_u64().unwrap(),
                l["stamp_ns"].as_i64().unwrap(),
            )
        })
        .collect();
    assert_eq!(got, [(0, 300_000_000), (3, 600_000_000)]);
}

#[test]
fn bad_videos_and_a_missing_ffmpeg_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mp4 = write_video(
        d,
        "run.mp4",
        10,
        &["-c:v", "libx264", "-pix_fmt", "yuv420p"],
    );
    let bytes = std::fs::read(&mp4).unwrap();
    std::fs::write(d.join("cut.mp4"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(d.join("noise.mkv"), vec![7u8; 5000]).unwrap();
    for video in ["cut.mp4", "noise.mkv"] {
        let out = whycode_in(
            d,
            &[
                "detect",
                "--format",
                "json",
                "--annotate",
                "seen.mp4",
                video,
            ],
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{video}: {err}");
        assert_eq!(err.lines().count(), 1, "{video}: {err}");
        assert!(
            err.starts_with(&format!("whycode: error: {video}: ")),
            "{video}: {err}"
        );
        assert!(!d.join("seen.mp4").exists(), "no half-written video");
    }
    let out = crate::support::whycode_env(
        d,
        &["detect", "run.mp4"],
        ("WHYCODE_FFMPEG", "/nonexistent/ffmpeg"),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("run.mp4") && err.contains("apt-get install ffmpeg"),
        "{err}"
    );
}

#[test]
fn a_frame_size_ffmpeg_reports_past_the_cap_is_refused_before_it_is_allocated() {
    // An ffmpeg that reports 100000x100000-pixel frames (10 GB each), as a
    // crafted file's metadata can make the real one do: the reader must
    // refuse the size it is told before allocating a frame of it.
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fake = d.join("ffmpeg");
    std::fs::write(
        &fake,
        "#!/bin/sh\n\
         echo '[Parsed_showinfo_1 @ 0x5] n:   0 pts:      0 pts_time:0 pos: 1 fmt:gray sar:1/1 s:100000x100000 i:P' >&2\n\
         exit 0\n",
    )
    .unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    std::fs::write(d.join("huge.mp4"), b"not really a video").unwrap();
    let out = crate::support::whycode_env(
        d,
        &["detect", "--format", "json", "huge.mp4"],
        ("WHYCODE_FFMPEG", fake.to_str().unwrap()),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("whycode: error: huge.mp4: ")
            && err.contains("ffmpeg reports frames of 100000x100000 pixels"),
        "{err}"
    );
}

#[test]
fn a_start_past_the_end_is_an_error_that_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_video(
        d,
        "run.mp4",
        10,
        &["-c:v", "libx264", "-pix_fmt", "yuv420p"],
    );
    let out = whycode_in(
        d,
        &[
            "detect",
            "--start",
            "1:00",
            "--annotate",
            "seen.mp4",
            "--output",
            "seen.mcap",
            "run.mp4",
        ],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(
        err.trim_end(),
        "whycode: error: run.mp4: no frame at or after 1:00.000"
    );
    assert!(out.stdout.is_empty());
    assert!(!d.join("seen.mp4").exists() && !d.join("seen.mcap").exists());
    // A window that holds frames is read as before.
    let out = whycode_in(
        d,
        &["detect", "--start", "0.1", "--format", "json", "run.mp4"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

/// Every input is a stream to `detect`: images, a folder and bags go in
/// one run, each printed in input order, and every picture lands under a
/// name of its own (two recordings called `run.mcap` do not overwrite each
/// other's frames).
#[test]
fn images_folders_and_bags_are_read_in_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bag = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/swarm.mcap");
    for sub in ["a", "b", "frames"] {
        std::fs::create_dir(d.join(sub)).unwrap();
    }
    std::fs::copy(&bag, d.join("a/run.mcap")).unwrap();
    std::fs::copy(&bag, d.join("b/run.mcap")).unwrap();
    for k in 0..3 {
        sequence()[k]
            .0
            .save(d.join(format!("frames/f{k}.png")))
            .unwrap();
    }
    sequence()[5].0.save(d.join("run.png")).unwrap();
    let out = whycode_in(
        d,
        &[
            "detect",
            "--format",
            "json",
            "--annotate",
            "seen",
            "run.png",
            "a/run.mcap",
            "frames",
            "b/run.mcap",
        ],
    );
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    let images: Vec<String> = lines(&stdout(&out))
        .iter()
        .map(|l| l["image"].as_str().unwrap().to_string())
        .collect();
    let mut expected = vec!["run.png".to_string()];
    expected.extend(std::iter::repeat_n("a/run.mcap".to_string(), 15));
    expected.extend((0..3).map(|k| format!("frames/f{k}.png")));
    expected.extend(std::iter::repeat_n("b/run.mcap".to_string(), 15));
    assert_eq!(images, expected);
    assert_eq!(sequence()[5].1, ids(&lines(&stdout(&out))[0]));
    let mut pictures: Vec<String> = std::fs::read_dir(d.join("seen"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    pictures.sort();
    assert_eq!(pictures.len(), 1 + 15 + 3 + 15, "{pictures:?}");
    for name in [
        "run.annotated.png",
        "run-2.frame_000000.png",
        "run-3.frame_000014.png",
        "f2.annotated.png",
    ] {
        assert!(pictures.contains(&name.to_string()), "{name}: {pictures:?}");
    }
    assert!(err.contains("a/run.mcap: read 15 frames"), "{err}");
    assert!(err.contains("wrote 34 annotated images to seen"), "{err}");
}

/// The temporary files of this crate's writes in `dir`.
fn temporary_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|name| name.starts_with(".whycode-"))
        .collect()
}

/// A run stopped by a signal (as `kill` or a closed terminal sends) while
/// ffmpeg writes its annotated video under a temporary name removes that
/// file, and stops ffmpeg first: ffmpeg opens its output only once its
/// encoder has packets, a few dozen frames in, so left running after the
/// run ended it would create the file again. Stopped from at once to
/// about a second in; the run ends with the signal's status and says
/// nothing of the ffmpeg it stopped (it said "ffmpeg failed" in one run
/// of about twenty).
#[test]
fn a_run_stopped_while_writing_its_video_leaves_no_file_behind() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    sequence()[0].0.save(d.join("still.png")).unwrap();
    let out = Command::new("ffmpeg")
        .current_dir(d)
        .args(["-hide_banner", "-loglevel", "error", "-loop", "1"])
        .args(["-i", "still.png", "-vf", "pad=1280:720:480:240:white"])
        .args(["-frames:v", "1000", "-c:v", "mjpeg", "long.avi"])
        .output()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    assert!(out.status.success(), "{}", stderr(&out));
    for round in 0..8u64 {
        let mut run = Command::new(env!("CARGO_BIN_EXE_whycode"))
            .current_dir(d)
            .args(["detect", "--annotate", "seen.mp4", "long.avi"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while temporary_files(d).is_empty() {
            assert!(
                run.try_wait().unwrap().is_none(),
                "round {round}: the run ended before it staged its video"
            );
            assert!(start.elapsed() < Duration::from_secs(60), "round {round}");
            std::thread::sleep(Duration::from_millis(2));
        }
        std::thread::sleep(Duration::from_millis(120 * round));
        let kill = Command::new("sh")
            .args(["-c", &format!("kill -TERM {}", run.id())])
            .status()
            .unwrap();
        assert!(kill.success());
        let ended = run.wait_with_output().unwrap();
        // Ended by the signal's handler, with its status, and without an
        // error about the ffmpeg its clean-up stopped.
        assert_eq!(ended.status.code(), Some(128 + 15), "round {round}");
        assert_eq!(stderr(&ended), "", "round {round}");
        // An ffmpeg left running would write its file in this time.
        std::thread::sleep(Duration::from_millis(300));
        assert_eq!(temporary_files(d), Vec::<String>::new(), "round {round}");
        assert!(!d.join("seen.mp4").exists(), "round {round}");
    }
}
