//! What a recorded run writes: the detections as a bag in the ROS 2 node's
//! layout (`/tf` and `~/markers`, stamped like their images) and the
//! annotated frames as a video through ffmpeg. And the other end of a
//! run: [`CameraBag`], a bag of a camera's images and camera_info as
//! `ros2 bag record` stores them (the sample recordings are made with it).

use super::RecordingError;
use crate::ros::cdr;
use crate::ros::describe::Described;
use crate::ros::msg::{CameraInfo, CompressedImage, Image, MarkerArray, RosType, TfMessage, Time};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::{Cursor, Read, Write};
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::process::{ChildStderr, ChildStdin, Command, Stdio};

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

fn compressed_image_definition() -> String {
    definition(
        "std_msgs/Header header\nstring format\nuint8[] data",
        &[HEADER, TIME],
    )
}

fn image_definition() -> String {
    definition(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n\
         uint8 is_bigendian\nuint32 step\nuint8[] data",
        &[HEADER, TIME],
    )
}

fn camera_info_definition() -> String {
    definition(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n\
         float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n\
         uint32 binning_y\nsensor_msgs/RegionOfInterest roi",
        &[
            HEADER,
            TIME,
            (
                "sensor_msgs/RegionOfInterest",
                "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify",
            ),
        ],
    )
}

/// An MCAP file in rosbag2's layout (the `ros2` profile, ros2msg schemas,
/// CDR messages), built in memory.
struct Ros2Bag {
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    sequence: u32,
}

impl Ros2Bag {
    fn new(options: mcap::WriteOptions) -> Result<Ros2Bag, mcap::McapError> {
        let writer = options
            .profile("ros2")
            .library(concat!("whycode ", env!("CARGO_PKG_VERSION")))
            .create(Cursor::new(Vec::new()))?;
        Ok(Ros2Bag {
            writer,
            sequence: 0,
        })
    }

    /// A channel on `topic` for messages of type `T`, whose ros2msg
    /// definition is `text`.
    fn channel<T: RosType>(&mut self, topic: &str, text: &str) -> Result<u16, mcap::McapError> {
        let schema = self
            .writer
            .add_schema(&T::schema_name(), "ros2msg", text.as_bytes())?;
        self.writer
            .add_channel(schema, topic, "cdr", &BTreeMap::new())
    }

    /// Writes `message` on a channel, logged and published at `stamp_ns`.
    fn write<T: Serialize>(
        &mut self,
        channel_id: u16,
        stamp_ns: i64,
        message: &T,
    ) -> Result<(), mcap::McapError> {
        let time = stamp_ns.max(0) as u64;
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: time,
                publish_time: time,
            },
            &cdr::encode(message),
        )
    }

    fn finish(mut self) -> Result<Vec<u8>, mcap::McapError> {
        self.writer.finish()?;
        Ok(self.writer.into_inner().into_inner())
    }
}

/// A bag of detections, built in memory (markers are small next to the
/// images they came from) and written whole by the caller.
pub struct DetectionsBag {
    bag: Ros2Bag,
    tf: u16,
    markers: u16,
}

impl DetectionsBag {
    /// An empty bag with the /tf and marker channels.
    pub fn new() -> Result<DetectionsBag, mcap::McapError> {
        let mut bag = Ros2Bag::new(mcap::WriteOptions::new())?;
        let tf = bag.channel::<TfMessage>(TF_TOPIC, &tf_definition())?;
        let markers = bag.channel::<MarkerArray>(MARKERS_TOPIC, &markers_definition())?;
        Ok(DetectionsBag { bag, tf, markers })
    }

    /// Adds one image's messages at its stamp: the marker array always
    /// (also when empty, as the node publishes it), the transforms when
    /// there are any.
    pub fn add(&mut self, stamp_ns: i64, described: &Described) -> Result<(), mcap::McapError> {
        if !described.transforms.is_empty() {
            let message = TfMessage {
                transforms: described.transforms.clone(),
            };
            self.bag.write(self.tf, stamp_ns, &message)?;
        }
        self.bag.write(self.markers, stamp_ns, &described.markers)
    }

