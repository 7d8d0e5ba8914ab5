//! Fuzzing on stable Rust: proptest generates mutations of valid seed files
//! (images, family files, manifests, page templates, camera calibrations,
//! arena files, boards and bundles, bags and videos) and random images up
//! to 2 megapixels; each input goes through the
//! library's loaders and, when accepted, through what uses them (detector,
//! validation, sheet layout, projection). A run fails on a panic, on an
//! input that takes too long, and on any JSON output that does not parse
//! back or carries a non-finite number.
//!
//! Bags and videos go through the command line (`whycode detect`, which
//! must end in its output or one error line, never a panic, a signal or a
//! hang). With the `whycode` binary at hand it also runs the command line itself:
//! with its standard output or error closed or full (it must not panic, and
//! exits as it would have, 0 for a reader that went away, 1 for a full
//! disk), and several runs at once writing one output (the files they
//! leave must be one run's set, as the manifest's and the truth's digests
//! tell, with no temporary file left over).
//!
//! Shared by the bounded run in the test suite (`tests/integration/fuzz_bounded.rs`)
//! and the long run (`cargo run --release --example fuzz -- --minutes N`).

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::io::Cursor;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::image_io::load_gray;
use whycode::manifest::{FamilyRef, Manifest};
use whycode::render::sheet::{family_markers, layout, SheetSpec};
use whycode::render::template::Template;
use whycode::simulate::{render, Background, LooseMarker, Placement, Scene, SceneObject};

/// How a run is bounded and judged.
pub struct Settings {
    /// Total time for all targets, shared equally.
    pub budget: Duration,
    /// Longest a detector may take on a 2-megapixel image (scaled by size);
    /// `None` in unoptimised builds, where only hangs count.
    pub detect_limit: Option<Duration>,
    /// Longest any single input may take before it counts as a hang.
    pub hang_limit: Duration,
    pub seed: u64,
    /// The `whycode` binary for the command-line targets; without it they
    /// are reported as skipped.
    pub whycode: Option<std::path::PathBuf>,
}

/// What one target did.
#[derive(Debug, Default, Clone)]
pub struct TargetSummary {
    pub name: &'static str,
    pub inputs: u64,
    /// Inputs the loader accepted and that went on through the pipeline.
    pub accepted: u64,
    /// Slowest detector run, scaled to 2 megapixels, milliseconds.
    pub slowest_ms_per_2mp: f64,
    pub failures: Vec<String>,
    /// Why the target did not run, if it did not.
    pub skipped: Option<&'static str>,
}

type FuzzTarget = fn(&mut Fuzzer, &mut TestRunner) -> Result<bool, String>;

const TARGETS: [(&str, FuzzTarget); 12] = [
    ("image files", Fuzzer::image_file),
    ("random images", Fuzzer::random_image),
    ("family files", Fuzzer::family_file),
    ("manifests", Fuzzer::manifest_file),
    ("templates", Fuzzer::template_file),
    ("camera files", Fuzzer::camera_file),
    ("arena files", Fuzzer::arena_file),
    ("board files", Fuzzer::board_file),
    ("bags", Fuzzer::bag_file),
    ("videos", Fuzzer::video_file),
    ("output streams", Fuzzer::output_streams),
    ("concurrent runs", Fuzzer::concurrent_writers),
];

/// Targets that run the `whycode` binary.
const NEEDS_BINARY: [&str; 4] = ["bags", "videos", "output streams", "concurrent runs"];

/// Runs every target for its share of the budget.
pub fn run(settings: &Settings) -> Vec<TargetSummary> {
    let share = settings.budget / TARGETS.len() as u32;
    TARGETS
        .iter()
        .enumerate()
        .map(|(k, &(name, target))| run_target(settings, name, target, share, k as u64))
        .collect()
}

fn run_target(
    settings: &Settings,
    name: &'static str,
    target: FuzzTarget,
    share: Duration,
    index: u64,
) -> TargetSummary {
    let mut summary = TargetSummary {
        name,
        ..Default::default()
    };
    if settings.whycode.is_none() && NEEDS_BINARY.contains(&name) {
        summary.skipped = Some("no whycode binary (build it with cargo build --release)");
        return summary;
    }
    let seed = settings.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ index;
    let mut seed_bytes = [0u8; 32];
    seed_bytes[..8].copy_from_slice(&seed.to_le_bytes());
    let runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes),
    );
    // The target runs on a worker thread, so a hang is reported instead of
    // stalling the run; it stops at its deadline or its first failure.
    let (tx, rx) = mpsc::channel::<Progress>();
    let deadline = Instant::now() + share;
    let detect_limit = settings.detect_limit;
    let whycode = settings.whycode.clone();
    let current = std::sync::Arc::new(std::sync::Mutex::new(None::<String>));
    let shared = current.clone();
    std::thread::spawn(move || {
        let mut fuzzer = Fuzzer::new(detect_limit, whycode);
        fuzzer.hung_input = Some(shared);
        let mut runner = runner;
        while Instant::now() < deadline {
            fuzzer.last.clear();
            let outcome = catch_unwind(AssertUnwindSafe(|| target(&mut fuzzer, &mut runner)));
            let progress = match outcome {
                Ok(Ok(accepted)) => Progress::Done {
                    accepted,
                    slowest: fuzzer.slowest_ms_per_2mp,
                },
                Ok(Err(problem)) => Progress::Failed(format!("{problem}; input: {}", fuzzer.last)),
                Err(panic) => Progress::Failed(format!(
                    "panic: {}; input: {}",
                    panic_text(&panic),
                    fuzzer.last
                )),
            };
            let failed = matches!(progress, Progress::Failed(_));
            if let Some(hung) = &fuzzer.hung_input {
                *hung.lock().unwrap() = None;
            }
            if tx.send(progress).is_err() || failed {
                return;
            }
        }
    });
    loop {
        match rx.recv_timeout(settings.hang_limit) {
            Ok(Progress::Done { accepted, slowest }) => {
                summary.inputs += 1;
                summary.accepted += u64::from(accepted);
                summary.slowest_ms_per_2mp = slowest;
            }
            Ok(Progress::Failed(problem)) => {
                summary.inputs += 1;
                summary.failures.push(problem);
                break;
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                let input = current.lock().unwrap().clone().unwrap_or_default();
                summary.failures.push(format!(
                    "hang: one input took more than {:?}; input: {input}",
                    settings.hang_limit
                ));
                break;
            }
        }
    }
    summary
}

