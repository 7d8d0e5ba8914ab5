//! Recorded runs for the tests: a simulated sequence of frames (markers
//! that move, one that comes and goes), bags written by PyPI's mcap and
//! mcap-ros2-support (`tests/recordings/bag.py`, in a virtual environment
//! under target/ made on first use) and videos encoded by ffmpeg.

use image::GrayImage;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use whycode::camera::Camera;
use whycode::geometry::Marker;
use whycode::Family;
use whycode_testkit::scenes::{self, Look};

/// Frame size of the sequence.
pub const SIZE: (u32, u32) = (320, 240);
/// Focal length of its camera, pixels.
pub const FOCAL: f64 = 300.0;
/// The printed diameter of its markers, millimetres.
pub const DIAMETER_MM: f64 = 40.0;
/// Frames in the sequence.
pub const FRAMES: usize = 20;
/// The ID that is only in some frames.
pub const VISITOR: u32 = 7;
/// The frames it is in.
pub const VISIT: std::ops::RangeInclusive<usize> = 4..=15;
/// A recording is scanned whole in every frame: a newcomer is found in
/// the frame it comes (live tracking would look in one band of rows a
/// frame and take up to 8).
pub const DISCOVERY_FRAMES: usize = 0;

/// The sequence's camera.
pub fn camera() -> Camera {
    scenes::camera(SIZE.0, SIZE.1, FOCAL)
}

/// Frame `k` of the sequence and the IDs it shows (ascending): IDs 1 and
/// 4 move across the frame, [`VISITOR`] joins in the frames of [`VISIT`].
pub fn frame(k: usize) -> (GrayImage, Vec<u32>) {
    let family = Family::generate(8, 2).expect("the default family");
    let camera = camera();
    let marker = |id: u32| {
        (
            Marker::whycode(8, family.code(id).unwrap(), DIAMETER_MM),
            id,
        )
    };
    let t = k as f64;
    let mut markers = vec![
        scenes::marker_at(
            &camera,
            marker(1),
            (60.0 + 4.0 * t, 70.0),
            52.0,
            0.1 * t,
            (0.0, 0.0),
        ),
        scenes::marker_at(
            &camera,
            marker(4),
            (250.0 - 3.0 * t, 160.0 + t),
            56.0,
            1.0,
            (0.3, 0.5),
        ),
    ];
    let mut ids = vec![1, 4];
    if VISIT.contains(&k) {
        markers.push(scenes::marker_at(
            &camera,
            marker(VISITOR),
            (150.0, 110.0 + 2.0 * t),
            50.0,
            2.0,
            (0.0, 0.0),
        ));
        ids.push(VISITOR);
    }
    let look = Look {
        noise: 2.0,
        ..Look::default()
    };
    (scenes::render(&camera, &markers, look).0, ids)
}

/// The whole sequence, rendered once per test process.
pub fn sequence() -> &'static [(GrayImage, Vec<u32>)] {
    static FRAMES_ONCE: std::sync::OnceLock<Vec<(GrayImage, Vec<u32>)>> =
        std::sync::OnceLock::new();
    FRAMES_ONCE.get_or_init(|| (0..FRAMES).map(frame).collect())
}

/// The Python with mcap and mcap-ros2-support: a virtual environment in
/// target/, made (and the packages installed from PyPI) on first use.
pub fn python() -> PathBuf {
    static MADE: Mutex<()> = Mutex::new(());
    let _once = MADE.lock().unwrap_or_else(|p| p.into_inner());
    let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join("../recordings-venv");
    let python = venv.join("bin/python");
    let ready = venv.join(".installed");
    if !ready.exists() {
        let made = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .expect("python3 runs");
        assert!(made.success(), "python3 -m venv failed");
        let installed = Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "-q",
                "mcap==1.6.0",
                "mcap-ros2-support==0.6.0",
            ])
            .status()
            .expect("pip runs");
        assert!(
            installed.success(),
            "pip install mcap mcap-ros2-support failed"
        );
        std::fs::write(&ready, "").unwrap();
    }
    python
}

fn bag_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/recordings/bag.py")
}

/// Writes a bag of `messages` (see tests/recordings/bag.py) to `path`.
pub fn write_bag(path: &Path, messages: &[serde_json::Value]) {
    let spec = path.with_extension("json");
    let body = serde_json::json!({ "path": path, "messages": messages });
    std::fs::write(&spec, body.to_string()).unwrap();
    let out = Command::new(python())
        .arg(bag_script())
        .arg("write")
        .arg(&spec)
        .output()
        .expect("bag.py runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every message of a bag, decoded by mcap-ros2-support.
pub fn read_bag(path: &Path) -> Vec<serde_json::Value> {
    let out = Command::new(python())
        .arg(bag_script())
        .arg("read")
        .arg(path)
        .output()
        .expect("bag.py runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Encodes the sequence's frames into a video with ffmpeg at `fps`
/// (`codec`: ffmpeg's arguments for the codec).
pub fn write_video(dir: &Path, name: &str, fps: u32, codec: &[&str]) -> PathBuf {
    let frames = dir.join(format!("{name}-frames"));
    std::fs::create_dir_all(&frames).unwrap();
    for (k, (image, _)) in sequence().iter().enumerate() {
        image.save(frames.join(format!("f{k:03}.png"))).unwrap();
    }
    let path = dir.join(name);
    let out = Command::new("ffmpeg")
        .args(["-hide_banner", "-loglevel", "error", "-y", "-framerate"])
        .arg(fps.to_string())
        .arg("-i")
        .arg(frames.join("f%03d.png"))
        .args(codec)
        .arg(&path)
        .output()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

/// Checks the IDs a tracked stream reported for frame `k`: only IDs the
/// frame shows, those there from the start in every frame, and the
/// visitor from at most [`DISCOVERY_FRAMES`] after it came until it left.
pub fn assert_ids(k: usize, reported: &[u32], what: &str) {
    let truth = &sequence()[k].1;
    assert!(
        reported.iter().all(|id| truth.contains(id)),
        "{what}: frame {k} reports {reported:?}, shows {truth:?}"
    );
    assert!(
        reported.contains(&1) && reported.contains(&4),
        "{what}: frame {k}: {reported:?}"
    );
    if k >= VISIT.start() + DISCOVERY_FRAMES && VISIT.contains(&k) {
        assert!(
            reported.contains(&VISITOR),
            "{what}: frame {k}: {reported:?}"
        );
    }
}

/// The JSON lines of `whycode detect` output.
pub fn lines(stdout: &str) -> Vec<serde_json::Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect()
}

/// The IDs of a JSON line's markers, ascending, without 0.
pub fn ids(line: &serde_json::Value) -> Vec<u32> {
    let mut ids: Vec<u32> = line["markers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["id"].as_u64().unwrap() as u32)
        .filter(|&id| id != 0)
        .collect();
    ids.sort_unstable();
    ids
}
