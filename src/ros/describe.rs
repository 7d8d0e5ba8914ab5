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

/// A session's frame as messages (see [`describe`]), its /tf holding the
/// markers', then the boards' and, with an arena measured with a camera,
/// the arena's floor frame (named `arena_frame`): what the node publishes
/// and a detections bag records.
pub fn describe_frame(
    report: &crate::session::FrameReport,
    header: &Header,
    computed_for: Option<f64>,
    tag: impl Fn(u32) -> (Option<String>, Option<f64>),
    arena: Option<(&crate::arena::Arena, &str)>,
) -> Described {
    let mut described = describe(&report.markers, header, computed_for, tag);
    described
        .transforms
        .extend(board_transforms(&report.boards, header));
    if let Some((arena, frame)) = arena {
        described
            .transforms
            .extend(arena_transform(arena, header, frame));
    }
    described
}

/// The markers of `described` placed on the arena: the same markers in the
/// same order, each with its pose in the arena's floor frame (`frame`,
/// z up): position x, y, z in metres and the orientation a turn of its
/// yaw about z (identity for a marker without a heading); `has_pose`
/// false for a marker not placed. The camera-frame pose of `~/markers`
/// stays there, so this is a second array of the same type.
pub fn arena_markers(
    described: &MarkerArray,
    places: &[Option<crate::arena::ArenaPosition>],
    frame: &str,
) -> MarkerArray {
    let markers = described
        .markers
        .iter()
        .zip(places)
        .map(|(marker, place)| {
            let mut marker = marker.clone();
            match *place {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::{Arena, ArenaPosition, Mapping};
    use nalgebra::{Matrix3, Vector3 as V3};

    fn detection(id: u32) -> Detection {
        Detection {
            id,
            code: Some(7),
            u: 10.0,
            v: 20.0,
            yaw: Some(0.5),
            axes: [30.0, 29.0],
            angle: 0.0,
            confidence: 0.9,
            status: None,
            pose: None,
            bits: Some(8),
            unreadable: false,
            unnamed: None,
            track: None,
        }
    }

    fn header() -> Header {
        Header {
            stamp: super::super::msg::Time { sec: 5, nanosec: 6 },
            frame_id: "camera_optical".into(),
        }
    }

    #[test]
    fn arena_markers_keep_the_order_and_put_the_place_in_the_floor_frame() {
        let placed = ArenaPosition {
            x: 1.5,
            y: 0.25,
            z: 0.12,
            yaw: Some(std::f64::consts::FRAC_PI_2),
        };
        let detections = [detection(3), detection(4)];
        let described = describe(&detections, &header(), None, |_| (None, None));
        let on_floor = arena_markers(&described.markers, &[Some(placed), None], "arena");
        assert_eq!(on_floor.header.frame_id, "arena");
        assert_eq!(on_floor.header.stamp, described.markers.header.stamp);
        assert_eq!(on_floor.markers.len(), 2);
        let first = &on_floor.markers[0];
        assert!(first.has_pose && first.id == 3);
        assert_eq!(
            (
                first.pose.position.x,
                first.pose.position.y,
                first.pose.position.z
            ),
            (1.5, 0.25, 0.12)
        );
        // A quarter turn about z.
        let q = first.pose.orientation;
        assert!((q.z - 0.5f64.sqrt()).abs() < 1e-12 && (q.w - 0.5f64.sqrt()).abs() < 1e-12);
        assert!(!on_floor.markers[1].has_pose && on_floor.markers[1].id == 4);
    }

    #[test]
    fn the_floor_frame_is_a_transform_only_with_a_camera() {
        // A camera looking straight down at the floor 2.5 m below: the
        // floor's z (up) is the camera's −z, its x the camera's x.
        let rotation = Matrix3::from_diagonal(&V3::new(1.0, -1.0, -1.0));
        let camera = crate::Camera {
            fx: 1000.0,
            fy: 1000.0,
            cx: 640.0,
            cy: 480.0,
            distortion: [0.0; 5],
            width: 1280,
            height: 960,
        };
        let mut arena = Arena {
            ids: [1, 2, 3, 4],
            size_m: [2.0, 1.5],
            marker_height_m: 0.0,
            corner_error_m: 0.0,
            mapping: Mapping::Floor {
                camera,
                rotation,
                translation: V3::new(-1.0, 0.75, 2.5),
            },
        };
        let t = arena_transform(&arena, &header(), "arena").unwrap();
        assert_eq!(t.child_frame_id, "arena");
        assert_eq!(t.header, header());
        assert_eq!(
            (
                t.transform.translation.x,
                t.transform.translation.y,
                t.transform.translation.z
            ),
            (-1.0, 0.75, 2.5)
        );
        // Half a turn about x.
        let q = t.transform.rotation;
        assert!((q.x.abs() - 1.0).abs() < 1e-12 && q.w.abs() < 1e-12);
        arena.mapping = Mapping::Homography {
            width: 1280,
            height: 960,
            floor_to_image: Matrix3::identity(),
        };
        assert!(arena_transform(&arena, &header(), "arena").is_none());
    }
}
