"""The ROS 2 wire types the peer exchanges with whycode_node, declared for
CycloneDDS as rosidl would generate them: DDS type `pkg::msg::dds_::Type_`,
fields in .msg order. The peer knows nothing of the node's Rust code."""

from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import _machinery
from cyclonedds.idl.types import (
    array,
    float32,
    float64,
    int8,
    int32,
    int64,
    sequence,
    uint8,
    uint32,
)


# CycloneDDS's Python binding packs a sequence<uint8> through struct with
# one argument per byte (45 ms for a 640x480 image). The same bytes on the
# wire, in one copy: a length, then the octets; read back as `bytes`.
_Octets = _machinery.PlainCdrV2SequenceOfPrimitiveMachine
_plain_serialize = _Octets.serialize
_plain_deserialize = _Octets.deserialize


def _serialize(self, buffer, value, *args, **kwargs):
    if self.code == "B" and isinstance(value, (bytes, bytearray, memoryview)):
        assert self.max_length is None or len(value) <= self.max_length
        buffer.align(4)
        buffer.write("I", 4, len(value))
        buffer.write_bytes(bytes(value))
        return
    _plain_serialize(self, buffer, value, *args, **kwargs)


def _deserialize(self, buffer, *args, **kwargs):
    if self.code == "B":
        buffer.align(4)
        return buffer.read_bytes(buffer.read("I", 4))
    return _plain_deserialize(self, buffer, *args, **kwargs)


_Octets.serialize = _serialize
_Octets.deserialize = _deserialize


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header = field(default_factory=Header)
    height: uint32 = 0
    width: uint32 = 0
    encoding: str = ""
    is_bigendian: uint8 = 0
    step: uint32 = 0
    data: sequence[uint8] = field(default_factory=bytes)


@dataclass
class CompressedImage(IdlStruct, typename="sensor_msgs::msg::dds_::CompressedImage_"):
    header: Header = field(default_factory=Header)
    format: str = ""
    data: sequence[uint8] = field(default_factory=bytes)


@dataclass
class RegionOfInterest(IdlStruct, typename="sensor_msgs::msg::dds_::RegionOfInterest_"):
    x_offset: uint32 = 0
    y_offset: uint32 = 0
    height: uint32 = 0
    width: uint32 = 0
    do_rectify: bool = False


@dataclass
class CameraInfo(IdlStruct, typename="sensor_msgs::msg::dds_::CameraInfo_"):
    header: Header = field(default_factory=Header)
    height: uint32 = 0
    width: uint32 = 0
    distortion_model: str = ""
    d: sequence[float64] = field(default_factory=list)
    k: array[float64, 9] = field(default_factory=lambda: [0.0] * 9)
    r: array[float64, 9] = field(default_factory=lambda: [0.0] * 9)
    p: array[float64, 12] = field(default_factory=lambda: [0.0] * 12)
    binning_x: uint32 = 0
    binning_y: uint32 = 0
    roi: RegionOfInterest = field(default_factory=RegionOfInterest)


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped] = field(default_factory=list)


# whycode_msgs, as ros2/whycode_msgs/msg/*.msg define them.
@dataclass
class Marker(IdlStruct, typename="whycode_msgs::msg::dds_::Marker_"):
    id: uint32 = 0
    code: uint32 = 0
    has_code: bool = False
    bits: uint8 = 0
    status: str = ""
    u: float64 = 0.0
    v: float64 = 0.0
    semi_major: float64 = 0.0
    semi_minor: float64 = 0.0
    axis_angle: float64 = 0.0
    yaw: float64 = 0.0
    has_yaw: bool = False
    confidence: float64 = 0.0
    pose: Pose = field(default_factory=Pose)
    has_pose: bool = False
    diameter: float64 = 0.0
    frame_id: str = ""


@dataclass
class MarkerArray(IdlStruct, typename="whycode_msgs::msg::dds_::MarkerArray_"):
    header: Header = field(default_factory=Header)
    markers: sequence[Marker] = field(default_factory=list)


# whycode_interfaces, the original whycode-ros2 node's package.
@dataclass
class CompatMarker(IdlStruct, typename="whycode_interfaces::msg::dds_::Marker_"):
    id: int8 = 0
    size: int32 = 0
    u: float32 = 0.0
    v: float32 = 0.0
    angle: float32 = 0.0
    position: Pose = field(default_factory=Pose)
    rotation: Vector3 = field(default_factory=Vector3)


@dataclass
class CompatMarkerArray(IdlStruct, typename="whycode_interfaces::msg::dds_::MarkerArray_"):
    header: Header = field(default_factory=Header)
    markers: sequence[CompatMarker] = field(default_factory=list)


# rcl_interfaces: the parameter service `ros2 param set` calls.
@dataclass
class ParameterValue(IdlStruct, typename="rcl_interfaces::msg::dds_::ParameterValue_"):
    type: uint8 = 0
    bool_value: bool = False
    integer_value: int64 = 0
    double_value: float64 = 0.0
    string_value: str = ""
    byte_array_value: sequence[uint8] = field(default_factory=list)
    bool_array_value: sequence[bool] = field(default_factory=list)
    integer_array_value: sequence[int64] = field(default_factory=list)
    double_array_value: sequence[float64] = field(default_factory=list)
    string_array_value: sequence[str] = field(default_factory=list)


@dataclass
class Parameter(IdlStruct, typename="rcl_interfaces::msg::dds_::Parameter_"):
    name: str = ""
    value: ParameterValue = field(default_factory=ParameterValue)


@dataclass
class SetParametersRequest(
    IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Request_"
):
    parameters: sequence[Parameter] = field(default_factory=list)


@dataclass
class SetParametersResult(
    IdlStruct, typename="rcl_interfaces::msg::dds_::SetParametersResult_"
):
    successful: bool = False
    reason: str = ""


@dataclass
class SetParametersResponse(
    IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Response_"
):
    results: sequence[SetParametersResult] = field(default_factory=list)


@dataclass
class GetParametersRequest(
    IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Request_"
):
    names: sequence[str] = field(default_factory=list)


@dataclass
class GetParametersResponse(
    IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Response_"
):
    values: sequence[ParameterValue] = field(default_factory=list)


# rcl_interfaces/msg/ParameterType
PARAMETER_BOOL = 1
PARAMETER_INTEGER = 2
PARAMETER_DOUBLE = 3
PARAMETER_STRING = 4