enum Progress {
    Done { accepted: bool, slowest: f64 },
    Failed(String),
}

fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "(no message)".to_string())
}

/// A change to a seed file.
#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(u32, u8),
    SetByte(u32, u8),
    Truncate(u32),
    Delete(u32, u8),
    Duplicate(u32, u8),
    /// Replaces the n-th number in a text with a troublesome one.
    Number(u32, u8),
}

const TROUBLESOME_NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "1e30",
    ".nan",
    "NaN",
    "inf",
    "-0",
    "4294967296",
    "18446744073709551616",
    "2147483647",
    "0.5",
    "999",
    "-5",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<u32>(), 0u8..8).prop_map(|(at, bit)| Mutation::FlipBit(at, bit)),
        (any::<u32>(), any::<u8>()).prop_map(|(at, b)| Mutation::SetByte(at, b)),
        any::<u32>().prop_map(Mutation::Truncate),
        (any::<u32>(), any::<u8>()).prop_map(|(at, n)| Mutation::Delete(at, n)),
        (any::<u32>(), any::<u8>()).prop_map(|(at, n)| Mutation::Duplicate(at, n)),
        (any::<u32>(), any::<u8>()).prop_map(|(at, n)| Mutation::Number(at, n)),
    ]
}

fn mutations(max: usize) -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 0..=max)
}

fn apply(seed: &[u8], changes: &[Mutation]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for change in changes {
        let n = bytes.len();
        let at = |i: u32| if n == 0 { 0 } else { i as usize % n };
        match *change {
            Mutation::FlipBit(i, bit) if n > 0 => bytes[at(i)] ^= 1 << bit,
            Mutation::SetByte(i, b) if n > 0 => bytes[at(i)] = b,
            Mutation::Truncate(i) => bytes.truncate(if n == 0 { 0 } else { i as usize % (n + 1) }),
            Mutation::Delete(i, k) if n > 0 => {
                let start = at(i);
                let end = (start + usize::from(k) + 1).min(n);
                bytes.drain(start..end);
            }
            Mutation::Duplicate(i, k) if n > 0 => {
                let start = at(i);
                let end = (start + usize::from(k) + 1).min(n);
                let chunk = bytes[start..end].to_vec();
                bytes.splice(end..end, chunk);
            }
            Mutation::Number(i, k) => {
                let numbers = number_spans(&bytes);
                if !numbers.is_empty() {
                    let (s, e) = numbers[i as usize % numbers.len()];
                    let with = TROUBLESOME_NUMBERS[usize::from(k) % TROUBLESOME_NUMBERS.len()];
                    bytes.splice(s..e, with.bytes());
                }
            }
            _ => {}
        }
    }
    bytes
}

