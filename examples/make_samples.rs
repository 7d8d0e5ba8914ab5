//! Writes the sample recordings in `samples/` (see samples/README.md), the
//! recordings the README's "Try it on a recording" commands run on: five
//! robots' markers driving across a floor (`whycode_testkit::swarm`), drawn
//! by the library's simulator, as
//!
//! - `swarm.mp4`: 3 s at 15 frames per second, H.264 (yuv420p) by the
//!   `ffmpeg` program;
//! - `swarm.mcap`: a ROS 2 bag of every third of those frames (5 per
//!   second) as JPEG sensor_msgs/msg/CompressedImage on
//!   /camera/image_raw/compressed, each with the camera's
//!   sensor_msgs/msg/CameraInfo on /camera/camera_info;
//! - `camera.yaml`: the same calibration as a ROS camera_info file, for
//!   `--camera` on the video.
//!
//! Every run gives the same frames and the same JPEG bytes, and the same
//! video with the same ffmpeg (its encoder runs on one thread). The bag
//! holds the same messages, but the mcap crate's writer puts the summary's
//! copies of the schema and channel records in a random order (a HashMap's).
//!
//!     cargo run --release --example make_samples [-- OUT_DIR]   # default: samples/

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;
use whycode::recording::output::CameraBag;
use whycode::ros::msg::{CameraInfo, CompressedImage, Header, Time};
use whycode_testkit::swarm;

/// JPEG quality of the bag's frames: below compressed_image_transport's
/// default of 95, to keep the bag small; the rings stay readable.
const JPEG_QUALITY: u8 = 80;
/// x264's constant rate factor: 23 is its default; the markers' rings
/// stay sharp at it.
const CRF: &str = "23";

fn main() {
    let out: PathBuf = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("samples"));
    std::fs::create_dir_all(&out).expect("the output folder");
    let started = Instant::now();

    let count = swarm::frames(swarm::VIDEO_FPS);
    eprintln!("rendering {count} frames of 640x480 ...");
    let frames: Vec<image::GrayImage> = (0..count)
        .map(|k| swarm::frame(k, swarm::VIDEO_FPS))
        .collect();

    write_video(&out.join("swarm.mp4"), &frames);
    write_bag(&out.join("swarm.mcap"), &frames);
    let camera = swarm::camera().to_ros_yaml("swarm_camera");
    std::fs::write(out.join("camera.yaml"), camera).expect("camera.yaml written");

    for name in ["swarm.mp4", "swarm.mcap", "camera.yaml"] {
        let size = std::fs::metadata(out.join(name)).expect("written").len();
        println!("{:>10} bytes  {}", size, out.join(name).display());
    }
    println!("done in {:.1} s", started.elapsed().as_secs_f64());
}

/// The frames as an H.264 video through ffmpeg.
fn write_video(path: &Path, frames: &[image::GrayImage]) {
    let (width, height) = frames[0].dimensions();
    let mut child = Command::new("ffmpeg")
        .args(["-hide_banner", "-loglevel", "error", "-y"])
        .args(["-f", "rawvideo", "-pix_fmt", "gray", "-s"])
        .arg(format!("{width}x{height}"))
        .args(["-framerate", &swarm::VIDEO_FPS.to_string(), "-i", "-"])
        .args(["-c:v", "libx264", "-preset", "slow", "-crf", CRF])
        .args(["-pix_fmt", "yuv420p", "-movflags", "+faststart"])
        // x264's output depends on its thread count, which ffmpeg sets from
        // the machine's cores: one thread gives the same bytes everywhere.
        // bitexact keeps ffmpeg's version string out of the file.
        .args([
            "-threads",
            "1",
            "-fflags",
            "+bitexact",
            "-flags:v",
            "+bitexact",
        ])
        .arg(path)
        .stdin(Stdio::piped())
        .spawn()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    let mut stdin = child.stdin.take().expect("ffmpeg's input");
    for frame in frames {
        stdin.write_all(frame.as_raw()).expect("a frame to ffmpeg");
    }
    drop(stdin);
    assert!(
        child.wait().expect("ffmpeg ends").success(),
        "ffmpeg failed"
    );
}

/// Every third frame as the bag a camera driver's recording gives.
fn write_bag(path: &Path, frames: &[image::GrayImage]) {
    let step = swarm::VIDEO_FPS / swarm::BAG_FPS;
    let mut bag = CameraBag::<CompressedImage>::new(swarm::BAG_TOPIC).expect("a bag");
    for (k, frame) in frames.iter().step_by(step as usize).enumerate() {
        let stamp_ns = swarm::FIRST_STAMP_NS + k as i64 * 1_000_000_000 / i64::from(swarm::BAG_FPS);
        let header = Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: swarm::CAMERA_FRAME.into(),
        };
        let info = CameraInfo::from_camera(&swarm::camera(), header.clone());
        bag.add_camera_info(&info).expect("camera_info added");
        let jpeg = whycode::image_io::encode_image(Path::new("frame.jpg"), frame, JPEG_QUALITY)
            .expect("a JPEG frame");
        bag.add_image(&CompressedImage {
            header,
            format: "jpeg".into(),
            data: jpeg,
        })
        .expect("an image added");
    }
    std::fs::write(path, bag.finish().expect("the bag")).expect("the bag written");
}
