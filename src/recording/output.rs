//! What a recorded run writes: the detections as a bag in the ROS 2 node's
//! layout (`/tf` and `~/markers`, stamped like their images) and the
//! annotated frames as a video through ffmpeg.

use super::RecordingError;
use crate::ros::cdr;
use crate::ros::describe::Described;
use crate::ros::msg::{MarkerArray, RosType, TfMessage};
use std::collections::BTreeMap;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// The topic the node publishes its marker arrays on (`~/markers` of a
/// node named `whycode`).
pub const MARKERS_TOPIC: &str = "/whycode/markers";
/// The transforms' topic.
pub const TF_TOPIC: &str = "/tf";

const SEPARATOR: &str =
    "\n================================================================================\n";

/// ros2msg definitions, as rosbag2 stores them: the message, then each
/// type it uses after a separator line and `MSG: package/Type`.
fn definition(main: &str, dependencies: &[(&str, &str)]) -> String {
    let mut text = main.trim_end().to_string();
    for (name, body) in dependencies {
        text.push_str(SEPARATOR);
        text.push_str(&format!("MSG: {name}\n{}", body.trim_end()));
    }
    text.push('\n');
    text
}

const HEADER: (&str, &str) = (
    "std_msgs/Header",
    "builtin_interfaces/Time stamp\nstring frame_id",
);
const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec");
const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z");
const POINT: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z");
const QUATERNION: (&str, &str) = (
    "geometry_msgs/Quaternion",
    "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
);

fn tf_definition() -> String {
    definition(
        "geometry_msgs/TransformStamped[] transforms",
        &[
            (
                "geometry_msgs/TransformStamped",
                "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform",
            ),
            HEADER,
            TIME,
            (
                "geometry_msgs/Transform",
                "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation",
            ),
            VECTOR3,
            QUATERNION,
        ],
    )
}

fn markers_definition() -> String {
    // The .msg files colcon builds for the node, type names qualified.
    let array = include_str!("../../ros2/whycode_msgs/msg/MarkerArray.msg")
        .replace("\nMarker[] markers", "\nwhycode_msgs/Marker[] markers");
    definition(
        &array,
        &[
            HEADER,
            TIME,
            (
                "whycode_msgs/Marker",
                include_str!("../../ros2/whycode_msgs/msg/Marker.msg"),
            ),
            (
                "geometry_msgs/Pose",
                "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
            ),
            POINT,
            QUATERNION,
        ],
    )
}

/// A bag of detections, built in memory (markers are small next to the
/// images they came from) and written whole by the caller.
pub struct DetectionsBag {
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    tf: u16,
    markers: u16,
    sequence: u32,
}

impl DetectionsBag {
    /// An empty bag with the /tf and marker channels.
    pub fn new() -> Result<DetectionsBag, mcap::McapError> {
        let mut writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("whycode ", env!("CARGO_PKG_VERSION")))
            .create(Cursor::new(Vec::new()))?;
        let mut channel = |topic: &str, name: String, text: String| {
            let schema = writer.add_schema(&name, "ros2msg", text.as_bytes())?;
            writer.add_channel(schema, topic, "cdr", &BTreeMap::new())
        };
        let tf = channel(TF_TOPIC, TfMessage::schema_name(), tf_definition())?;
        let markers = channel(
            MARKERS_TOPIC,
            MarkerArray::schema_name(),
            markers_definition(),
        )?;
        Ok(DetectionsBag {
            writer,
            tf,
            markers,
            sequence: 0,
        })
    }

    /// Adds one image's messages at its stamp: the marker array always
    /// (also when empty, as the node publishes it), the transforms when
    /// there are any.
    pub fn add(&mut self, stamp_ns: i64, described: &Described) -> Result<(), mcap::McapError> {
        let time = stamp_ns.max(0) as u64;
        if !described.transforms.is_empty() {
            let message = TfMessage {
                transforms: described.transforms.clone(),
            };
            self.write(self.tf, time, &cdr::encode(&message))?;
        }
        self.write(self.markers, time, &cdr::encode(&described.markers))
    }

    fn write(&mut self, channel_id: u16, time: u64, data: &[u8]) -> Result<(), mcap::McapError> {
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: time,
                publish_time: time,
            },
            data,
        )
    }

    /// The bag's bytes.
    pub fn finish(mut self) -> Result<Vec<u8>, mcap::McapError> {
        self.writer.finish()?;
        Ok(self.writer.into_inner().into_inner())
    }
}