/// Byte ranges of the decimal numbers in a text.
fn number_spans(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = if i > 0 && bytes[i - 1] == b'-' {
                i - 1
            } else {
                i
            };
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

fn draw<S: Strategy>(strategy: S, runner: &mut TestRunner) -> S::Value {
    strategy
        .new_tree(runner)
        .expect("strategies here always produce a value")
        .current()
}

/// A JSON text must parse back. (serde_json writes NaN as null, so the
/// numbers behind it are checked for being finite separately.)
fn check_json(what: &str, text: &str) -> Result<(), String> {
    serde_json::from_str::<serde_json::Value>(text)
        .map(drop)
        .map_err(|e| format!("{what}: invalid JSON: {e}"))
}

fn check_detections(detections: &[Detection]) -> Result<(), String> {
    for d in detections {
        let numbers = [d.u, d.v, d.axes[0], d.axes[1], d.confidence, d.angle];
        if numbers.iter().any(|x| !x.is_finite()) || d.yaw.is_some_and(|y| !y.is_finite()) {
            return Err(format!("detection with a non-finite number: {d:?}"));
        }
        if let Some(p) = &d.pose {
            if !(p.position.iter().all(|x| x.is_finite())
                && p.quaternion.iter().all(|x| x.is_finite()))
            {
                return Err(format!("pose with a non-finite number: {d:?}"));
            }
        }
    }
    Ok(())
}

/// State of one target's worker: seeds, reusable detectors, what it is on.
struct Fuzzer {
    dir: tempfile::TempDir,
    detector: Detector,
    detect_limit: Option<Duration>,
    slowest_ms_per_2mp: f64,
    image_seeds: Vec<(&'static str, Vec<u8>)>,
    family_seed: Vec<u8>,
    manifest_seed: Vec<u8>,
    template_seeds: Vec<Vec<u8>>,
    camera_seeds: Vec<(&'static str, Vec<u8>)>,
    arena_seeds: Vec<Vec<u8>>,
    board_seeds: Vec<(&'static str, Vec<u8>)>,
    bag_seeds: Vec<Vec<u8>>,
    /// Videos ffmpeg made of the seed scene (none without ffmpeg), made
    /// on the first video input.
    video_seeds: Option<Vec<(&'static str, Vec<u8>)>>,
    /// The command line's binary, for the targets that run it.
    whycode: Option<std::path::PathBuf>,
    /// Exit codes of the commands run with both streams working.
    baseline: std::collections::HashMap<usize, i32>,
    /// The input being tried, for the failure report.
    last: String,
    /// The same, seen by the thread that watches for hangs.
    hung_input: Option<std::sync::Arc<std::sync::Mutex<Option<String>>>>,
}

impl Fuzzer {
    fn new(detect_limit: Option<Duration>, whycode: Option<std::path::PathBuf>) -> Fuzzer {
        let family = Family::generate(8, 2).unwrap();
        let scene_image = seed_scene(&family);
        let encode = |format: image::ImageFormat, img: &image::DynamicImage| {
            let mut bytes = Vec::new();
            img.write_to(&mut Cursor::new(&mut bytes), format).unwrap();
            bytes
        };
        let grey = image::DynamicImage::ImageLuma8(scene_image.clone());
        let deep = image::DynamicImage::ImageLuma16(image::ImageBuffer::from_fn(
            scene_image.width(),
            scene_image.height(),
            |x, y| image::Luma([u16::from(scene_image.get_pixel(x, y).0[0]) * 16]),
        ));
        let colour = image::DynamicImage::ImageRgb8(grey.to_rgb8());
        let image_seeds = vec![
            ("png", encode(image::ImageFormat::Png, &grey)),
            ("png", encode(image::ImageFormat::Png, &deep)),
            ("jpg", encode(image::ImageFormat::Jpeg, &colour)),
            ("pgm", encode(image::ImageFormat::Pnm, &grey)),
            ("bmp", encode(image::ImageFormat::Bmp, &colour)),
        ];
        let markers = family_markers(&family, &[1, 2, 3, 4, 5], 40.0).unwrap();
        let sheet = layout(&SheetSpec {
            markers,
            template: Template::builtin("a4").unwrap(),
            name: "fuzz".into(),
            family: Some(FamilyRef {
                bits: 8,
                distance: 2,
            }),
            legacy: false,
        })
        .unwrap();
        let template_seeds = [
            include_bytes!("../../templates/a3.toml").to_vec(),
            include_bytes!("../../templates/a4.toml").to_vec(),
            include_bytes!("../../templates/letter.toml").to_vec(),
        ]
        .to_vec();
        Fuzzer {
            dir: tempfile::tempdir().unwrap(),
            detector: Detector::new(DetectorConfig {
                target: Target::WhyCode(family.clone()),
                ..DetectorConfig::default()
            }),
            detect_limit,
            slowest_ms_per_2mp: 0.0,
            image_seeds,
            family_seed: family.to_json().into_bytes(),
            manifest_seed: sheet.manifest.to_json().into_bytes(),
            template_seeds,
            camera_seeds: CAMERA_SEEDS
                .iter()
                .map(|(ext, text)| (*ext, text.as_bytes().to_vec()))
                .collect(),
            arena_seeds: ARENA_SEEDS.iter().map(|t| t.as_bytes().to_vec()).collect(),
            board_seeds: vec![
                ("yaml", BUNDLE_SEED.as_bytes().to_vec()),
                ("json", sheet.manifest.to_json().into_bytes()),
            ],
            bag_seeds: bag_seeds(&scene_image),
            video_seeds: None,
            whycode,
            baseline: std::collections::HashMap::new(),
            last: String::new(),
            hung_input: None,
        }
    }

    fn note_input(&mut self, description: String) {
        if let Some(shared) = &self.hung_input {
            *shared.lock().unwrap() = Some(description.clone());
        }
        self.last = description;
    }

    fn write(&self, name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let path = self.dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    /// Detects, timing against the limit and checking every number.
    fn detect(&mut self, image: &image::GrayImage) -> Result<Vec<Detection>, String> {
        self.detector.reset();
        let start = Instant::now();
        let found = self.detector.detect(image);
        let elapsed = start.elapsed();
        let pixels = f64::from(image.width()) * f64::from(image.height());
        let per_2mp = elapsed.as_secs_f64() * 1000.0 * 2.0e6 / pixels.max(2.0e6);
        self.slowest_ms_per_2mp = self.slowest_ms_per_2mp.max(per_2mp);
        if let Some(limit) = self.detect_limit {
            if per_2mp > limit.as_secs_f64() * 1000.0 {
                return Err(format!(
                    "detection took {:.0} ms on a {}x{} image (limit {:?} per 2 megapixels)",
                    elapsed.as_secs_f64() * 1000.0,
                    image.width(),
                    image.height(),
                    limit
                ));
            }
        }
        check_detections(&found)?;
        Ok(found)
    }

    fn image_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.image_seeds.len(), mutations(6)), runner);
        let (ext, seed) = self.image_seeds[which].clone();
        self.note_input(format!("{ext} seed {which} with {changes:?}"));
        let bytes = apply(&seed, &changes);
        let path = self.write(&format!("input.{ext}"), &bytes);
        let Ok(image) = load_gray(&path) else {
            return Ok(false);
        };
        self.detect(&image)?;
        Ok(true)
    }

    fn random_image(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (w, h, kind, seed) = draw((1u32..=1920, 1u32..=1080, 0u8..4, any::<u64>()), runner);
        self.note_input(format!("random image {w}x{h}, kind {kind}, seed {seed}"));
        let image = random_image(w, h, kind, seed);
        self.detect(&image)?;
        Ok(true)
    }

    fn family_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let changes = draw(mutations(4), runner);
        self.note_input(format!("family file with {changes:?}"));
        let path = self.write("family.json", &apply(&self.family_seed, &changes));
        let Ok(family) = Family::load(&path) else {
            return Ok(false);
        };
        check_json("family file", &family.to_json())?;
        // A loaded family must read its own markers.
        let mut detector = Detector::new(DetectorConfig {
            target: Target::WhyCode(family.clone()),
            ..DetectorConfig::default()
        });
        let id = family.len() as u32;
        let code = family
            .code(id)
            .ok_or("loaded family has no code for its last ID")?;
        let mut scene = Scene::new(Camera::ideal(160, 120, 60.0));
        let placement = Placement::viewed(nalgebra::Vector3::new(0.0, 0.0, 0.3), 0.0, 0.0, 0.0);
        let marker = Marker::whycode(family.bits(), code, 100.0);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
        let found = detector.detect(&render(&scene).0);
        check_detections(&found)?;
        Ok(true)
    }

    fn manifest_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let changes = draw(mutations(4), runner);
        self.note_input(format!("manifest with {changes:?}"));
        let path = self.write("manifest.json", &apply(&self.manifest_seed, &changes));
        let Ok(manifest) = Manifest::load(&path) else {
            return Ok(false);
        };
        check_json("manifest", &manifest.to_json())?;
        let Ok(mut detector) = whycode::validate::detector_for(&manifest) else {
            return Ok(true);
        };
        // Validate a small simulated view of page 1 against it.
        let mut scene = Scene::new(Camera::ideal(320, 240, 60.0));
        scene
            .objects
            .push(SceneObject::Page(whycode::simulate::SheetPage::new(
                manifest.clone(),
                1,
                Placement::viewed(nalgebra::Vector3::new(0.0, 0.0, 0.6), 0.2, 0.0, 0.0),
            )));
        let (image, truth) = render(&scene);
        check_json("ground truth", &truth.to_json())?;
        let report = whycode::validate::check_image("view", &manifest, &image, None, &mut detector);
        let summary = whycode::validate::summarise(&manifest, vec![report]);
        check_json("validate report", &summary.to_json())?;
        let _ = summary.to_table();
        Ok(true)
    }

    fn template_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.template_seeds.len(), mutations(4)), runner);
        self.note_input(format!("template {which} with {changes:?}"));
        let bytes = apply(&self.template_seeds[which], &changes);
        let Ok(template) = Template::parse("fuzz", &String::from_utf8_lossy(&bytes)) else {
            return Ok(false);
        };
        let family = Family::generate(8, 2).unwrap();
        let Ok(markers) = family_markers(&family, &[1, 2, 3], 30.0) else {
            return Ok(true);
        };
        let spec = SheetSpec {
            markers,
            template,
            name: "fuzz".into(),
            family: Some(FamilyRef {
                bits: 8,
                distance: 2,
            }),
            legacy: false,
        };
        if let Ok(sheet) = layout(&spec) {
            check_json("sheet manifest", &sheet.manifest.to_json())?;
        }
        Ok(true)
    }

    fn camera_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.camera_seeds.len(), mutations(4)), runner);
        let (ext, seed) = self.camera_seeds[which].clone();
        self.note_input(format!("camera seed {which} with {changes:?}"));
        let path = self.write(&format!("camera.{ext}"), &apply(&seed, &changes));
        let Ok(camera) = Camera::load(&path) else {
            return Ok(false);
        };
        // An accepted calibration projects and inverts finitely in its image.
        for (u, v) in [
            (0.0, 0.0),
            (f64::from(camera.width), f64::from(camera.height)),
        ] {
            let ray = camera.ray(u, v);
            if !(ray.x.is_finite() && ray.y.is_finite()) {
                return Err(format!(
                    "accepted calibration gives a non-finite ray: {camera:?}"
                ));
            }
            if !camera
                .project(&ray)
                .is_some_and(|(pu, pv)| pu.is_finite() && pv.is_finite())
            {
                return Err(format!("accepted calibration cannot project: {camera:?}"));
            }
        }
        Ok(true)
    }
}

