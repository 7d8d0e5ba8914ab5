//! ROS 2 bags in MCAP: the image topic's messages in the bag's order (which
//! rosbag2 writes in log order), sensor_msgs/msg/Image through the same
//! conversion as the ROS 2 node ([`crate::ros::image`]) and
//! sensor_msgs/msg/CompressedImage (JPEG, PNG) through the library's image
//! decoder; the camera from the newest camera_info beside the image topic.

use super::{in_window, Frame, ReadOptions, RecordingError, Skipped, Window};
use crate::camera::Camera;
use crate::ros::msg::{CameraInfo, CompressedImage, Image, RosType};
use crate::ros::{camera_info_beside, cdr};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// An MCAP file mapped into memory, with its channels.
pub struct Bag {
    path: PathBuf,
    bytes: memmap2::Mmap,
    /// Every channel: topic, schema name and message count (when the
    /// summary has statistics).
    channels: Vec<ChannelInfo>,
}

#[derive(Debug, Clone)]
struct ChannelInfo {
    topic: String,
    schema: String,
    messages: Option<u64>,
}

impl ChannelInfo {
    fn is_image(&self) -> bool {
        self.schema == Image::schema_name() || self.schema == CompressedImage::schema_name()
    }
}

impl Bag {
    /// The bag's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Maps the bag and reads its summary (or, for a bag written without
    /// one, walks its records once for the channels).
    pub fn open(path: &Path) -> Result<Bag, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = super::open_file(path)?;
        // SAFETY: the map is only read; a bag changed by another process
        // while mapped can give wrong frames, not undefined behaviour in
        // safe code that copies out of it (the MCAP reader checks lengths).
        let bytes = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        let corrupt = |e: mcap::McapError| RecordingError::CorruptBag {
            path: path.to_path_buf(),
            problem: e.to_string(),
        };
        let summary = mcap::Summary::read(&bytes).map_err(corrupt)?;
        let channels = match summary {
            Some(summary) => {
                let counts = summary.stats.as_ref().map(|s| &s.channel_message_counts);
                let mut channels: Vec<ChannelInfo> = summary
                    .channels
                    .values()
                    .map(|c| ChannelInfo {
                        topic: c.topic.clone(),
                        schema: c
                            .schema
                            .as_ref()
                            .map(|s| s.name.clone())
                            .unwrap_or_default(),
                        messages: counts.and_then(|m| m.get(&c.id).copied()),
                    })
                    .collect();
                channels.sort_by(|a, b| a.topic.cmp(&b.topic));
                channels
            }
            None => {
                let mut seen: BTreeMap<String, ChannelInfo> = BTreeMap::new();
                for message in mcap::MessageStream::new(&bytes).map_err(corrupt)? {
                    let message = message.map_err(corrupt)?;
                    seen.entry(message.channel.topic.clone())
                        .or_insert_with(|| ChannelInfo {
                            topic: message.channel.topic.clone(),
                            schema: message
                                .channel
                                .schema
                                .as_ref()
                                .map(|s| s.name.clone())
                                .unwrap_or_default(),
                            messages: None,
                        });
                }
                seen.into_values().collect()
            }
        };
        Ok(Bag {
            path: path.to_path_buf(),
            bytes,
            channels,
        })
    }

    /// The image topics, named with their type.
    pub fn image_topics(&self) -> Vec<String> {
        self.channels
            .iter()
            .filter(|c| c.is_image())
            .map(|c| c.topic.clone())
            .collect()
    }

    /// The frames of the image topic `options` names (or of the bag's one
    /// image topic).
    pub fn frames(&self, options: &ReadOptions) -> Result<BagFrames<'_>, RecordingError> {
        let images: Vec<&ChannelInfo> = self.channels.iter().filter(|c| c.is_image()).collect();
        let described = |c: &&ChannelInfo| format!("{} ({})", c.topic, c.schema);
        let chosen = match &options.topic {
            Some(topic) if !images.is_empty() => *images
                .iter()
                .find(|c| c.topic == *topic)
                .ok_or_else(|| RecordingError::UnknownTopic {
                    path: self.path.clone(),
                    topic: topic.clone(),
                    topics: images.iter().map(described).collect(),
                })?,
            _ => match images.as_slice() {
                [one] => *one,
                [] => {
                    return Err(RecordingError::NoImageTopic {
                        path: self.path.clone(),
                        topics: self
                            .channels
                            .iter()
                            .map(|c| format!("{} ({})", c.topic, c.schema))
                            .collect(),
                    })
                }
                _ => {
                    return Err(RecordingError::SeveralImageTopics {
                        path: self.path.clone(),
                        topics: images.iter().map(described).collect(),
                    })
                }
            },
        };
        let stream =
            mcap::MessageStream::new(&self.bytes).map_err(|e| RecordingError::CorruptBag {
                path: self.path.clone(),
                problem: e.to_string(),
            })?;
        let info_topic = camera_info_beside(&chosen.topic);
        Ok(BagFrames {
            path: &self.path,
            stream,
            rectified: chosen
                .topic
                .rsplit('/')
                .find(|part| *part != "compressed")
                .is_some_and(|name| name.starts_with("image_rect")),
            topic: chosen.topic.clone(),
            info_topic,
            expected: chosen.messages.map(|n| n.div_ceil(options.every)),
            options: options.clone(),
            messages: 0,
            in_window: 0,
            first_stamp: None,
            camera: None,
            skipped: Skipped::default(),
            done: false,
        })
    }
}

