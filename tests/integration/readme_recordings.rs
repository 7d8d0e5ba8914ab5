//! The README's "Try it on a recording" commands, run as written on the
//! sample recordings the repository ships (`samples/`, made by
//! `examples/make_samples.rs` from `whycode_testkit::swarm`): each must
//! succeed and do what the README says, on the markers the samples hold.
//! A command that stops working, a README edit that breaks one, or samples
//! that no longer give detections fail here.

use crate::support::{have_tool, stderr, stdout, whycode_in};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use whycode::recording::{ReadOptions, Recording};
use whycode::ros::msg::{MarkerArray, TfMessage};
use whycode_testkit::swarm;

const MARK: &str = "<!-- recording-examples: run by tests/integration/readme_recordings.rs -->";

/// The commands of the README's marked block: the indented lines after
/// the mark, comments cut off, split into arguments (the block holds no
/// quoting, so splitting on spaces is what a shell does with them).
fn readme_commands() -> Vec<Vec<String>> {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let (_, block) = readme
        .split_once(&format!("{MARK}\n"))
        .expect("the README marks its recording examples");
    let commands: Vec<Vec<String>> = block
        .lines()
        .take_while(|line| line.starts_with("    "))
        .map(|line| {
            let command = line.split(" #").next().unwrap();
            assert!(
                !command.contains(['"', '\'', '$', '|', '>', '<', '*', '`']),
                "not plain arguments: {line}"
            );
            command.split_whitespace().map(str::to_string).collect()
        })
        .collect();
    assert!(!commands.is_empty(), "no indented commands after the mark");
    for command in &commands {
        assert_eq!(command[0], "whycode", "{command:?}");
    }
    commands
}

/// The value of `flag` in `args`.
fn option<'a>(args: &'a [String], flag: &str) -> Option<&'a str> {
    let at = args.iter().position(|a| a == flag)?;
    args.get(at + 1).map(String::as_str)
}

/// Checks the IDs of a stream's frames: only the samples' markers, each of
/// them in every frame (they are in view and whole throughout).
fn check_ids(what: &str, frames: &[Vec<u32>]) {
    for (k, ids) in frames.iter().enumerate() {
        let mut ids = ids.clone();
        ids.sort_unstable();
        assert_eq!(ids, swarm::IDS, "{what}: frame {k}");
    }
}

/// A distance from the camera the samples' markers lie at, metres: the
/// camera is 1.2 m above them and looks 30° from straight down.
fn plausible_distance(position: [f64; 3]) -> bool {
    let d = position.iter().map(|c| c * c).sum::<f64>().sqrt();
    (1.0..2.2).contains(&d)
}

