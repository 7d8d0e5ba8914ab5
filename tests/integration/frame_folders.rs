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