    /// The bag's bytes.
    pub fn finish(self) -> Result<Vec<u8>, mcap::McapError> {
        self.bag.finish()
    }
}

/// The image messages a [`CameraBag`] records: sensor_msgs/msg/Image and
/// sensor_msgs/msg/CompressedImage.
pub trait ImageMessage: RosType + Serialize {
    /// The type's ros2msg definition, as a bag's schema carries it.
    fn definition() -> String;
    /// The header's stamp, which the message is logged at.
    fn stamp(&self) -> Time;
}

impl ImageMessage for Image {
    fn definition() -> String {
        image_definition()
    }
    fn stamp(&self) -> Time {
        self.header.stamp
    }
}

impl ImageMessage for CompressedImage {
    fn definition() -> String {
        compressed_image_definition()
    }
    fn stamp(&self) -> Time {
        self.header.stamp
    }
}

/// A bag of what a camera driver publishes, as `ros2 bag record` stores
/// it: images of type `M` on one topic and sensor_msgs/msg/CameraInfo on
/// the topic beside it ([`crate::ros::camera_info_beside`]: where `whycode
/// detect` looks for the calibration), each message logged at its header's
/// stamp. Built in memory and written whole by the caller. Its chunks are
/// not compressed, as rosbag2 records by default: JPEG frames and sensor
/// noise gain nothing from it.
pub struct CameraBag<M> {
    bag: Ros2Bag,
    image: u16,
    info: u16,
    images: PhantomData<M>,
}

impl<M: ImageMessage> CameraBag<M> {
    /// An empty bag with the image topic `image_topic` and its camera_info.
    pub fn new(image_topic: &str) -> Result<CameraBag<M>, mcap::McapError> {
        let mut bag = Ros2Bag::new(mcap::WriteOptions::new().compression(None))?;
        let image = bag.channel::<M>(image_topic, &M::definition())?;
        let info = bag.channel::<CameraInfo>(
            &crate::ros::camera_info_beside(image_topic),
            &camera_info_definition(),
        )?;
        Ok(CameraBag {
            bag,
            image,
            info,
            images: PhantomData,
        })
    }

    /// Adds a camera_info (a driver sends one with every image, just
    /// before it).
    pub fn add_camera_info(&mut self, info: &CameraInfo) -> Result<(), mcap::McapError> {
        self.bag.write(self.info, info.header.stamp.nanos(), info)
    }

    /// Adds an image.
    pub fn add_image(&mut self, image: &M) -> Result<(), mcap::McapError> {
        self.bag.write(self.image, image.stamp().nanos(), image)
    }

    /// The bag's bytes.
    pub fn finish(self) -> Result<Vec<u8>, mcap::McapError> {
        self.bag.finish()
    }
}

/// An annotated video written by ffmpeg into a staged file, frame by frame
/// as they come: the frame rate follows the first two frames' stamps.
pub struct AnnotatedVideo {
    target: PathBuf,
    staged: PathBuf,
    ffmpeg: Option<Encoder>,
    first: Option<(image::RgbImage, i64)>,
    size: (u32, u32),
}

/// The ffmpeg filling the staged file: the program (held by
/// [`crate::io::StagedWriter`], which stops it if a signal ends the run),
/// its input and its messages.
struct Encoder {
    writer: crate::io::StagedWriter,
    input: ChildStdin,
    messages: ChildStderr,
}

