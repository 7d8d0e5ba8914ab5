//! A folder of frames is read as one sequence: every file named like a
//! frame counts, and one that cannot be read is named while the rest are
//! processed.

use crate::support::{stderr, stdout, whycode_in};

#[test]
fn a_folder_or_broken_link_among_the_frames_is_reported_not_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("frames")).unwrap();
    for k in 1..=3 {
        let out = whycode_in(
            d,
            &[
                "simulate",
                "--ids",
                "1-2",
                "--size",
                "320x240",
                "--seed",
                &k.to_string(),
                "-o",
                &format!("frames/f{k}.png"),
                "--truth",
                &format!("t{k}.json"),
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
    }
    std::fs::create_dir(d.join("frames/f100.png")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("gone.png", d.join("frames/f50.png")).unwrap();
    let out = whycode_in(d, &["detect", "--format", "json", "frames"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("f100.png"), "{err}");
    #[cfg(unix)]
    assert!(err.contains("f50.png"), "{err}");
    // The readable frames are all there.
    assert_eq!(stdout(&out).lines().count(), 3, "{}", stdout(&out));
}

/// Legacy circles all read as ID 0: in a sequence each keeps its own track
/// number, which is what tells them apart; single images carry none.
#[test]
fn markers_of_a_sequence_keep_their_track_numbers() {
    use whycode::camera::Camera;
    use whycode::geometry::Marker;
    use whycode::simulate::{render, LooseMarker, Placement, Scene, SceneObject};
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let camera = Camera::ideal(480, 320, 60.0);
    let marker = Marker::whycon(40.0);
    for frame in 0..4 {
        let mut scene = Scene::new(camera);
        for (k, (u, v)) in [(100.0, 100.0), (240.0, 160.0), (380.0, 220.0)]
            .into_iter()
            .enumerate()
        {
            let step = 3.0 * frame as f64;
            let at =
                Placement::at_pixel(&camera, &marker, (u + step, v - step), 50.0, 0.2, 0.0, 0.0);
            scene
                .objects
                .push(SceneObject::Marker(LooseMarker::new(marker, k as u32, at)));
        }
        let (image, _) = render(&scene);
        image.save(frames.join(format!("f{frame}.png"))).unwrap();
    }
    let out = whycode_in(
        dir.path(),
        &["detect", "--legacy", "--format", "json", "frames"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let mut first: Vec<(f64, u64)> = Vec::new();
    for (n, line) in stdout(&out).lines().enumerate() {
        let frame: serde_json::Value = serde_json::from_str(line).unwrap();
        let mut tracks: Vec<(f64, u64)> = frame["markers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| {
                (
                    m["u"].as_f64().unwrap(),
                    m["track"].as_u64().expect("a track number"),
                )
            })
            .collect();
        tracks.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(tracks.len(), 3, "frame {n}: {line}");
        let numbers: Vec<u64> = tracks.iter().map(|t| t.1).collect();
        if n == 0 {
            let mut distinct = numbers.clone();
            distinct.dedup();
            assert_eq!(distinct.len(), 3, "{numbers:?}");
            first = tracks;
        } else {
            assert_eq!(
                numbers,
                first.iter().map(|t| t.1).collect::<Vec<_>>(),
                "frame {n}"
            );
        }
    }
    let single = whycode_in(
        dir.path(),
        &["detect", "--legacy", "--format", "json", "frames/f0.png"],
    );
    assert!(
        !stdout(&single).contains("\"track\""),
        "{}",
        stdout(&single)
    );
}