/// An annotated video written by ffmpeg into a staged file, frame by frame
/// as they come: the frame rate follows the first two frames' stamps.
pub struct AnnotatedVideo {
    target: PathBuf,
    staged: PathBuf,
    child: Option<Child>,
    first: Option<(image::RgbImage, i64)>,
    size: (u32, u32),
}

impl AnnotatedVideo {
    /// A video for `target`, written into `staged` (a temporary file beside
    /// it, renamed by the caller once [`AnnotatedVideo::finish`] is done).
    pub fn new(target: &Path, staged: &Path) -> AnnotatedVideo {
        AnnotatedVideo {
            target: target.to_path_buf(),
            staged: staged.to_path_buf(),
            child: None,
            first: None,
            size: (0, 0),
        }
    }

    fn fail(&self, problem: impl std::fmt::Display) -> RecordingError {
        RecordingError::Video {
            path: self.target.clone(),
            problem: format!("cannot write the annotated video: {problem}"),
        }
    }

    /// Adds a frame shown at `stamp_ns`.
    pub fn push(&mut self, frame: image::RgbImage, stamp_ns: i64) -> Result<(), RecordingError> {
        if self.child.is_none() {
            match self.first.take() {
                None => {
                    self.first = Some((frame, stamp_ns));
                    return Ok(());
                }
                Some((first, first_ns)) => {
                    let step = stamp_ns - first_ns;
                    let fps = if step > 0 { 1e9 / step as f64 } else { 30.0 };
                    self.start(first.dimensions(), fps)?;
                    self.write(&first)?;
                }
            }
        }
        self.write(&frame)
    }

    fn start(&mut self, (width, height): (u32, u32), fps: f64) -> Result<(), RecordingError> {
        let ext = self
            .target
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let (muxer, codec): (&str, &[&str]) = match ext.as_str() {
            "mkv" => (
                "matroska",
                &[
                    "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p",
                ],
            ),
            "mov" => (
                "mov",
                &[
                    "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p",
                ],
            ),
            "avi" => (
                "avi",
                &["-c:v", "mjpeg", "-q:v", "3", "-pix_fmt", "yuvj420p"],
            ),
            "webm" => (
                "webm",
                &["-c:v", "libvpx", "-deadline", "realtime", "-b:v", "2M"],
            ),
            _ => (
                "mp4",
                &[
                    "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p",
                ],
            ),
        };
        // 4:2:0 needs even sizes: the last odd row or column is dropped.
        let even = "crop=trunc(iw/2)*2:trunc(ih/2)*2";
        let child = Command::new(super::video::ffmpeg_program())
            .args([
                "-hide_banner",
                "-nostdin",
                "-nostats",
                "-loglevel",
                "error",
                "-y",
            ])
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-s"])
            .arg(format!("{width}x{height}"))
            .args(["-framerate", &format!("{fps:.6}"), "-i", "-", "-vf", even])
            .args(codec)
            .args(["-f", muxer])
            .arg(&self.staged)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => RecordingError::FfmpegMissing {
                    path: self.target.clone(),
                },
                _ => self.fail(e),
            })?;
        self.child = Some(child);
        self.size = (width, height);
        Ok(())
    }

    fn write(&mut self, frame: &image::RgbImage) -> Result<(), RecordingError> {
        if frame.dimensions() != self.size {
            return Err(self.fail(format!(
                "a frame of {}x{} among frames of {}x{}",
                frame.width(),
                frame.height(),
                self.size.0,
                self.size.1
            )));
        }
        let stdin = self.child.as_mut().and_then(|c| c.stdin.as_mut());
        match stdin.map(|s| s.write_all(frame.as_raw())) {
            Some(Ok(())) => Ok(()),
            _ => Err(self
                .finish_child()
                .err()
                .unwrap_or_else(|| self.fail("ffmpeg stopped"))),
        }
    }

    fn finish_child(&mut self) -> Result<(), RecordingError> {
        let Some(mut child) = self.child.take() else {
            return Ok(());
        };
        drop(child.stdin.take());
        let output = child.wait_with_output().map_err(|e| self.fail(e))?;
        if output.status.success() {
            Ok(())
        } else {
            let said = String::from_utf8_lossy(&output.stderr);
            Err(self.fail(said.lines().last().unwrap_or("ffmpeg failed")))
        }
    }

    /// Ends the video (a single frame is written at 1 frame per second).
    pub fn finish(mut self) -> Result<(), RecordingError> {
        if let Some((first, _)) = self.first.take() {
            self.start(first.dimensions(), 1.0)?;
            self.write(&first)?;
        }
        self.finish_child()
    }
}

impl Drop for AnnotatedVideo {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
