"""The independent ROS 2 peer: CycloneDDS (PyPI `cyclonedds`) speaking the
ROS 2 wire types of ros2_types.py on the DDS topics ROS 2 maps its topics
to (`/camera/image_raw` is `rt/camera/image_raw`), plus helpers to run
whycode_node and to make simulated frames with their ground truth."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros2_types as t

# Camera drivers publish best effort with a short history ("sensor data").
SENSOR_QOS = Qos(
    Policy.Reliability.BestEffort,
    Policy.History.KeepLast(5),
    Policy.Durability.Volatile,
)
# tf2 listeners: reliable, volatile, keep last 100.
TF_QOS = Qos(
    Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
    Policy.History.KeepLast(100),
    Policy.Durability.Volatile,
)
RELIABLE_QOS = Qos(
    Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
    Policy.History.KeepLast(100),
    Policy.Durability.Volatile,
)


def dds_topic(ros_name: str, prefix: str = "rt") -> str:
    """`/camera/image_raw` -> `rt/camera/image_raw`."""
    return prefix + ros_name


class Peer:
    """One CycloneDDS participant on a domain, with writers and readers
    made on demand."""

    def __init__(self, domain: int):
        self.domain = domain
        self.dp = DomainParticipant(domain)
        self._topics: dict[tuple[str, type], Topic] = {}
        self._writers: dict[tuple[str, type], DataWriter] = {}
        self._readers: dict[tuple[str, type], DataReader] = {}
        self._received: dict[tuple[str, type], list] = {}

    def topic(self, name: str, kind: type) -> Topic:
        key = (name, kind)
        if key not in self._topics:
            self._topics[key] = Topic(self.dp, name, kind)
        return self._topics[key]

    def writer(self, name: str, kind: type, qos: Qos = SENSOR_QOS) -> DataWriter:
        key = (name, kind)
        if key not in self._writers:
            self._writers[key] = DataWriter(self.dp, self.topic(name, kind), qos=qos)
        return self._writers[key]

    def reader(self, name: str, kind: type, qos: Qos = RELIABLE_QOS) -> DataReader:
        key = (name, kind)
        if key not in self._readers:
            self._readers[key] = DataReader(self.dp, self.topic(name, kind), qos=qos)
        return self._readers[key]

    def wait_matched(self, *entities, timeout: float = 15.0, settle: float = 0.3) -> None:
        """Until each writer has a reader (or reader a writer) on the other
        side, and then `settle` seconds more: discovery is two-sided, and
        the node may learn of the peer's endpoints a little after the peer
        learns of the node's (what a writer sends to a reader it does not
        know yet is lost)."""
        deadline = time.monotonic() + timeout
        for entity in entities:
            while not matched(entity):
                if time.monotonic() > deadline:
                    raise TimeoutError(f"no match on {entity.topic.name} within {timeout} s")
                time.sleep(0.02)
        time.sleep(settle)

    def close(self) -> None:
        """Deletes the participant: the node sees its writers and readers go."""
        self._writers.clear()
        self._readers.clear()
        self._topics.clear()
        self._received.clear()
        self.dp = None

    def received(self, name: str, kind: type, qos: Qos = RELIABLE_QOS) -> list:
        """Everything read on a topic so far (new samples taken first)."""
        box = self._received.setdefault((name, kind), [])
        box.extend(take_all(self.reader(name, kind, qos)))
        return box

    def find(self, name: str, kind: type, match, timeout: float = 5.0, qos: Qos = RELIABLE_QOS):
        """The first sample read on a topic that `match` accepts, waiting up
        to `timeout` seconds; None if none came."""
        deadline = time.monotonic() + timeout
        checked = 0
        while True:
            box = self.received(name, kind, qos)
            for sample in box[checked:]:
                if match(sample):
                    return sample
            checked = len(box)
            if time.monotonic() > deadline:
                return None
            time.sleep(0.0002)


def matched(entity) -> int:
    """How many readers a writer (or writers a reader) has on the other side."""
    if isinstance(entity, DataWriter):
        return entity.get_publication_matched_status().current_count
    return entity.get_subscription_matched_status().current_count


def take_all(reader: DataReader) -> list:
    return [s for s in reader.take(N=1000) if not _is_invalid(s)]


def _is_invalid(sample) -> bool:
    # CycloneDDS hands out "invalid" samples (dispose/unregister notices)
    # as InvalidSample objects.
    return type(sample).__name__ == "InvalidSample"


def wait_for(reader: DataReader, match, timeout: float = 5.0):
    """The first sample taken from `reader` that `match` accepts (others
    are dropped); None after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for sample in take_all(reader):
            if match(sample):
                return sample
        time.sleep(0.0005)
    return None


def stamp_of(header: t.Header) -> tuple[int, int]:
    return (header.stamp.sec, header.stamp.nanosec)


