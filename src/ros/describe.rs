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

fn transform(
    header: &Header,
    child: &str,
    position: nalgebra::Vector3<f64>,
    [x, y, z, w]: [f64; 4],
) -> TransformStamped {
    TransformStamped {
        header: header.clone(),
        child_frame_id: child.to_string(),
        transform: Transform {
            translation: Vector3 {
                x: position.x,
                y: position.y,
                z: position.z,
            },
            rotation: super::msg::Quaternion { x, y, z, w },
        },
    }
}

/// Each board's pose as a transform from the camera frame (`header`'s) to
/// a frame named after the board; they join the markers' in one TFMessage.
pub fn board_transforms(
    boards: &[crate::board::BoardPose],
    header: &Header,
) -> Vec<TransformStamped> {
    boards
        .iter()
        .map(|b| transform(header, &b.name, b.position, b.quaternion))
        .collect()
}

/// The arena's floor frame as a transform from the camera frame to
/// `frame`, for an arena measured with a camera (one measured without
/// maps the image to the floor and has no pose in the camera's frame).
pub fn arena_transform(
    arena: &crate::arena::Arena,
    header: &Header,
    frame: &str,
) -> Option<TransformStamped> {
    let crate::arena::Mapping::Floor {
        rotation,
        translation,
        ..
    } = &arena.mapping
    else {
        return None;
    };
    let q = nalgebra::UnitQuaternion::from_matrix(rotation);
    let w_sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    let q = [q.i, q.j, q.k, q.w].map(|c| c * w_sign);
    Some(transform(header, frame, *translation, q))
}

/// The markers of `described` placed on the arena: the same markers in the
/// same order, each with its pose in the arena's floor frame (`frame`,
/// z up): position x, y, z in metres and the orientation a turn of its
/// yaw about z (identity for a marker without a heading); `has_pose`
/// false for a marker not placed. The camera-frame pose of `~/markers`
/// stays there, so this is a second array of the same type.
pub fn arena_markers(
    described: &MarkerArray,
    detections: &[Detection],
    frame: &str,
) -> MarkerArray {
    let markers = described
        .markers
        .iter()
        .zip(detections)
        .map(|(marker, d)| {
            let mut marker = marker.clone();
            match d.arena {
                Some(at) => {
                    let half = at.yaw.unwrap_or(0.0) / 2.0;
                    marker.pose = Pose {
                        position: Vector3 {
                            x: at.x,
                            y: at.y,
                            z: at.z,
                        },
                        orientation: super::msg::Quaternion {
                            x: 0.0,
                            y: 0.0,
                            z: half.sin(),
                            w: half.cos(),
                        },
                    };
                    marker.has_pose = true;
                }
                None => {
                    marker.pose = Pose::default();
                    marker.has_pose = false;
                }
            }
            marker
        })
        .collect();
    MarkerArray {
        header: Header {
            stamp: described.header.stamp,
            frame_id: frame.to_string(),
        },
        markers,
    }
}