#[test]
fn the_readmes_recording_examples_run_on_the_samples() {
    if !have_tool("ffmpeg", "ffmpeg") {
        return;
    }
    let commands = readme_commands();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The commands name samples/... as seen from a clone's root.
    std::os::unix::fs::symlink(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("samples"),
        d.join("samples"),
    )
    .unwrap();
    let mut seen = BTreeMap::new();
    for command in &commands {
        let args: Vec<&str> = command[1..].iter().map(String::as_str).collect();
        let out = whycode_in(d, &args);
        let shown = command.join(" ");
        assert!(out.status.success(), "{shown}: {}", stderr(&out));
        let input = *args.last().unwrap();
        let (frames, bag) = match input {
            "samples/swarm.mcap" => (swarm::frames(swarm::BAG_FPS) as usize, true),
            "samples/swarm.mp4" => (swarm::frames(swarm::VIDEO_FPS) as usize, false),
            other => panic!("{shown}: runs on {other}, not on a sample recording"),
        };
        let posed = option(command, "--diameter").is_some()
            && (bag || option(command, "--camera").is_some());

        // The summary: every frame read, each marker in every one.
        let summary = stderr(&out);
        assert!(
            summary.contains(&format!("read {frames} frames")),
            "{shown}: {summary}"
        );
        let per_id: Vec<String> = swarm::IDS
            .iter()
            .map(|id| format!("{id}: {frames}"))
            .collect();
        assert!(
            summary.contains(&format!("frames per ID: {}", per_id.join(", "))),
            "{shown}: {summary}"
        );
        assert!(!summary.contains("without ID"), "{shown}: {summary}");

        if option(command, "--format") == Some("json") {
            let lines: Vec<Value> = stdout(&out)
                .lines()
                .map(|l| serde_json::from_str(l).expect("a JSON line"))
                .collect();
            assert_eq!(lines.len(), frames, "{shown}");
            let ids: Vec<Vec<u32>> = lines
                .iter()
                .map(|line| {
                    line["markers"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|m| m["id"].as_u64().unwrap() as u32)
                        .collect()
                })
                .collect();
            check_ids(&shown, &ids);
            for line in &lines {
                for marker in line["markers"].as_array().unwrap() {
                    let position = marker["position"].as_array();
                    assert_eq!(position.is_some(), posed, "{shown}: {marker}");
                    if let Some(p) = position {
                        let p = [0, 1, 2].map(|i| p[i].as_f64().unwrap());
                        assert!(plausible_distance(p), "{shown}: {marker}");
                    }
                }
            }
            seen.insert("json", shown.clone());
        }

        if let Some(output) = option(command, "--output") {
            check_detections_bag(&d.join(output), frames, posed, &shown);
            seen.insert("output", shown.clone());
        }

        if let Some(annotated) = option(command, "--annotate") {
            let path = d.join(annotated);
            assert!(
                std::fs::metadata(&path).is_ok_and(|m| m.is_file() && m.len() > 0),
                "{shown}: no video {annotated}"
            );
            let video = Recording::open(&path).unwrap();
            let read: Vec<_> = video
                .frames(&ReadOptions::default())
                .unwrap()
                .map(|f| f.expect("an annotated frame"))
                .collect();
            assert_eq!(read.len(), frames, "{shown}: frames of {annotated}");
            let camera = swarm::camera();
            for frame in &read {
                assert_eq!(frame.image.dimensions(), (camera.width, camera.height));
            }
            seen.insert("annotate", shown.clone());
        }
    }
    // The block shows each kind of run the README promises.
    for kind in ["json", "output", "annotate"] {
        assert!(
            seen.contains_key(kind),
            "no README recording example with {kind}: {commands:?}"
        );
    }
}

/// The detections bag `whycode detect --output` wrote: a marker array per
/// frame with the samples' IDs, and with poses their transforms on /tf.
fn check_detections_bag(path: &Path, frames: usize, posed: bool, shown: &str) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{shown}: {e}"));
    let mut arrays = Vec::new();
    let mut transforms = Vec::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        let schema = message.channel.schema.as_ref().unwrap().name.clone();
        match message.channel.topic.as_str() {
            "/whycode/markers" => {
                assert_eq!(schema, "whycode_msgs/msg/MarkerArray");
                arrays.push(cdr::deserialize::<MarkerArray>(&message.data).unwrap());
            }
            "/tf" => {
                assert_eq!(schema, "tf2_msgs/msg/TFMessage");
                transforms.push(cdr::deserialize::<TfMessage>(&message.data).unwrap());
            }
            other => panic!("{shown}: a message on {other}"),
        }
    }
    assert_eq!(arrays.len(), frames, "{shown}: marker arrays");
    let ids: Vec<Vec<u32>> = arrays
        .iter()
        .map(|a| a.markers.iter().map(|m| m.id).collect())
        .collect();
    check_ids(shown, &ids);
    for array in &arrays {
        assert_eq!(array.header.frame_id, swarm::CAMERA_FRAME, "{shown}");
        for marker in &array.markers {
            assert_eq!(marker.has_pose, posed, "{shown}: {marker:?}");
        }
    }
    if posed {
        assert_eq!(transforms.len(), frames, "{shown}: /tf messages");
        for tf in &transforms {
            let mut children: Vec<&str> = tf
                .transforms
                .iter()
                .map(|t| t.child_frame_id.as_str())
                .collect();
            children.sort_unstable();
            let mut expected: Vec<String> = swarm::IDS
                .iter()
                .map(|id| format!("whycode_{id}"))
                .collect();
            expected.sort_unstable();
            assert_eq!(children, expected, "{shown}");
            for t in &tf.transforms {
                let p = t.transform.translation;
                assert!(plausible_distance([p.x, p.y, p.z]), "{shown}: {t:?}");
            }
        }
    }
}