impl AnnotatedVideo {
    /// A video for `target`, written into `staged` (a temporary file beside
    /// it, renamed by the caller once [`AnnotatedVideo::finish`] is done).
    pub fn new(target: &Path, staged: &Path) -> AnnotatedVideo {
        AnnotatedVideo {
            target: target.to_path_buf(),
            staged: staged.to_path_buf(),
            ffmpeg: None,
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
        if self.ffmpeg.is_none() {
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
        let mut command = Command::new(super::video::ffmpeg_program());
        command
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
            .stderr(Stdio::piped());
        let (writer, pipes) = crate::io::StagedWriter::spawn(&mut command, |child| {
            (child.stdin.take(), child.stderr.take())
        })
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => RecordingError::FfmpegMissing {
                path: self.target.clone(),
            },
            _ => self.fail(e),
        })?;
        let (Some(input), Some(messages)) = pipes else {
            unreachable!("ffmpeg's input and messages are piped");
        };
        self.ffmpeg = Some(Encoder {
            writer,
            input,
            messages,
        });
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
        let input = self.ffmpeg.as_mut().map(|f| &mut f.input);
        match input.map(|s| s.write_all(frame.as_raw())) {
            Some(Ok(())) => Ok(()),
            _ => Err(self
                .finish_child()
                .err()
                .unwrap_or_else(|| self.fail("ffmpeg stopped"))),
        }
    }

    fn finish_child(&mut self) -> Result<(), RecordingError> {
        let Some(Encoder {
            writer,
            input,
            mut messages,
        }) = self.ffmpeg.take()
        else {
            return Ok(());
        };
        drop(input);
        // ffmpeg closes its messages as it ends.
        let mut said = Vec::new();
        messages.read_to_end(&mut said).map_err(|e| self.fail(e))?;
        let status = writer.wait().map_err(|e| self.fail(e))?;
        if status.success() {
            Ok(())
        } else {
            let said = String::from_utf8_lossy(&said);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{ReadOptions, Recording};
    use crate::ros::msg::Header;

    fn header(stamp_ns: i64) -> Header {
        Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: "cam_optical".into(),
        }
    }

    /// A camera bag reads back through the bag reader: every frame with
    /// its stamp and pixels, the camera from its camera_info.
    #[test]
    fn a_camera_bag_reads_back_with_its_calibration() {
        let camera = crate::Camera {
            fx: 40.0,
            fy: 40.0,
            cx: 7.5,
            cy: 5.5,
            distortion: [-0.05, 0.0, 0.0, 0.0, 0.0],
            width: 16,
            height: 12,
        };
        let frame =
            |k: u8| image::GrayImage::from_fn(16, 12, |x, y| image::Luma([k + (x * y) as u8]));
        let stamp = |k: u8| 1_700_000_000_000_000_000 + i64::from(k) * 100_000_000;
        let dir = tempfile::tempdir().unwrap();

        let mut compressed =
            CameraBag::<CompressedImage>::new("/cam/image_raw/compressed").unwrap();
        let mut raw = CameraBag::<Image>::new("/cam/image_raw").unwrap();
        for k in 0..3 {
            let info = CameraInfo::from_camera(&camera, header(stamp(k)));
            compressed.add_camera_info(&info).unwrap();
            raw.add_camera_info(&info).unwrap();
            let png = crate::image_io::encode_image(Path::new("f.png"), &frame(k), 90).unwrap();
            compressed
                .add_image(&CompressedImage {
                    header: header(stamp(k)),
                    format: "png".into(),
                    data: png,
                })
                .unwrap();
            raw.add_image(&Image {
                header: header(stamp(k)),
                height: 12,
                width: 16,
                encoding: "mono8".into(),
                is_bigendian: 0,
                step: 16,
                data: frame(k).into_raw(),
            })
            .unwrap();
        }
        for (name, bytes) in [
            ("compressed.mcap", compressed.finish().unwrap()),
            ("raw.mcap", raw.finish().unwrap()),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let recording = Recording::open(&path).unwrap();
            let frames: Vec<_> = recording
                .frames(&ReadOptions::default())
                .unwrap()
                .map(Result::unwrap)
                .collect();
            assert_eq!(frames.len(), 3, "{name}");
            for (k, got) in (0..3).zip(&frames) {
                assert_eq!(got.stamp_ns, stamp(k), "{name}");
                assert_eq!(got.frame_id, "cam_optical");
                assert_eq!(got.image, frame(k), "{name}");
                assert_eq!(got.camera, Some(camera), "{name}");
            }
        }
    }
}