impl Fuzzer {
    fn arena_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.arena_seeds.len(), mutations(4)), runner);
        self.note_input(format!("arena seed {which} with {changes:?}"));
        let path = self.write("arena.yaml", &apply(&self.arena_seeds[which], &changes));
        let Ok(arena) = whycode::arena::Arena::load(&path) else {
            return Ok(false);
        };
        // An accepted arena places the seed scene's markers finitely (or
        // not at all), with and without a diameter.
        let image = load_gray(&self.write("seed.png", &self.image_seeds[0].1.clone()))
            .map_err(|e| e.to_string())?;
        for diameter in [None, Some(whycode::units::Length::from_mm(60.0))] {
            let Ok(config) = (whycode::spec::DetectSpec {
                arena: Some(arena.clone()),
                diameter,
                ..Default::default()
            })
            .build() else {
                continue;
            };
            let mut session = whycode::Session::new(config);
            let Ok(report) = session.process(whycode::session::Frame::new(&image, "seed.png"))
            else {
                continue;
            };
            check_detections(&report.markers)?;
            for (d, a) in report.markers.iter().zip(&report.places) {
                if let Some(a) = a {
                    if ![a.x, a.y, a.z].iter().all(|v| v.is_finite())
                        || a.yaw.is_some_and(|y| !y.is_finite())
                    {
                        return Err(format!("arena position with a non-finite number: {d:?}"));
                    }
                }
            }
        }
        Ok(true)
    }

    fn board_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.board_seeds.len(), mutations(4)), runner);
        let (ext, seed) = self.board_seeds[which].clone();
        self.note_input(format!("board seed {which} with {changes:?}"));
        let path = self.write(&format!("board.{ext}"), &apply(&seed, &changes));
        let Ok(boards) = whycode::board::Board::load(&path) else {
            return Ok(false);
        };
        let Ok(config) = (whycode::spec::DetectSpec {
            camera: Some(Camera::ideal(320, 240, 60.0)),
            boards,
            ..Default::default()
        })
        .build() else {
            return Ok(true);
        };
        let mut session = whycode::Session::new(config);
        let image = load_gray(&self.write("seed.png", &self.image_seeds[0].1.clone()))
            .map_err(|e| e.to_string())?;
        let report = session
            .process(whycode::session::Frame::new(&image, "seed.png"))
            .map_err(|e| format!("the seed frame does not fit the board's camera: {e}"))?;
        check_detections(&report.markers)?;
        for pose in report.boards {
            let numbers = pose
                .position
                .iter()
                .chain(&pose.quaternion)
                .chain([&pose.rms_px]);
            if !numbers.into_iter().all(|v| v.is_finite()) {
                return Err(format!("board pose with a non-finite number: {pose:?}"));
            }
        }
        Ok(true)
    }

    /// Runs `whycode detect --format json FILE` on a mutated recording: it
    /// must print JSON lines and end with status 0, or end with status 1
    /// and one error line; never a panic, a signal or a hang.
    fn detect_recording(&mut self, name: &str, bytes: &[u8]) -> Result<bool, String> {
        let binary = self.whycode.clone().ok_or("no whycode binary")?;
        let path = self.write(name, bytes);
        let out = std::process::Command::new(&binary)
            .args(["detect", "--format", "json", "--diameter", "60mm"])
            .arg(&path)
            .current_dir(self.dir.path())
            .stdin(std::process::Stdio::null())
            .output()
            .map_err(|e| format!("cannot run {}: {e}", binary.display()))?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let Some(code) = out.status.code() else {
            return Err(format!("killed by a signal ({}): {stderr}", out.status));
        };
        if code == 101 || stderr.contains("panicked") {
            return Err(format!("panicked (exit {code}): {stderr}"));
        }
        for line in String::from_utf8_lossy(&out.stdout).lines() {
            check_json("detect's JSON line", line)?;
        }
        match code {
            0 => Ok(true),
            1 if stderr
                .lines()
                .last()
                .is_some_and(|l| l.starts_with("whycode: error: ")) =>
            {
                Ok(false)
            }
            _ => Err(format!("exit {code} without one error line: {stderr}")),
        }
    }

    fn bag_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, changes) = draw((0..self.bag_seeds.len(), mutations(6)), runner);
        self.note_input(format!("bag seed {which} with {changes:?}"));
        let bytes = apply(&self.bag_seeds[which], &changes);
        self.detect_recording("fuzz.mcap", &bytes)
    }

    fn video_file(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let seeds = match &self.video_seeds {
            Some(seeds) => seeds.clone(),
            None => {
                let made = video_seeds(self.dir.path(), &self.image_seeds[0].1);
                self.video_seeds = Some(made.clone());
                made
            }
        };
        if seeds.is_empty() {
            // No ffmpeg: nothing to mutate (the recordings tests say so).
            return Ok(false);
        }
        let (which, changes) = draw((0..seeds.len(), mutations(4)), runner);
        let (ext, seed) = &seeds[which];
        self.note_input(format!("{ext} video seed {which} with {changes:?}"));
        let bytes = apply(seed, &changes);
        self.detect_recording(&format!("fuzz.{ext}"), &bytes)
    }
}

