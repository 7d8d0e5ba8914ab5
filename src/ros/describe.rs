//! Detections as ROS messages: the marker array of one image and the
//! transforms it puts on /tf. The node publishes them; `whycode detect
//! --output run.mcap` writes them into a bag; both through [`describe`],
//! so a bag holds what the node would have sent for the same frames.

use super::msg::{Header, Marker, MarkerArray, Pose, Transform, TransformStamped, Vector3};
use crate::detect::Detection;

/// One image's detections as messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    /// Every marker, in the detector's order.
    pub markers: MarkerArray,
    /// Everything the frame puts on /tf, sent as one TFMessage: one
    /// transform per identified marker with a pose.
    pub transforms: Vec<TransformStamped>,
    /// Each marker's pose at its own diameter, in the markers' order.
    pub poses: Vec<Option<crate::Pose>>,
    /// Frames two markers of this image read as: /tf got the more
    /// confident one (for a front end to warn about).
    pub duplicate_frames: Vec<String>,
}

/// The detections of one image stamped with `header` (the image's stamp
/// and the camera frame). `tag(id)` names a marker's /tf frame (`None`
/// for ID 0, which gets none) and its printed diameter in metres, when
/// known; `computed_for` is the diameter the detector computed its poses
/// for, which scale with the diameter.
pub fn describe(
    detections: &[Detection],
    header: &Header,
    computed_for: Option<f64>,
    tag: impl Fn(u32) -> (Option<String>, Option<f64>),
) -> Described {
    let mut markers = Vec::with_capacity(detections.len());
    let mut poses = Vec::with_capacity(detections.len());
    let mut transforms: Vec<(f64, TransformStamped)> = Vec::new();
    let mut duplicate_frames = Vec::new();
    for d in detections {
        let (frame, size) = tag(d.id);
        let frame = frame.filter(|_| d.id != 0);
        let pose = match (d.pose, size, computed_for) {
            (Some(mut pose), Some(size), Some(computed)) => {
                pose.position *= size / computed;
                Some(pose)
            }
            _ => None,
        };
        let published_frame = match (&frame, pose) {
            (Some(frame), Some(pose)) => {
                let transform = TransformStamped {
                    header: header.clone(),
                    child_frame_id: frame.clone(),
                    transform: Transform {
                        translation: Vector3 {
                            x: pose.position.x,
                            y: pose.position.y,
                            z: pose.position.z,
                        },
                        rotation: Pose::from(pose).orientation,
                    },
                };
                match transforms
                    .iter_mut()
                    .find(|(_, t)| t.child_frame_id == *frame)
                {
                    Some(slot) => {
                        if !duplicate_frames.contains(frame) {
                            duplicate_frames.push(frame.clone());
                        }
                        if d.confidence > slot.0 {
                            *slot = (d.confidence, transform);
                        }
                    }
                    None => transforms.push((d.confidence, transform)),
                }
                frame.clone()
            }
            _ => String::new(),
        };
        poses.push(pose);
        markers.push(Marker {
            id: d.id,
            code: d.code.unwrap_or(0),
            has_code: d.code.is_some(),
            bits: d.bits.map_or(0, |b| b as u8),
            status: d
                .status
                .map(|s| format!("{s:?}").to_ascii_lowercase())
                .unwrap_or_default(),
            u: d.u,
            v: d.v,
            semi_major: d.axes[0],
            semi_minor: d.axes[1],
            axis_angle: d.angle,
            yaw: d.yaw.unwrap_or(0.0),
            has_yaw: d.yaw.is_some(),
            confidence: d.confidence,
            pose: pose.map(Pose::from).unwrap_or_default(),
            has_pose: pose.is_some(),
            diameter: if pose.is_some() {
                size.unwrap_or(0.0)
            } else {
                0.0
            },
            frame_id: published_frame,
        });
    }
    Described {
        markers: MarkerArray {
            header: header.clone(),
            markers,
        },
        transforms: transforms.into_iter().map(|(_, t)| t).collect(),
        poses,
        duplicate_frames,
    }
}
