//! The ROS 2 messages the node publishes and reads and that bags hold, as
//! serde structs whose field order is the `.msg` order: serialised as CDR
//! (ros2-client's on DDS, [`super::cdr`] in bags) they have the layout
//! every RMW puts on the wire. Each type names its ROS package and type
//! ([`RosType`]), from which the DDS type name
//! (`sensor_msgs::msg::dds_::Image_`) and a bag's schema name
//! (`sensor_msgs/msg/Image`) follow.
//!
//! `whycode_msgs` is ours (its `.msg` files ship in `ros2/whycode_msgs/`,
//! for colcon); `whycode_interfaces` is the original whycode-ros2 node's,
//! published on a compatibility topic only.

use serde::{Deserialize, Serialize};

/// A message type's ROS package and name.
pub trait RosType {
    /// ROS package, e.g. `sensor_msgs`.
    const PACKAGE: &'static str;
    /// Type name within the package, e.g. `Image`.
    const NAME: &'static str;

    /// The name a bag's schema carries: `sensor_msgs/msg/Image`.
    fn schema_name() -> String {
        format!("{}/msg/{}", Self::PACKAGE, Self::NAME)
    }
}

macro_rules! ros_type {
    ($type:ty, $package:literal, $name:literal) => {
        impl RosType for $type {
            const PACKAGE: &'static str = $package;
            const NAME: &'static str = $name;
        }
    };
}

/// builtin_interfaces/Time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

/// std_msgs/Header.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// When the data was captured.
    pub stamp: Time,
    /// The coordinate frame the data is in.
    pub frame_id: String,
}

/// sensor_msgs/Image.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// Stamp and camera frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel layout, e.g. `mono8`, `rgb8` (sensor_msgs/image_encodings).
    pub encoding: String,
    /// 1 when multi-byte channels are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step * height` bytes. Read and written in one piece (serde_bytes):
    /// as a plain sequence, each byte would pass through serde alone.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// sensor_msgs/CompressedImage.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and camera frame.
    pub header: Header,
    /// `jpeg`, `png`, or image_transport's `mono8; jpeg compressed mono8`.
    pub format: String,
    /// The encoded image.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// sensor_msgs/RegionOfInterest.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RegionOfInterest {
    /// Left column of the region.
    pub x_offset: u32,
    /// Top row of the region.
    pub y_offset: u32,
    /// Rows; 0 means the full image.
    pub height: u32,
    /// Columns; 0 means the full image.
    pub width: u32,
    /// True when the region is to be rectified.
    pub do_rectify: bool,
}

/// sensor_msgs/CameraInfo.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    /// Stamp and camera frame.
    pub header: Header,
    /// Image rows the calibration is for.
    pub height: u32,
    /// Image columns the calibration is for.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`.
    pub distortion_model: String,
    /// Distortion coefficients (k1, k2, p1, p2, k3, ... for plumb_bob).
    pub d: Vec<f64>,
    /// Intrinsic matrix, row-major: fx 0 cx; 0 fy cy; 0 0 1.
    pub k: [f64; 9],
    /// Rectification rotation, row-major.
    pub r: [f64; 9],
    /// Projection matrix of the rectified image, row-major 3x4.
    pub p: [f64; 12],
    /// Horizontal binning (0 or 1: none).
    pub binning_x: u32,
    /// Vertical binning.
    pub binning_y: u32,
    /// Part of the sensor the image shows.
    pub roi: RegionOfInterest,
}

/// geometry_msgs/Vector3.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// geometry_msgs/Point.
pub type Point = Vector3;

/// geometry_msgs/Quaternion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    /// The identity, as in the message's own default.
    fn default() -> Quaternion {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// geometry_msgs/Pose.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// geometry_msgs/Transform.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// geometry_msgs/TransformStamped.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The frame the transform leads to.
    pub child_frame_id: String,
    /// Child frame in the parent frame.
    pub transform: Transform,
}