/// Arena files as `whycode arena` writes them: measured with a camera
/// looking down from 2.5 m, and without one.
const ARENA_SEEDS: [&str; 2] = [
    "format: whycode-arena\nversion: 1\nids: [1, 5, 9, 3]\nsize: [2.0, 1.5]\n\
     marker_height: 0.1\ncorner_error: 0.001\n\
     camera: {fx: 277.1, fy: 277.1, cx: 159.5, cy: 119.5, distortion: [-0.1, 0.01, 0.0, 0.0, 0.0], width: 320, height: 240}\n\
     floor:\n  rotation: [[1, 0, 0], [0, -1, 0], [0, 0, -1]]\n  translation: [-1.0, 0.75, 2.5]\n",
    "format: whycode-arena\nversion: 1\nids: [1, 5, 9, 3]\nsize: [2.0, 1.5]\n\
     marker_height: 0.0\ncorner_error: 0.0\nimage_to_floor:\n  width: 320\n  height: 240\n\
     floor_to_image: [[120, 0, 40], [0, -120, 200], [0, 0, 1]]\n",
];

/// A bundle of the seed scene's markers, one given by position only.
const BUNDLE_SEED: &str = "bundles:\n  - name: rig\n    layout:\n\
      - {id: 1, diameter: 0.06, x: -0.12, y: 0, z: 0, qw: 1, qx: 0, qy: 0, qz: 0}\n\
      - {id: 5, diameter: 0.06, x: 0, y: 0, z: 0, qw: 1, qx: 0, qy: 0, qz: 0}\n\
      - {id: 9, size: 0.06, x: 0.12, y: 0, z: 0}\n";

/// Little-endian CDR, as bags hold ROS 2 messages: the encapsulation
/// header, then each primitive aligned to its size from the body's start.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Cdr {
        Cdr(vec![0, 1, 0, 0])
    }
    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u32(&mut self, v: u32) -> &mut Cdr {
        self.align(4);
        self.0.extend(v.to_le_bytes());
        self
    }
    fn f64s(&mut self, values: &[f64]) -> &mut Cdr {
        for v in values {
            self.align(8);
            self.0.extend(v.to_le_bytes());
        }
        self
    }
    fn bytes(&mut self, data: &[u8]) -> &mut Cdr {
        self.u32(data.len() as u32);
        self.0.extend(data);
        self
    }
    fn string(&mut self, text: &str) -> &mut Cdr {
        let mut data = text.as_bytes().to_vec();
        data.push(0);
        self.bytes(&data)
    }
    fn header(&mut self, k: u32) -> &mut Cdr {
        self.u32(100 + k).u32(5_000).string("cam")
    }
}

