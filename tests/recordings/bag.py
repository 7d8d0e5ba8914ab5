"""The integration tests' independent MCAP writer and reader: PyPI's mcap and
mcap-ros2-support, not whycode's Rust code.

    bag.py write SPEC.json   writes the bag SPEC describes
    bag.py read BAG.mcap     prints each message as a JSON line

SPEC: {"path": "...", "messages": [{"topic", "type", "log_time", ...fields}]}
where an image's "data_file" names a file holding its data bytes.
"""

import json
import sys

from mcap_ros2.reader import read_ros2_messages
from mcap_ros2.writer import Writer

SEPARATOR = "\n" + "=" * 80 + "\n"
HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id"
TIME = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec"
ROI = (
    "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\n"
    "uint32 height\nuint32 width\nbool do_rectify"
)

DEFINITIONS = {
    "sensor_msgs/msg/Image": SEPARATOR.join(
        [
            "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
            "uint8 is_bigendian\nuint32 step\nuint8[] data",
            HEADER,
            TIME,
        ]
    ),
    "sensor_msgs/msg/CompressedImage": SEPARATOR.join(
        ["std_msgs/Header header\nstring format\nuint8[] data", HEADER, TIME]
    ),
    "sensor_msgs/msg/CameraInfo": SEPARATOR.join(
        [
            "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
            "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
            "uint32 binning_y\nsensor_msgs/RegionOfInterest roi",
            HEADER,
            TIME,
            ROI,
        ]
    ),
    "std_msgs/msg/String": "string data",
}


def header(message):
    stamp = message["stamp_ns"]
    return {
        "stamp": {"sec": stamp // 1_000_000_000, "nanosec": stamp % 1_000_000_000},
        "frame_id": message.get("frame_id", "camera"),
    }


def body(message):
    kind = message["type"]
    if kind == "std_msgs/msg/String":
        return {"data": message["data"]}
    fields = {"header": header(message)}
    if "data_file" in message:
        with open(message["data_file"], "rb") as f:
            fields["data"] = f.read()
    if kind == "sensor_msgs/msg/Image":
        for key in ("height", "width", "encoding", "is_bigendian", "step"):
            fields[key] = message[key]
    elif kind == "sensor_msgs/msg/CompressedImage":
        fields["format"] = message["format"]
    elif kind == "sensor_msgs/msg/CameraInfo":
        fields.update(
            {
                "height": message["height"],
                "width": message["width"],
                "distortion_model": "plumb_bob",
                "d": [0.0] * 5,
                "k": message["k"],
                "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                "p": message["p"],
                "binning_x": 0,
                "binning_y": 0,
                "roi": {
                    "x_offset": 0,
                    "y_offset": 0,
                    "height": 0,
                    "width": 0,
                    "do_rectify": False,
                },
            }
        )
    return fields


def write(spec_path):
    with open(spec_path) as f:
        spec = json.load(f)
    with open(spec["path"], "wb") as out:
        writer = Writer(out)
        schemas = {}
        for sequence, message in enumerate(spec["messages"]):
            kind = message["type"]
            if kind not in schemas:
                schemas[kind] = writer.register_msgdef(kind, DEFINITIONS[kind])
            writer.write_message(
                topic=message["topic"],
                schema=schemas[kind],
                message=body(message),
                log_time=message["log_time"],
                publish_time=message["log_time"],
                sequence=sequence,
            )
        writer.finish()


def plain(value):
    """A decoded message as JSON values."""
    if isinstance(value, (bytes, bytearray)):
        return len(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "__slots__") or hasattr(value, "__dict__"):
        names = getattr(value, "__slots__", None) or vars(value).keys()
        return {n: plain(getattr(value, n)) for n in names if not n.startswith("_")}
    return value


def read(bag_path):
    for m in read_ros2_messages(bag_path):
        print(
            json.dumps(
                {
                    "topic": m.channel.topic,
                    "schema": m.schema.name,
                    "log_time": m.log_time_ns,
                    "message": plain(m.ros_msg),
                }
            )
        )


if __name__ == "__main__":
    {"write": write, "read": read}[sys.argv[1]](sys.argv[2])