/// tf2_msgs/TFMessage.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// whycode_msgs/Marker: one marker in one image (see ros2/README.md).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Family ID; 0 when unknown.
    pub id: u32,
    /// The member's code, when the ring decoded to one.
    pub code: u32,
    /// False when `code` means nothing.
    pub has_code: bool,
    /// Bit count the ring shows; 0 when not counted.
    pub bits: u8,
    /// How the ring decoded: `exact`, `corrected`, `ambiguous`, `rejected`,
    /// or empty for a legacy marker.
    pub status: String,
    /// Centre column, pixels (origin at the top-left pixel's centre).
    pub u: f64,
    /// Centre row, pixels.
    pub v: f64,
    /// Outer ellipse's semi-major axis, pixels.
    pub semi_major: f64,
    /// Outer ellipse's semi-minor axis, pixels.
    pub semi_minor: f64,
    /// Direction of the major axis in the image, radians, atan2(dv, du).
    pub axis_angle: f64,
    /// Direction of the marker's +x axis in the image, radians.
    pub yaw: f64,
    /// False when `yaw` means nothing (legacy marker, unreadable ring).
    pub has_yaw: bool,
    /// 0..1: how well the marker passed the tests.
    pub confidence: f64,
    /// Marker in the camera's optical frame (metres), when known.
    pub pose: Pose,
    /// False when `pose` means nothing (no camera_info, no size).
    pub has_pose: bool,
    /// Outer diameter the pose was computed for, metres; 0 without pose.
    pub diameter: f64,
    /// The /tf child frame published for this marker; empty when none.
    pub frame_id: String,
}

/// whycode_msgs/MarkerArray: every marker of one image.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The image's stamp and camera frame.
    pub header: Header,
    /// The markers, most confident first.
    pub markers: Vec<Marker>,
}

/// whycode_interfaces/Marker: the original whycode-ros2 node's marker.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompatMarker {
    /// ID (only 0..127 fit).
    pub id: i8,
    /// Size in pixels (the outer ellipse's area).
    pub size: i32,
    /// Centre column, pixels.
    pub u: f32,
    /// Centre row, pixels.
    pub v: f32,
    /// Rotation about the marker's normal (its image yaw), radians.
    pub angle: f32,
    /// Pose in the camera frame.
    pub position: Pose,
    /// Roll, pitch, yaw of the pose, radians.
    pub rotation: Vector3,
}

/// whycode_interfaces/MarkerArray.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompatMarkerArray {
    /// The image's stamp and camera frame.
    pub header: Header,
    /// The markers.
    pub markers: Vec<CompatMarker>,
}

ros_type!(Image, "sensor_msgs", "Image");
ros_type!(CompressedImage, "sensor_msgs", "CompressedImage");
ros_type!(CameraInfo, "sensor_msgs", "CameraInfo");
ros_type!(TfMessage, "tf2_msgs", "TFMessage");
ros_type!(MarkerArray, "whycode_msgs", "MarkerArray");
ros_type!(CompatMarkerArray, "whycode_interfaces", "MarkerArray");