@dataclass
class Answer:
    """What the node published for one frame."""

    markers: t.MarkerArray | None
    transforms: list  # TransformStamped of this frame
    latency_ms: float | None  # from the frame's write returning to its /tf read

    def tf(self) -> dict[str, t.TransformStamped]:
        return {x.child_frame_id: x for x in self.transforms}


class Rig:
    """The peer's side of one camera and the node reading it: writes frames
    and camera_info, reads /tf and the node's ~/markers."""

    def __init__(
        self,
        peer: Peer,
        camera: str = "/camera",
        node: str = "/whycode",
        frame_id: str = "camera_optical",
        compressed: bool = False,
    ):
        self.peer = peer
        self.frame_id = frame_id
        self.markers_topic = f"rt{node}/markers"
        image = f"rt{camera}/image_raw"
        if compressed:
            self.images = peer.writer(image + "/compressed", t.CompressedImage)
        else:
            self.images = peer.writer(image, t.Image)
        self.infos = peer.writer(f"rt{camera}/camera_info", t.CameraInfo)
        self.tf_reader = peer.reader("rt/tf", t.TFMessage, TF_QOS)
        self.markers_reader = peer.reader(self.markers_topic, t.MarkerArray)

    def ready(self, calibration: "Scene | None" = None, timeout: float = 15.0) -> "Rig":
        """Waits until the node's readers and writers are matched; with a
        scene, also gives the node its camera_info ahead of the first frame
        (the two topics are not ordered against each other)."""
        self.peer.wait_matched(
            self.images, self.infos, self.tf_reader, self.markers_reader, timeout=timeout
        )
        if calibration is not None:
            self.infos.write(calibration.camera_info(self.frame_id))
            time.sleep(0.05)
        return self

    def send(
        self,
        scene: Scene | None,
        stamp: tuple[int, int],
        encoding: str = "mono8",
        info: t.CameraInfo | None | bool = True,
        message=None,
        expect_tf: bool = True,
        timeout: float = 5.0,
    ) -> Answer:
        """Writes a frame (the scene in `encoding`, or `message` as given)
        after its camera_info, and waits for the node's answer to it."""
        if info is True:
            info = scene.camera_info(self.frame_id)
        if info:
            info.header.stamp = t.Time(sec=stamp[0], nanosec=stamp[1])
            self.infos.write(info)
        if message is None:
            if encoding in ("png", "jpeg"):
                message = compressed_message(scene, stamp, encoding, self.frame_id)
            else:
                message = image_message(scene, stamp, self.frame_id, encoding)
        self.images.write(message)
        sent = time.monotonic()
        parent = message.header.frame_id
        tf = None
        if expect_tf:
            tf = self.peer.find(
                "rt/tf",
                t.TFMessage,
                lambda m: any(
                    stamp_of(x.header) == stamp and x.header.frame_id == parent
                    for x in m.transforms
                ),
                timeout,
                TF_QOS,
            )
        latency = (time.monotonic() - sent) * 1e3 if tf is not None else None
        markers = self.peer.find(
            self.markers_topic,
            t.MarkerArray,
            lambda m: stamp_of(m.header) == stamp,
            timeout if expect_tf else timeout / 2,
        )
        transforms = [x for x in (tf.transforms if tf else []) if stamp_of(x.header) == stamp]
        return Answer(markers, transforms, latency)

    def silence(self, stamp: tuple[int, int], wait: float = 0.3) -> bool:
        """True if the node published nothing for `stamp` within `wait`."""
        time.sleep(wait)
        markers = self.peer.find(
            self.markers_topic, t.MarkerArray, lambda m: stamp_of(m.header) == stamp, 0.0
        )
        tf = self.peer.find(
            "rt/tf",
            t.TFMessage,
            lambda m: any(stamp_of(x.header) == stamp for x in m.transforms),
            0.0,
            TF_QOS,
        )
        return markers is None and tf is None


# ---------------------------------------------------------------- frames


