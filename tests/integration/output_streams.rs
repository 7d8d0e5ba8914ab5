//! Standard output and error that fail under the command: a reader that
//! went away (`| head`), a full disk behind a redirection (`>/dev/full`).
//! One rule for every subcommand: a closed pipe ends the run quietly with
//! success, another write failure is one line and exit 1, and nothing
//! panics (exit 101 with a backtrace).

use std::fs::File;
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn command(dir: &Path, args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_whycode"));
    command.args(args).current_dir(dir);
    command
}

/// A pipe whose reader is already gone: every write to it fails with EPIPE,
/// whatever the timing. (`std::io::pipe` is newer than the library's
/// minimum Rust; only this test needs it.)
#[allow(clippy::incompatible_msrv)]
fn closed_pipe() -> std::io::PipeWriter {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    writer
}

fn dev_full() -> File {
    File::options()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A sheet, a photo of its first page and the commands that print to
/// standard output about them.
fn printing_commands(dir: &Path) -> Vec<Vec<&'static str>> {
    for args in [
        &["sheet", "--ids", "1-4", "-o", "s.pdf"][..],
        &["simulate", "--manifest", "s.json", "-o", "v.png"],
    ] {
        let out = command(dir, args).output().unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
    vec![
        vec!["ids", "--bits", "12"],
        vec!["ids", "--counts"],
        vec!["sheet", "--list-templates"],
        vec!["validate", "--manifest", "s.json", "v.png"],
        vec![
            "validate",
            "--manifest",
            "s.json",
            "--format",
            "json",
            "v.png",
        ],
        vec!["detect", "--format", "json", "v.png"],
        vec!["detect", "v.png"],
        vec![
            "simulate", "--ids", "1-2", "--size", "320x240", "-o", "w.png",
        ],
    ]
}

#[test]
fn a_reader_that_went_away_ends_every_command_quietly() {
    let dir = tempfile::tempdir().unwrap();
    for args in printing_commands(dir.path()) {
        let out: Output = command(dir.path(), &args)
            .stdout(closed_pipe())
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(0),
            "whycode {}: {}",
            args.join(" "),
            text(&out.stderr)
        );
        assert!(
            !text(&out.stderr).contains("panicked") && !text(&out.stderr).contains("error"),
            "whycode {}: {}",
            args.join(" "),
            text(&out.stderr)
        );
    }
}

#[test]
fn a_full_standard_output_is_one_line_and_a_failure() {
    let dir = tempfile::tempdir().unwrap();
    for args in printing_commands(dir.path()) {
        let out = command(dir.path(), &args)
            .stdout(dev_full())
            .output()
            .unwrap();
        let stderr = text(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(1),
            "whycode {}: {stderr}",
            args.join(" ")
        );
        let last = stderr.lines().last().unwrap_or_default();
        assert!(
            last.starts_with("whycode: error: cannot write to standard output: "),
            "whycode {}: {stderr}",
            args.join(" ")
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn a_full_standard_error_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], i32)] = &[
        (&["sheet", "--ids", "1-4", "-o", "x.pdf"], 0),
        (&["detect", "missing.png"], 1),
        (
            &[
                "simulate", "--ids", "1-2", "--size", "320x240", "-o", "y.png",
            ],
            0,
        ),
        (
            &[
                "marker",
                "--id",
                "3",
                "--diameter",
                "30mm",
                "--no-check",
                "-o",
                "m.svg",
            ],
            0,
        ),
        (&["ids", "--bits", "99"], 1),
        (&["detect", "--no-such-flag"], 1),
    ];
    for (args, code) in cases {
        let out = command(dir.path(), args)
            .stdout(Stdio::null())
            .stderr(dev_full())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(*code), "whycode {}", args.join(" "));
    }
}