/// Bags of the seed scene: mono8 Image and PNG CompressedImage frames with
/// a camera_info, unchunked and in uncompressed chunks (so mutations reach
/// the records and messages, not a compressor's checksums).
fn bag_seeds(scene: &image::GrayImage) -> Vec<Vec<u8>> {
    let mut png = Vec::new();
    image::DynamicImage::ImageLuma8(scene.clone())
        .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let (w, h) = scene.dimensions();
    let info = {
        let mut m = Cdr::new();
        m.header(0).u32(h).u32(w).string("plumb_bob");
        m.u32(5).f64s(&[-0.1, 0.01, 0.0, 0.0, 0.0]);
        let (f, cx, cy) = (277.1, 159.5, 119.5);
        m.f64s(&[f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0]);
        m.f64s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        m.f64s(&[f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0]);
        m.u32(0).u32(0).u32(0).u32(0).u32(0).u32(0);
        m.0.push(0);
        m.0
    };
    let raw = |k: u32| {
        let mut m = Cdr::new();
        m.header(k).u32(h).u32(w).string("mono8");
        m.0.push(0);
        m.u32(w).bytes(scene.as_raw());
        m.0
    };
    let compressed = |k: u32| {
        let mut m = Cdr::new();
        m.header(k).string("png").bytes(&png);
        m.0
    };
    let write = |chunks: bool, topic: &str, schema: &str, frame: &dyn Fn(u32) -> Vec<u8>| {
        let mut writer = mcap::WriteOptions::new()
            .profile("ros2")
            .compression(None)
            .use_chunks(chunks)
            .calculate_chunk_crcs(false)
            .create(Cursor::new(Vec::new()))
            .unwrap();
        let mut channel = |topic: &str, schema: &str| {
            let s = writer.add_schema(schema, "ros2msg", b"").unwrap();
            writer
                .add_channel(s, topic, "cdr", &Default::default())
                .unwrap()
        };
        let (images, infos) = (
            channel(topic, schema),
            channel("/cam/camera_info", "sensor_msgs/msg/CameraInfo"),
        );
        for k in 0..3u32 {
            for (channel, data) in [(infos, info.clone()), (images, frame(k))] {
                let time = 1_000_000_000 + u64::from(k) * 33_000_000;
                writer
                    .write_to_known_channel(
                        &mcap::records::MessageHeader {
                            channel_id: channel,
                            sequence: k,
                            log_time: time,
                            publish_time: time,
                        },
                        &data,
                    )
                    .unwrap();
            }
        }
        writer.finish().unwrap();
        writer.into_inner().into_inner()
    };
    vec![
        write(false, "/cam/image_raw", "sensor_msgs/msg/Image", &raw),
        write(true, "/cam/image_raw", "sensor_msgs/msg/Image", &raw),
        write(
            false,
            "/cam/image_raw/compressed",
            "sensor_msgs/msg/CompressedImage",
            &compressed,
        ),
    ]
}

/// Short videos of the seed scene made by ffmpeg (MJPG in AVI, H.264 in
/// MP4 and Matroska); none when ffmpeg is missing.
fn video_seeds(dir: &std::path::Path, seed_png: &[u8]) -> Vec<(&'static str, Vec<u8>)> {
    let frame = dir.join("video-seed.png");
    if std::fs::write(&frame, seed_png).is_err() {
        return Vec::new();
    }
    let mut seeds = Vec::new();
    for (ext, codec) in [
        ("avi", &["-c:v", "mjpeg"][..]),
        ("mp4", &["-c:v", "libx264", "-pix_fmt", "yuv420p"][..]),
        ("mkv", &["-c:v", "libx264", "-pix_fmt", "yuv420p"][..]),
    ] {
        let out = dir.join(format!("video-seed.{ext}"));
        let made = std::process::Command::new("ffmpeg")
            .args([
                "-hide_banner",
                "-loglevel",
                "error",
                "-y",
                "-loop",
                "1",
                "-i",
            ])
            .arg(&frame)
            .args(["-t", "0.4", "-r", "10"])
            .args(codec)
            .arg(&out)
            .output();
        if matches!(made, Ok(m) if m.status.success()) {
            if let Ok(bytes) = std::fs::read(&out) {
                seeds.push((ext, bytes));
            }
        }
    }
    seeds
}

/// Commands for the output-stream target, run in the fuzzer's folder
/// (`seed.png` and `sheet.json` are written there first): each writes to
/// standard output or standard error or both, on success and on failure.
const STREAM_COMMANDS: [&[&str]; 10] = [
    &["ids", "--bits", "8", "--distance", "2"],
    &["ids", "--bits", "12", "--distance", "3", "--format", "json"],
    &["sheet", "--list-templates"],
    &["detect", "seed.png"],
    &["detect", "--format", "json", "--timings", "seed.png"],
    &["detect", "missing.png", "seed.png"],
    &["validate", "--manifest", "sheet.json", "seed.png"],
    &["marker", "--id", "3", "--no-check", "-o", "out.svg"],
    &[
        "simulate", "--ids", "1-3", "--size", "320x240", "-o", "sim.png",
    ],
    &["sheet", "--ids", "1-4", "--no-check", "-o", "sheet-out.pdf"],
];

/// What a standard stream of a child is connected to.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stream {
    /// A pipe that is read to the end.
    Read,
    /// A pipe whose reader has already gone: every write fails (EPIPE).
    Closed,
    /// /dev/full: every write fails (ENOSPC).
    Full,
}

impl Stream {
    fn of(k: u8) -> Stream {
        [Stream::Read, Stream::Closed, Stream::Full][usize::from(k % 3)]
    }

    /// The child's end, and the reader when it is read.
    fn connect(self) -> Result<(std::process::Stdio, Option<std::io::PipeReader>), String> {
        Ok(match self {
            Stream::Read => {
                let (reader, writer) = std::io::pipe().map_err(|e| e.to_string())?;
                (writer.into(), Some(reader))
            }
            Stream::Closed => {
                let (reader, writer) = std::io::pipe().map_err(|e| e.to_string())?;
                drop(reader);
                (writer.into(), None)
            }
            Stream::Full => (
                std::fs::OpenOptions::new()
                    .write(true)
                    .open("/dev/full")
                    .map_err(|e| format!("/dev/full: {e}"))?
                    .into(),
                None,
            ),
        })
    }
}

/// Reads a child's pipe to the end on a thread (so that a child filling
/// one pipe while the other is read does not stall).
fn drain(reader: Option<std::io::PipeReader>) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        if let Some(mut reader) = reader {
            let _ = std::io::Read::read_to_end(&mut reader, &mut bytes);
        }
        bytes
    })
}

