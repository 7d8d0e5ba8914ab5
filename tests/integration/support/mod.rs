//! Shared by the integration tests: running the real binary, one marker's
//! photo, the scenes the tests draw (`ring_view` for ring reading, `sheets`
//! for validation), plus the stored reference files of `tests/data/`. What
//! the examples and benches share too (scenes, desk clutter, the fuzz
//! harness) is in the `whycode-testkit` crate.
#![allow(dead_code)]

pub mod recordings;
pub mod reference;
pub mod ring_view;
pub mod sheets;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use whycode::camera::Camera;
use whycode::geometry::Marker;
/// The library's seeded generator, so test scenes draw like the simulator.
pub use whycode::math::Pcg32;
use whycode::simulate::{self, LooseMarker, Placement, Scene, SceneObject, TrueMarker};

/// Says that `what` is missing and the test skips, or fails the test where
/// a missing one means a broken run: `.ci/run` installs the tools and sets
/// `WHYCODE_REQUIRE_TOOLS=1`; a CI system (`CI` set) or
/// `WHYCODE_REQUIRE_FIXTURES=1` requires the fixtures too. So a check that
/// did not run never reads as passed there, while a user's machine without
/// the original project's files still runs the rest.
fn skip_or_fail(what: &str, required_by: &str) {
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| v == "1");
    let ci = std::env::var_os("CI").is_some_and(|v| !v.is_empty() && v != "false");
    assert!(
        !(set(required_by) || ci),
        "{what} is missing, and this run requires it"
    );
    eprintln!("skipping: {what} is missing");
}

/// Whether the command-line `tool` (from the Debian `package`) runs; when it
/// does not, the test skips, or fails under `.ci/run` and CI.
pub fn have_tool(tool: &str, package: &str) -> bool {
    let runs = Command::new(tool).arg("--version").output().is_ok();
    if !runs {
        skip_or_fail(
            &format!("{tool} (apt-get install {package})"),
            "WHYCODE_REQUIRE_TOOLS",
        );
    }
    runs
}

/// The original project's file `name` in `../shared/compat/`, or `None`
/// when the folder is absent, as it is on a user's machine (the test skips;
/// under CI it fails).
pub fn compat_fixture(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/compat")
        .join(name);
    if path.exists() {
        return Some(path);
    }
    skip_or_fail(
        &format!("the fixture {}", path.display()),
        "WHYCODE_REQUIRE_FIXTURES",
    );
    None
}

/// Runs the `whycode` binary built for this test run.
pub fn whycode(args: &[&str]) -> Output {
    whycode_command(args)
        .output()
        .expect("the whycode binary runs")
}

/// Runs whycode with `dir` as its working folder, where outputs named
/// without a folder (a sheet's default swarm.pdf) land.
pub fn whycode_in(dir: &Path, args: &[&str]) -> Output {
    whycode_command(args)
        .current_dir(dir)
        .output()
        .expect("the whycode binary runs")
}

/// [`whycode_in`] with one environment variable set.
pub fn whycode_env(dir: &Path, args: &[&str], (name, value): (&str, &str)) -> Output {
    whycode_command(args)
        .current_dir(dir)
        .env(name, value)
        .output()
        .expect("the whycode binary runs")
}

fn whycode_command(args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_whycode"));
    command.args(args);
    command
}

/// Runs a command that must succeed; returns its standard output.
pub fn run_ok(args: &[&str]) -> String {
    ok_stdout(args, whycode(args))
}

/// [`run_ok`] with `dir` as the working folder.
pub fn run_ok_in(dir: &Path, args: &[&str]) -> String {
    ok_stdout(args, whycode_in(dir, args))
}

fn ok_stdout(args: &[&str], out: Output) -> String {
    assert!(
        out.status.success(),
        "whycode {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("stdout is UTF-8")
}

/// The 8-bit ID 4, 20 mm at 150 dpi, drawn by the tool itself as `name` in
/// `dir` (a photo for the commands that read one).
pub fn tool_marker_png(dir: &Path, name: &str) {
    run_ok_in(
        dir,
        &[
            "marker",
            "--bits",
            "8",
            "--id",
            "4",
            "--diameter",
            "20mm",
            "--dpi",
            "150",
            "-o",
            name,
        ],
    );
}

/// Runs a command that must fail with exactly one line on stderr and nothing
/// on stdout; returns that line.
pub fn run_err(args: &[&str]) -> String {
    let out = whycode(args);
    assert!(!out.status.success(), "whycode {args:?} succeeded");
    assert!(
        out.stdout.is_empty(),
        "whycode {args:?} printed output: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    let stderr = String::from_utf8(out.stderr).expect("stderr is UTF-8");
    assert_eq!(
        stderr.lines().count(),
        1,
        "whycode {args:?} should fail with one line, got: {stderr}"
    );
    stderr.trim_end().to_string()
}

pub fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).expect("stdout is UTF-8")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8(out.stderr.clone()).expect("stderr is UTF-8")
}

/// A face-on photo of one marker, `diameter_px` across, turned by `roll`
/// about the line of sight, its centre a fraction of a pixel off the image
/// centre, with a light focus blur; and the simulator's truth about it.
pub fn marker_photo(
    marker: Marker,
    id: u32,
    diameter_px: f64,
    roll: f64,
) -> (image::GrayImage, TrueMarker) {
    let side = (diameter_px * 1.8).ceil() as u32 + 12;
    let camera = Camera::ideal(side, side, 60.0);
    let centre = (camera.cx + 0.37, camera.cy + 0.21);
    let placement = Placement::at_pixel(&camera, &marker, centre, diameter_px, 0.0, 0.0, roll);
    let mut scene = Scene::new(camera);
    scene
        .objects
        .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    scene.focus_blur_px = 0.6;
    let (image, truth) = simulate::render(&scene);
    (image, truth.markers[0].clone())
}