impl Time {
    /// Nanoseconds since the epoch.
    pub fn nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The time `nanos` nanoseconds since the epoch ([`Time::nanos`] gives
    /// them back): the seconds rounded down, so `nanosec` stays in
    /// 0..1e9 before the epoch too, as ROS keeps it.
    pub fn from_nanos(nanos: i64) -> Time {
        Time {
            sec: nanos.div_euclid(1_000_000_000) as i32,
            nanosec: nanos.rem_euclid(1_000_000_000) as u32,
        }
    }
}

/// Why a camera_info describes no calibrated camera the library can use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraInfoError {
    /// No image size.
    #[error("camera_info has no image size ({width}x{height})")]
    NoImageSize {
        /// Its width, pixels.
        width: u32,
        /// Its height, pixels.
        height: u32,
    },
    /// Focal lengths that are not positive numbers, or a principal point
    /// that is not a number.
    #[error(
        "camera_info is not a calibration ({matrix} gives fx {fx}, fy {fy}, cx {cx}, cy {cy})"
    )]
    NotACalibration {
        /// The matrix they were read from: "K", or "P" for a rectified topic.
        matrix: &'static str,
        /// Focal length along x, pixels.
        fx: f64,
        /// Focal length along y, pixels.
        fy: f64,
        /// Principal point x, pixels.
        cx: f64,
        /// Principal point y, pixels.
        cy: f64,
    },
    /// Distortion coefficients that are not numbers.
    #[error("camera_info's distortion coefficients are not finite")]
    DistortionNotFinite,
    /// rational_polynomial with k4..k6 in use.
    #[error(
        "camera_info's rational_polynomial model uses k4..k6, which this node does not model \
         (plumb_bob does: k1, k2, p1, p2, k3)"
    )]
    RationalTerms,
    /// plumb_bob with another number of coefficients than 5.
    #[error("camera_info's plumb_bob model has {count} coefficients, not 5")]
    PlumbBobTerms {
        /// How many it has.
        count: usize,
    },
    /// A distortion model the library does not have.
    #[error("camera_info's distortion model '{model}' is not modelled (plumb_bob is)")]
    UnknownModel {
        /// The model's name.
        model: String,
    },
    /// A calibration no real lens gives.
    #[error("camera_info is not a real lens: {0}")]
    NotARealLens(crate::camera::ImplausibleCamera),
    /// A region of interest outside the image.
    #[error(
        "camera_info's region of interest {}x{}+{}+{} lies outside its {width}x{height} image",
        roi.width,
        roi.height,
        roi.x_offset,
        roi.y_offset
    )]
    RoiOutside {
        /// The region.
        roi: RegionOfInterest,
        /// The image's width, pixels.
        width: u32,
        /// The image's height, pixels.
        height: u32,
    },
}

impl CameraInfo {
    /// What a camera driver publishes for `camera` (a calibration file's
    /// content, as camera_info_manager sends it): K and plumb_bob's D, R
    /// the identity and P = K, as a calibration file without a rectified
    /// camera of its own has them. [`CameraInfo::camera`] gives `camera`
    /// back.
    pub fn from_camera(camera: &crate::Camera, header: Header) -> CameraInfo {
        let crate::Camera { fx, fy, cx, cy, .. } = *camera;
        CameraInfo {
            header,
            height: camera.height,
            width: camera.width,
            distortion_model: "plumb_bob".into(),
            d: camera.distortion.to_vec(),
            k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
            binning_x: 0,
            binning_y: 0,
            roi: RegionOfInterest::default(),
        }
    }

    /// The calibration of the images this camera_info describes: K and D
    /// (or, for a rectified image topic, P without distortion), cropped to
    /// its region of interest and scaled for its binning. A camera_info
    /// that describes no calibrated camera is refused with the reason.
    pub fn camera(&self, rectified: bool) -> Result<crate::Camera, CameraInfoError> {
        if self.width == 0 || self.height == 0 {
            return Err(CameraInfoError::NoImageSize {
                width: self.width,
                height: self.height,
            });
        }
        let [fx, fy, cx, cy] = if rectified {
            [self.p[0], self.p[5], self.p[2], self.p[6]]
        } else {
            [self.k[0], self.k[4], self.k[2], self.k[5]]
        };
        let matrix = if rectified { "P" } else { "K" };
        let finite = [fx, fy, cx, cy].iter().all(|v| v.is_finite());
        if !(finite && fx > 0.0 && fy > 0.0) {
            return Err(CameraInfoError::NotACalibration {
                matrix,
                fx,
                fy,
                cx,
                cy,
            });
        }
        let distortion = if rectified {
            [0.0; 5]
        } else {
            self.distortion()?
        };
        // ROS puts the principal point in the same pixel-centre convention
        // as OpenCV, which is the library's.
        let mut camera = crate::Camera {
            fx,
            fy,
            cx,
            cy,
            distortion,
            width: self.width,
            height: self.height,
        };
        // The checks a calibration file gets: a camera_info is used the same way.
        camera
            .check_plausible()
            .map_err(CameraInfoError::NotARealLens)?;
        let roi = self.roi;
        if roi.width != 0 && roi.height != 0 && (roi.width, roi.height) != (self.width, self.height)
        {
            if u64::from(roi.x_offset) + u64::from(roi.width) > u64::from(self.width)
                || u64::from(roi.y_offset) + u64::from(roi.height) > u64::from(self.height)
            {
                return Err(CameraInfoError::RoiOutside {
                    roi,
                    width: self.width,
                    height: self.height,
                });
            }
            camera.cx -= f64::from(roi.x_offset);
            camera.cy -= f64::from(roi.y_offset);
            camera.width = roi.width;
            camera.height = roi.height;
        }
        let (bx, by) = (self.binning_x.max(1), self.binning_y.max(1));
        if bx > 1 || by > 1 {
            camera = camera.with_resolution(camera.width / bx, camera.height / by);
        }
        Ok(camera)
    }