impl Fuzzer {
    /// Runs command `which` with its streams connected as asked; its exit
    /// code, standard output and standard error (empty when not read).
    fn run_streams(
        &self,
        which: usize,
        out: Stream,
        err: Stream,
    ) -> Result<(i32, Vec<u8>, Vec<u8>), String> {
        let binary = self.whycode.as_ref().ok_or("no whycode binary")?;
        let (out_end, out_reader) = out.connect()?;
        let (err_end, err_reader) = err.connect()?;
        let mut child = std::process::Command::new(binary)
            .args(STREAM_COMMANDS[which])
            .current_dir(self.dir.path())
            .stdin(std::process::Stdio::null())
            .stdout(out_end)
            .stderr(err_end)
            .spawn()
            .map_err(|e| format!("cannot run {}: {e}", binary.display()))?;
        let (out_text, err_text) = (drain(out_reader), drain(err_reader));
        let status = child.wait().map_err(|e| e.to_string())?;
        let out_text = out_text.join().unwrap_or_default();
        let err_text = err_text.join().unwrap_or_default();
        let Some(code) = status.code() else {
            return Err(format!("killed by a signal ({status})"));
        };
        Ok((code, out_text, err_text))
    }

    fn output_streams(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (which, out_kind, err_kind) = draw((0..STREAM_COMMANDS.len(), 0u8..3, 0u8..3), runner);
        let (out, err) = (Stream::of(out_kind), Stream::of(err_kind));
        self.note_input(format!(
            "whycode {} with stdout {out:?}, stderr {err:?}",
            STREAM_COMMANDS[which].join(" ")
        ));
        if !self.dir.path().join("sheet.json").exists() {
            self.write("sheet.json", &self.manifest_seed.clone());
            self.write("seed.png", &self.image_seeds[0].1.clone());
        }
        let baseline = match self.baseline.get(&which) {
            Some(&code) => code,
            None => {
                let (code, _, text) = self.run_streams(which, Stream::Read, Stream::Read)?;
                if String::from_utf8_lossy(&text).contains("panicked") {
                    return Err(format!("panicked: {}", String::from_utf8_lossy(&text)));
                }
                self.baseline.insert(which, code);
                code
            }
        };
        let (code, _, text) = self.run_streams(which, out, err)?;
        let text = String::from_utf8_lossy(&text);
        if code == 101 || text.contains("panicked") {
            return Err(format!("panicked (exit {code}): {text}"));
        }
        // A reader that went away ends the run quietly (0); a full disk is
        // an error (1); standard error failing changes nothing.
        let allowed: &[i32] = match out {
            Stream::Read => &[baseline],
            Stream::Closed => &[baseline, 0],
            Stream::Full => &[baseline, 1],
        };
        if !allowed.contains(&code) {
            return Err(format!(
                "exit {code}, expected one of {allowed:?} (exit {baseline} with both streams read); stderr: {text}"
            ));
        }
        if out == Stream::Full && err == Stream::Read && code == 1 && baseline != 1 {
            let lines: Vec<&str> = text.lines().collect();
            if !lines
                .last()
                .is_some_and(|l| l.starts_with("whycode: error: "))
            {
                return Err(format!(
                    "a full stdout was not reported in one error line: {text}"
                ));
            }
        }
        Ok(true)
    }

    fn concurrent_writers(&mut self, runner: &mut TestRunner) -> Result<bool, String> {
        let (runs, sheet, ext, first) =
            draw((2usize..=4, any::<bool>(), 0usize..3, 1u32..=4), runner);
        let binary = self.whycode.clone().ok_or("no whycode binary")?;
        let dir = self.dir.path().join("concurrent");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let ext = ["pdf", "png", "svg"][ext];
        let commands: Vec<Vec<String>> = (0..runs as u32)
            .map(|k| {
                // Different IDs per run (the default family has 16).
                let ids = format!("{}-{}", first + 3 * k, first + 3 * k + 2);
                if sheet {
                    ["sheet", "--ids", &ids, "--no-check", "--dpi", "40"]
                        .iter()
                        .map(|s| s.to_string())
                        .chain(["-o".into(), format!("out.{ext}")])
                        .collect()
                } else {
                    let image = if ext == "pdf" { "jpg" } else { "png" };
                    ["simulate", "--ids", &ids, "--size", "320x240"]
                        .iter()
                        .map(|s| s.to_string())
                        .chain(["-o".into(), format!("out.{image}")])
                        .collect()
                }
            })
            .collect();
        self.note_input(format!("{runs} concurrent runs: {commands:?}"));
        let children: Vec<_> = commands
            .iter()
            .map(|args| {
                std::process::Command::new(&binary)
                    .args(args)
                    .current_dir(&dir)
                    .stdout(std::process::Stdio::null())
                    .stderr(std::process::Stdio::piped())
                    .spawn()
                    .map_err(|e| e.to_string())
            })
            .collect::<Result<_, _>>()?;
        for child in children {
            let out = child.wait_with_output().map_err(|e| e.to_string())?;
            if !out.status.success() {
                return Err(format!(
                    "a run failed ({}): {}",
                    out.status,
                    String::from_utf8_lossy(&out.stderr)
                ));
            }
        }
        // The record written last names the files of its own run.
        let record = dir.join("out.json");
        let text = std::fs::read_to_string(&record).map_err(|e| format!("out.json: {e}"))?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("out.json: {e}"))?;
        let files = value["files"].as_array().cloned().unwrap_or_default();
        if files.is_empty() {
            return Err("out.json lists no files".into());
        }
        for entry in files {
            let name = entry["file"].as_str().unwrap_or_default();
            let bytes = std::fs::read(dir.join(name)).map_err(|e| format!("{name}: {e}"))?;
            if whycode::fileset::sha256_hex(&bytes) != entry["sha256"].as_str().unwrap_or_default()
            {
                return Err(format!("{name} is not the file out.json was written with"));
            }
        }
        let leftovers: Vec<String> = std::fs::read_dir(&dir)
            .map_err(|e| e.to_string())?
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".whycode-"))
            .collect();
        if !leftovers.is_empty() {
            return Err(format!("temporary files left: {leftovers:?}"));
        }
        Ok(true)
    }
}