@dataclass
class Scene:
    """A simulated camera view: grey pixels and the ground truth."""

    gray: np.ndarray  # uint8, height x width
    truth: dict
    png: bytes
    jpeg: bytes

    @property
    def width(self) -> int:
        return self.gray.shape[1]

    @property
    def height(self) -> int:
        return self.gray.shape[0]

    def camera_info(self, frame_id: str = "camera_optical") -> t.CameraInfo:
        cam = self.truth["camera"]
        fx, fy, cx, cy = cam["fx"], cam["fy"], cam["cx"], cam["cy"]
        return t.CameraInfo(
            header=t.Header(frame_id=frame_id),
            height=self.height,
            width=self.width,
            distortion_model="plumb_bob",
            d=list(cam["distortion"]),
            k=[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            r=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p=[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        )

    def markers(self) -> dict[int, dict]:
        """Ground truth of the markers wholly in view, by ID."""
        return {m["id"]: m for m in self.truth["markers"] if m["visible"]}


def read_pgm(path: Path) -> np.ndarray:
    data = path.read_bytes()
    # P5\n<w> <h>\n<max>\n<bytes>
    parts = data.split(maxsplit=4)
    assert parts[0] == b"P5", path
    width, height, maxval = int(parts[1]), int(parts[2]), int(parts[3])
    assert maxval == 255, path
    pixels = np.frombuffer(parts[4][-width * height :], dtype=np.uint8)
    return pixels.reshape(height, width).copy()


def simulate(whycode: Path, out: Path, name: str, args: list[str]) -> Scene:
    """A scene from `whycode simulate` (the CLI writes the image and its
    truth JSON); also kept as PNG and JPEG for the compressed transport."""
    pgm = out / f"{name}.pgm"
    subprocess.run(
        [str(whycode), "simulate", *args, "-o", str(pgm)],
        check=True,
        capture_output=True,
    )
    png = out / f"{name}.png"
    jpg = out / f"{name}.jpg"
    for path, extra in ((png, []), (jpg, ["--jpeg", "95"])):
        subprocess.run(
            [str(whycode), "simulate", *args, *extra, "-o", str(path), "--truth", str(out / "unused.json")],
            check=True,
            capture_output=True,
        )
    truth = json.loads(pgm.with_suffix(".json").read_text())
    return Scene(read_pgm(pgm), truth, png.read_bytes(), jpg.read_bytes())


def image_message(
    scene: Scene,
    stamp: tuple[int, int],
    frame_id: str = "camera_optical",
    encoding: str = "mono8",
) -> t.Image:
    """The scene as sensor_msgs/Image in `encoding` (grey replicated into
    colour channels, so every encoding carries the same luma)."""
    g = scene.gray
    h, w = g.shape
    if encoding == "mono8":
        data, step = g.tobytes(), w
    elif encoding == "mono16":
        data, step = (g.astype("<u2") * 257).tobytes(), 2 * w
    elif encoding in ("rgb8", "bgr8"):
        data, step = np.repeat(g[:, :, None], 3, axis=2).tobytes(), 3 * w
    elif encoding in ("rgba8", "bgra8"):
        rgba = np.repeat(g[:, :, None], 4, axis=2)
        rgba[:, :, 3] = 255
        data, step = rgba.tobytes(), 4 * w
    elif encoding in ("yuv422", "uyvy"):
        uyvy = np.full((h, w * 2), 128, dtype=np.uint8)
        uyvy[:, 1::2] = g
        data, step = uyvy.tobytes(), 2 * w
    elif encoding in ("yuv422_yuy2", "yuyv"):
        yuyv = np.full((h, w * 2), 128, dtype=np.uint8)
        yuyv[:, 0::2] = g
        data, step = yuyv.tobytes(), 2 * w
    else:
        raise ValueError(encoding)
    return t.Image(
        header=t.Header(stamp=t.Time(sec=stamp[0], nanosec=stamp[1]), frame_id=frame_id),
        height=h,
        width=w,
        encoding=encoding,
        is_bigendian=0,
        step=step,
        data=data,
    )


def compressed_message(
    scene: Scene, stamp: tuple[int, int], fmt: str, frame_id: str = "camera_optical"
) -> t.CompressedImage:
    data = scene.png if fmt == "png" else scene.jpeg
    return t.CompressedImage(
        header=t.Header(stamp=t.Time(sec=stamp[0], nanosec=stamp[1]), frame_id=frame_id),
        format=fmt,
        data=data,
    )


def position_error(transform: t.Transform, truth: dict) -> float:
    p = transform.translation
    tx, ty, tz = truth["position"]
    return math.dist((p.x, p.y, p.z), (tx, ty, tz))


def rotation_error_deg(q: t.Quaternion, truth: dict) -> float:
    """Angle between the published and the true orientation."""
    a = np.array([q.x, q.y, q.z, q.w])
    b = np.array(truth["quaternion"])
    dot = abs(float(np.dot(a / np.linalg.norm(a), b / np.linalg.norm(b))))
    return math.degrees(2 * math.acos(min(1.0, dot)))


# ------------------------------------------------------------------ node


class NodeProcess:
    """whycode_node in a child process, its log in a file."""

    def __init__(self, binary: Path, args: list[str], domain: int, log: Path, env: dict | None = None):
        self.log_path = log
        self._log = open(log, "wb")
        environment = dict(os.environ)
        environment.update(
            {
                "ROS_DOMAIN_ID": str(domain),
                # Discovery and traffic on the loopback interface only.
                "ROS_LOCALHOST_ONLY": "1",
            }
        )
        environment.update(env or {})
        self.proc = subprocess.Popen(
            [str(binary), *args],
            stdout=self._log,
            stderr=subprocess.STDOUT,
            env=environment,
        )

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def wait_log(self, needle: str, timeout: float = 10.0) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            text = self.log()
            if needle in text:
                return text
            if self.proc.poll() is not None:
                break
            time.sleep(0.02)
        raise AssertionError(f"'{needle}' not in the node's log:\n{self.log()}")

    def stop(self, timeout: float = 10.0) -> int:
        """SIGINT, as ros2 launch sends; the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait()
        self._log.close()
        return code