    /// plumb_bob's k1, k2, p1, p2, k3; the other models only when they
    /// reduce to it (rational_polynomial with k4..k6 zero, or no
    /// distortion at all).
    fn distortion(&self) -> Result<[f64; 5], CameraInfoError> {
        if self.d.iter().any(|k| !k.is_finite()) {
            return Err(CameraInfoError::DistortionNotFinite);
        }
        let mut k = [0.0; 5];
        for (dst, src) in k.iter_mut().zip(&self.d) {
            *dst = *src;
        }
        let extra = self.d.get(5..).unwrap_or(&[]);
        let none = self.d.iter().all(|&c| c == 0.0);
        match self.distortion_model.as_str() {
            _ if none => Ok([0.0; 5]),
            "plumb_bob" | "rational_polynomial" if extra.iter().all(|&c| c == 0.0) => Ok(k),
            "rational_polynomial" => Err(CameraInfoError::RationalTerms),
            "plumb_bob" => Err(CameraInfoError::PlumbBobTerms {
                count: self.d.len(),
            }),
            other => Err(CameraInfoError::UnknownModel {
                model: other.to_string(),
            }),
        }
    }
}

impl From<crate::Pose> for Pose {
    fn from(pose: crate::Pose) -> Pose {
        let [x, y, z, w] = pose.quaternion;
        Pose {
            position: Point {
                x: pose.position.x,
                y: pose.position.y,
                z: pose.position.z,
            },
            orientation: Quaternion { x, y, z, w },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cdr<T: Serialize>(value: &T) -> Vec<u8> {
        let bytes = super::super::cdr::encode(value);
        // A bag's message starts with the CDR encapsulation (little-endian
        // CDR: 00 01 00 00); the rest is what DDS puts on the wire.
        assert_eq!(bytes[..4], [0, 1, 0, 0]);
        bytes[4..].to_vec()
    }

    #[test]
    fn image_data_is_a_cdr_sequence_of_octets() {
        // Hand-written XCDR1 little-endian: the bytes a C++ node sends.
        let image = Image {
            header: Header {
                stamp: Time { sec: 7, nanosec: 9 },
                frame_id: "cam".into(),
            },
            height: 1,
            width: 3,
            encoding: "mono8".into(),
            is_bigendian: 0,
            step: 3,
            data: vec![1, 2, 3],
        };
        let mut expected = Vec::new();
        expected.extend(7i32.to_le_bytes());
        expected.extend(9u32.to_le_bytes());
        expected.extend(4u32.to_le_bytes()); // "cam\0"
        expected.extend(b"cam\0");
        expected.extend(1u32.to_le_bytes());
        expected.extend(3u32.to_le_bytes());
        expected.extend(6u32.to_le_bytes()); // "mono8\0"
        expected.extend(b"mono8\0");
        expected.push(0); // is_bigendian
        expected.push(0); // padding to 4
        expected.extend(3u32.to_le_bytes());
        expected.extend(3u32.to_le_bytes());
        expected.extend([1, 2, 3]);
        assert_eq!(cdr(&image), expected);
    }

    fn info() -> CameraInfo {
        let mut info = CameraInfo {
            width: 640,
            height: 480,
            distortion_model: "plumb_bob".into(),
            d: vec![-0.1, 0.01, 0.0, 0.0, 0.0],
            k: [500.0, 0.0, 319.5, 0.0, 510.0, 239.5, 0.0, 0.0, 1.0],
            ..CameraInfo::default()
        };
        info.p[0] = 480.0;
        info.p[5] = 490.0;
        info.p[2] = 320.0;
        info.p[6] = 240.0;
        info
    }

    #[test]
    fn camera_info_gives_the_calibration() {
        let camera = info().camera(false).unwrap();
        assert_eq!(
            (camera.fx, camera.fy, camera.cx, camera.cy),
            (500.0, 510.0, 319.5, 239.5)
        );
        assert_eq!(camera.distortion, [-0.1, 0.01, 0.0, 0.0, 0.0]);
        assert_eq!((camera.width, camera.height), (640, 480));
        let rectified = info().camera(true).unwrap();
        assert_eq!((rectified.fx, rectified.cx), (480.0, 320.0));
        assert!(!rectified.has_distortion());
    }

    #[test]
    fn a_camera_sent_as_camera_info_comes_back() {
        let camera = crate::Camera {
            fx: 520.0,
            fy: 521.5,
            cx: 319.2,
            cy: 241.7,
            distortion: [-0.1, 0.02, 0.001, -0.0005, 0.0],
            width: 640,
            height: 480,
        };
        let info = CameraInfo::from_camera(&camera, Header::default());
        assert_eq!(info.camera(false).unwrap(), camera);
        let stamp = Time::from_nanos(-1_500_000_000);
        assert_eq!(
            stamp,
            Time {
                sec: -2,
                nanosec: 500_000_000
            }
        );
        assert_eq!(stamp.nanos(), -1_500_000_000);
    }

    #[test]
    fn regions_of_interest_and_binning_are_applied() {
        let mut cropped = info();
        cropped.roi = RegionOfInterest {
            x_offset: 100,
            y_offset: 50,
            width: 320,
            height: 240,
            do_rectify: false,
        };
        let camera = cropped.camera(false).unwrap();
        assert_eq!((camera.cx, camera.cy), (219.5, 189.5));
        assert_eq!((camera.width, camera.height), (320, 240));
        let mut binned = info();
        binned.binning_x = 2;
        binned.binning_y = 2;
        let camera = binned.camera(false).unwrap();
        assert_eq!((camera.fx, camera.cx, camera.width), (250.0, 159.5, 320));
    }

    #[test]
    fn camera_infos_that_calibrate_nothing_are_refused() {
        let zeros = CameraInfo::default();
        assert!(zeros
            .camera(false)
            .unwrap_err()
            .to_string()
            .contains("no image size"));
        let uncalibrated = CameraInfo {
            width: 640,
            height: 480,
            ..CameraInfo::default()
        };
        assert!(uncalibrated
            .camera(false)
            .unwrap_err()
            .to_string()
            .contains("not a calibration"));
        let mut fisheye = info();
        fisheye.distortion_model = "equidistant".into();
        fisheye.d = vec![0.1, 0.0, 0.0, 0.0];
        assert!(fisheye
            .camera(false)
            .unwrap_err()
            .to_string()
            .contains("equidistant"));
        let mut rational = info();
        rational.distortion_model = "rational_polynomial".into();
        rational.d = vec![-0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert!(rational.camera(false).is_ok());
        rational.d[6] = 0.2;
        assert!(rational
            .camera(false)
            .unwrap_err()
            .to_string()
            .contains("k4..k6"));
        let mut outside = info();
        outside.roi.width = 600;
        outside.roi.height = 100;
        outside.roi.x_offset = 100;
        assert!(outside
            .camera(false)
            .unwrap_err()
            .to_string()
            .contains("outside"));
        let mut nan = info();
        nan.k[0] = f64::NAN;
        assert!(nan.camera(false).is_err());
    }

    #[test]
    fn schema_names_follow_the_ros_convention() {
        assert_eq!(Image::schema_name(), "sensor_msgs/msg/Image");
        assert_eq!(TfMessage::schema_name(), "tf2_msgs/msg/TFMessage");
        assert_eq!(MarkerArray::schema_name(), "whycode_msgs/msg/MarkerArray");
    }
}