/// A 320x240 view of three markers, the seed of the image-file target.
fn seed_scene(family: &Family) -> image::GrayImage {
    let mut scene = Scene::new(Camera::ideal(320, 240, 60.0));
    for (k, id) in [1u32, 5, 9].into_iter().enumerate() {
        let marker = Marker::whycode(8, family.code(id).unwrap(), 60.0);
        let x = (k as f64 - 1.0) * 0.12;
        let placement = Placement::viewed(nalgebra::Vector3::new(x, 0.0, 0.5), 0.3, 0.1, 0.7);
        scene
            .objects
            .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    }
    scene.background = Background::Uniform(0.45);
    scene.noise = 2.0;
    render(&scene).0
}

/// Random pictures that stress segmentation: noise, many discs and rings,
/// stripes, or a simulated scene of markers at random poses.
fn random_image(w: u32, h: u32, kind: u8, seed: u64) -> image::GrayImage {
    let mut rng = whycode::math::rng::Pcg32::new(seed, 7);
    match kind {
        0 => image::GrayImage::from_fn(w, h, |_, _| image::Luma([rng.next_u32() as u8])),
        1 | 2 => {
            let mut img = image::GrayImage::from_pixel(w, h, image::Luma([rng.next_u32() as u8]));
            let shapes = rng.next_u32() % 400;
            for _ in 0..shapes {
                let (cx, cy) = (rng.range(0.0, f64::from(w)), rng.range(0.0, f64::from(h)));
                let r = rng.range(1.0, 80.0);
                let inner = if kind == 2 { rng.range(0.0, r) } else { 0.0 };
                let (ax, ay) = (rng.range(0.3, 1.0), rng.range(0.3, 1.0));
                let shade = (rng.next_u32() % 2 * 255) as u8;
                let (x0, x1) = ((cx - r).max(0.0) as u32, ((cx + r) as u32).min(w));
                let (y0, y1) = ((cy - r).max(0.0) as u32, ((cy + r) as u32).min(h));
                for y in y0..y1 {
                    for x in x0..x1 {
                        let d = ((f64::from(x) - cx) / ax).hypot((f64::from(y) - cy) / ay);
                        if d < r && d >= inner {
                            img.put_pixel(x, y, image::Luma([shade]));
                        }
                    }
                }
            }
            img
        }
        _ => {
            let family = Family::generate(8, 2).unwrap();
            let mut scene = Scene::new(Camera::ideal(w.max(16), h.max(16), rng.range(30.0, 120.0)));
            let count = rng.next_u32() % 40;
            for _ in 0..count {
                let id = 1 + rng.next_u32() % family.len() as u32;
                let marker = Marker::whycode(8, family.code(id).unwrap(), rng.range(5.0, 200.0));
                let position = nalgebra::Vector3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-0.6, 0.6),
                    rng.range(0.2, 4.0),
                );
                let placement = Placement::viewed(
                    position,
                    rng.range(-1.5, 1.5),
                    rng.range(-1.5, 1.5),
                    rng.range(0.0, 6.3),
                );
                scene
                    .objects
                    .push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
            }
            scene.background = if rng.next_u32().is_multiple_of(2) {
                Background::Clutter { density: 1.5 }
            } else {
                Background::Uniform(rng.range(0.0, 1.0))
            };
            scene.noise = rng.range(0.0, 20.0);
            scene.focus_blur_px = rng.range(0.0, 3.0);
            scene.seed = seed;
            render(&scene).0
        }
    }
}

const CAMERA_SEEDS: [(&str, &str); 3] = [
    (
        "yaml",
        "image_width: 640\nimage_height: 480\ncamera_name: cam\n\
         camera_matrix:\n  rows: 3\n  cols: 3\n  data: [612.5, 0, 319.5, 0, 611.8, 241.2, 0, 0, 1]\n\
         distortion_model: plumb_bob\n\
         distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [-0.21, 0.07, 0.001, -0.0005, 0]\n",
    ),
    (
        "yaml",
        "%YAML:1.0\n---\nimage_width: 1280\nimage_height: 720\n\
         camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   \
         data: [ 910.2, 0., 639.5, 0., 909.7, 359.5, 0., 0., 1. ]\n\
         distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   \
         data: [ 0.1, -0.25, 0., 0., 0.08 ]\n",
    ),
    (
        "xml",
        "<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width>640</image_width>\n\
         <image_height>480</image_height>\n<camera_matrix type_id=\"opencv-matrix\">\
         <rows>3</rows><cols>3</cols><dt>d</dt>\n<data>600. 0. 320. 0. 600. 240. 0. 0. 1.</data>\
         </camera_matrix>\n<distortion_coefficients type_id=\"opencv-matrix\"><rows>5</rows>\
         <cols>1</cols><dt>d</dt>\n<data>-0.1 0.02 0. 0. 0.</data></distortion_coefficients>\n\
         </opencv_storage>\n",
    ),
];

/// One line per target, and the failures.
pub fn report(summaries: &[TargetSummary]) -> String {
    let mut out = String::new();
    for s in summaries {
        if let Some(why) = s.skipped {
            out.push_str(&format!("{:<15} skipped: {why}\n", s.name));
            continue;
        }
        out.push_str(&format!(
            "{:<15} {:>7} inputs, {:>7} accepted by the loader, slowest detection {:>6.1} ms per 2 MP, {} failure(s)\n",
            s.name,
            s.inputs,
            s.accepted,
            s.slowest_ms_per_2mp,
            s.failures.len()
        ));
        for f in &s.failures {
            out.push_str(&format!("  FAILED: {f}\n"));
        }
    }
    out
}