/// The frames of one image topic, in the bag's order.
pub struct BagFrames<'a> {
    path: &'a Path,
    stream: mcap::MessageStream<'a>,
    topic: String,
    info_topic: String,
    /// The topic carries rectified images (`image_rect*`): camera_info's
    /// P, not K and D, describes them.
    rectified: bool,
    expected: Option<u64>,
    options: ReadOptions,
    /// Image messages seen on the topic.
    messages: u64,
    /// Frames inside the time window so far (the stream's index).
    in_window: u64,
    first_stamp: Option<i64>,
    camera: Option<Camera>,
    skipped: Skipped,
    done: bool,
}

impl BagFrames<'_> {
    /// The topic's message count over the thinning, when the bag says.
    pub fn expected(&self) -> Option<u64> {
        self.expected
    }

    /// CompressedImages that did not decode.
    pub fn skipped(&self) -> &Skipped {
        &self.skipped
    }

    fn bad_message(&self, message: u64, problem: impl ToString) -> RecordingError {
        RecordingError::BadMessage {
            path: self.path.to_path_buf(),
            topic: self.topic.clone(),
            message,
            problem: problem.to_string(),
        }
    }

    /// The next message of the image topic, decoded to grey pixels, or a
    /// frame skipped; `None` at the end.
    fn next_frame(&mut self) -> Result<Option<Frame>, RecordingError> {
        while let Some(message) = self.stream.next() {
            let message = message.map_err(|e| RecordingError::CorruptBag {
                path: self.path.to_path_buf(),
                problem: e.to_string(),
            })?;
            let channel = &message.channel;
            let schema = channel.schema.as_ref().map(|s| s.name.as_str());
            if channel.topic == self.info_topic && schema == Some(&CameraInfo::schema_name()) {
                let info: CameraInfo =
                    cdr::decode(&message.data).map_err(|e| RecordingError::BadMessage {
                        path: self.path.to_path_buf(),
                        topic: self.info_topic.clone(),
                        message: 0,
                        problem: e.to_string(),
                    })?;
                // An invalid calibration leaves the previous one in place,
                // as in the node, and is counted for the summary.
                match info.camera(self.rectified) {
                    Ok(camera) => self.camera = Some(camera),
                    Err(reason) => {
                        self.skipped.refused_calibrations += 1;
                        self.skipped
                            .first_refused_calibration
                            .get_or_insert_with(|| reason.to_string());
                    }
                }
                continue;
            }
            if channel.topic != self.topic {
                continue;
            }
            let number = self.messages;
            self.messages += 1;
            let raw = schema == Some(&Image::schema_name());
            let (header, pixels) = if raw {
                let msg: Image =
                    cdr::decode(&message.data).map_err(|e| self.bad_message(number, e))?;
                (msg.header.clone(), Pixels::Raw(msg))
            } else {
                let msg: CompressedImage =
                    cdr::decode(&message.data).map_err(|e| self.bad_message(number, e))?;
                (msg.header.clone(), Pixels::Compressed(msg))
            };
            let stamp_ns = header.stamp.nanos();
            let first = *self.first_stamp.get_or_insert(stamp_ns);
            match in_window(&self.options, stamp_ns - first) {
                Window::Before => continue,
                Window::After => return Ok(None),
                Window::In => {}
            }
            let index = self.in_window;
            self.in_window += 1;
            if !index.is_multiple_of(self.options.every) {
                continue;
            }
            let mut converter = crate::ros::image::Converter::default();
            let image = match &pixels {
                Pixels::Raw(msg) => converter
                    .gray(msg)
                    .map(|view| {
                        image::GrayImage::from_raw(view.width(), view.height(), view.to_vec())
                            .expect("a whole image")
                    })
                    .map_err(|problem| RecordingError::BadImage {
                        path: self.path.to_path_buf(),
                        topic: self.topic.clone(),
                        frame: index,
                        problem,
                    })?,
                Pixels::Compressed(msg) => match converter.gray_compressed(msg, &self.topic) {
                    Ok(gray) => gray,
                    Err(crate::ros::image::FrameError::Undecodable(reason)) => {
                        self.skipped.add(index, reason);
                        continue;
                    }
                    Err(problem) => {
                        return Err(RecordingError::BadImage {
                            path: self.path.to_path_buf(),
                            topic: self.topic.clone(),
                            frame: index,
                            problem,
                        })
                    }
                },
            };
            return Ok(Some(Frame {
                index,
                stamp_ns,
                topic: Some(self.topic.clone()),
                frame_id: header.frame_id,
                image,
                camera: self.camera,
            }));
        }
        Ok(None)
    }
}

enum Pixels {
    Raw(Image),
    Compressed(CompressedImage),
}

impl Iterator for BagFrames<'_> {
    type Item = Result<Frame, RecordingError>;

    fn next(&mut self) -> Option<Self::Item> {
        let mut done = self.done;
        let result = super::fused(&mut done, || self.next_frame());
        self.done = done;
        result
    }
}
