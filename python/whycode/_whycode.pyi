"""Type stubs of the compiled whycode module."""

import os
from typing import Any, Iterator, Literal, Optional, Sequence, Tuple, TypedDict, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

StrPath = Union[str, "os.PathLike[str]"]
Quantity = Union[float, str]
"""A quantity, given as on the command line: text with its unit ("50mm",
"2in", "30deg", "2px", "97%"); a number means what it means typed there
without a unit (metres for a detector's diameter, an arena's size and a
marker height; pixels for blur; a ratio for a print scale; refused for
the other lengths and for angles, with the command line's message)."""
Length = Quantity
"""A length: text with a unit ("50mm", "2in"), or a number where the
command line takes bare metres."""
ImageArray = Union[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]
"""HxW grey, HxWx3 BGR or HxWx4 BGRA, uint8 or uint16."""

class WhycodeError(Exception):
    """Base of every error whycode raises."""

class WhycodeValueError(WhycodeError, ValueError):
    """Bad input: an argument, an array or a file's contents."""

class WhycodeOSError(WhycodeError, OSError):
    """A file could not be read or written."""

class Code:
    """One ID of a family, with the fields of ``whycode ids``."""

    @property
    def id(self) -> int: ...
    @property
    def code(self) -> int: ...
    @property
    def binary(self) -> str: ...
    @property
    def self_distance(self) -> int: ...

class Decoded:
    """A decoded ring reading."""

    @property
    def id(self) -> int: ...
    @property
    def code(self) -> int: ...
    @property
    def rotation(self) -> int: ...
    @property
    def rotation_ambiguous(self) -> bool: ...
    @property
    def errors(self) -> int: ...
    @property
    def status(self) -> Literal["exact", "corrected", "ambiguous", "rejected"]: ...

class Family:
    """A family of WhyCode IDs (rotation-free necklace codes)."""

    def __init__(self, bits: int = 8, distance: int = 2) -> None: ...
    @staticmethod
    def load(path: StrPath) -> Family: ...
    @staticmethod
    def from_json(text: str) -> Family: ...
    @property
    def bits(self) -> int: ...
    @property
    def distance(self) -> int: ...
    @property
    def min_distance(self) -> Optional[int]: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[Code]: ...
    def __getitem__(self, id: int) -> Code: ...
    def decode(self, word: int) -> Decoded: ...
    def to_json(self) -> str: ...
    def save(self, path: StrPath) -> None: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...

def family_counts(bits: Sequence[int], distances: Sequence[int]) -> dict[tuple[int, int], int]:
    """Number of IDs for every (bits, distance) with distance <= bits."""

class Camera:
    """A calibrated pinhole camera with plumb_bob distortion."""

    @staticmethod
    def load(path: StrPath) -> Camera: ...
    @staticmethod
    def from_opencv(
        camera_matrix: npt.ArrayLike,
        dist_coeffs: Optional[npt.ArrayLike],
        image_size: tuple[int, int],
    ) -> Camera: ...
    @staticmethod
    def ideal(width: int, height: int, fov_deg: float = 60.0) -> Camera: ...
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def distortion(self) -> tuple[float, float, float, float, float]: ...
    @property
    def camera_matrix(self) -> npt.NDArray[np.float64]: ...
    def to_ros_yaml(self, camera_name: str = "camera") -> str: ...
    def save(
        self,
        path: StrPath,
        *,
        format: Optional[Literal["ros", "opencv-yaml", "opencv-xml"]] = None,
        camera_name: str = "camera",
    ) -> None:
        """Writes the calibration as ``whycode calibrate -o path`` would (format from the extension)."""
    def __eq__(self, other: object) -> bool: ...

class Arena:
    """A floor frame from four corner markers (``whycode arena``)."""

    @staticmethod
    def load(path: StrPath) -> Arena: ...
    @staticmethod
    def from_yaml(text: str) -> Arena: ...
    @staticmethod
    def measure(
        image: ImageArray,
        size: tuple[Length, Length],
        *,
        ids: Optional[Sequence[int]] = None,
        camera: Optional[Camera] = None,
        marker_height: Optional[Length] = None,
        family: Optional[Family] = None,
        legacy: bool = False,
    ) -> Arena:
        """The arena in one photo, as ``whycode arena`` measures it."""
    def to_yaml(self) -> str: ...
    def save(self, path: StrPath) -> None: ...
    @property
    def ids(self) -> tuple[int, int, int, int]:
        """Origin, +x corner, far corner, +y corner."""
    @property
    def size(self) -> tuple[float, float]: ...
    @property
    def marker_height(self) -> float: ...
    @property
    def camera(self) -> Optional[Camera]: ...

class ArenaPosition(TypedDict):
    x: float
    y: float
    z: float
    yaw: Optional[float]
def calibrate(
    manifest: StrPath,
    images: Sequence[Union[StrPath, ImageArray]],
    *,
    fix_principal_point: bool = False,
    fix_aspect: bool = False,
    no_tangential: bool = False,
    no_k3: bool = False,
    print_scale: Optional[Quantity] = None,
) -> tuple[Camera, dict[str, Any]]:
    """A camera from photos of a printed sheet, as ``whycode calibrate``: (camera, report)."""

class Marker:
    """One marker found in a frame (attributes at full precision)."""

    @property
    def arena(self) -> Optional[ArenaPosition]:
        """With ``Detector(arena=...)``: x, y, z (metres) and yaw on the floor."""

    @property
    def id(self) -> int:
        """The marker's ID; 0 means unknown."""
    @property
    def code(self) -> Optional[int]: ...
    @property
    def u(self) -> float: ...
    @property
    def v(self) -> float: ...
    @property
    def yaw(self) -> Optional[float]: ...
    @property
    def axes(self) -> tuple[float, float]: ...
    @property
    def confidence(self) -> float: ...
    @property
    def position(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def rotation(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def quaternion(self) -> Optional[tuple[float, float, float, float]]: ...
    @property
    def rvec(self) -> Optional[npt.NDArray[np.float64]]:
        """The rotation as OpenCV's Rodrigues vector (radians)."""
    @property
    def tvec(self) -> Optional[npt.NDArray[np.float64]]:
        """OpenCV's translation: the marker centre in the camera frame, metres."""
    @property
    def angle(self) -> float:
        """Direction of the outer ellipse's major axis, radians."""
    @property
    def bits(self) -> Optional[int]: ...
    @property
    def unknown(self) -> Optional[str]:
        """Why a WhyCode marker has ID 0 ("no_code_ring", "ring_unread", "not_a_member", ...)."""
    @property
    def track(self) -> Optional[int]:
        """With tracking, the marker's track number (the same while it is followed)."""
    def as_dict(self) -> dict[str, Any]:
        """The object ``whycode detect --format json`` prints for this marker."""

class Detections(list[Marker]):
    """The markers of one frame, with the poses of the Detector's boards."""

    boards: list[dict[str, Any]]
    """One dict per board seen, as ``whycode detect --board`` writes it in JSON."""
    legacy_looking: int
    """Discs that looked like legacy WhyCon markers (a white centre, no code
    ring) while WhyCode markers were looked for: ``Detector(legacy=True)``
    reads them (``whycode detect`` says so in a note)."""

class Detector:
    """Finds WhyCode markers (or legacy WhyCon circles) in frames."""

    def __init__(
        self,
        family: Optional[Family] = None,
        *,
        legacy: bool = False,
        diameter: Optional[Length] = None,
        camera: Optional[Camera] = None,
        tracking: bool = False,
        max_markers: Optional[int] = None,
        timings: bool = False,
        arena: Optional[Union[Arena, StrPath]] = None,
        boards: Sequence[StrPath] = (),
    ) -> None: ...
    def detect(self, image: ImageArray) -> Detections: ...
    def last_timings(self) -> Optional[dict[str, Any]]:
        """Milliseconds per stage of the frame detected last (``timings=True``)."""
    def reset(self) -> None: ...
    @property
    def tracking(self) -> bool: ...
    @property
    def family(self) -> Optional[Family]: ...

def draw(image: ImageArray, markers: Sequence[Marker]) -> npt.NDArray[np.uint8]:
    """The markers drawn over the image: a new HxWx3 BGR array."""

def load_image(path: StrPath) -> npt.NDArray[np.uint8]:
    """An image file as the HxW uint8 grey array the CLI's loader makes."""

class FrameReader:
    """The frames of a recording: (frame, stamp_ns, HxW uint8 grey array)."""

    def __iter__(self) -> FrameReader: ...
    def __next__(self) -> Tuple[int, int, npt.NDArray[np.uint8]]: ...

def read_frames(
    path: StrPath,
    *,
    topic: Optional[str] = None,
    every: Optional[int] = None,
    start: Optional[float] = None,
    end: Optional[float] = None,
) -> FrameReader:
    """A ROS 2 bag's (.mcap) or a video's frames, as `whycode detect` reads them:
    frame index, stamp (ns: the header stamp or presentation time) and grey image."""

def render_marker(
    id: Optional[int] = None,
    *,
    diameter: Length,
    family: Optional[Family] = None,
    legacy: bool = False,
    format: Optional[str] = None,
    output: Optional[StrPath] = None,
    margin: Optional[Length] = None,
    dpi: float = 300.0,
    cross: bool = False,
    cut_guide: bool = False,
    label: bool = False,
    check: bool = True,
) -> bytes: ...
def render_sheet(
    ids: Optional[Sequence[int]] = None,
    *,
    family: Optional[Family] = None,
    legacy: bool = False,
    count: Optional[int] = None,
    diameter: Optional[Length] = None,
    template: str = "a4",
    format: Optional[str] = None,
    output: Optional[StrPath] = None,
    name: Optional[str] = None,
    dpi: float = 300.0,
    check: bool = True,
) -> tuple[list[bytes], dict[str, Any]]: ...
def render_marker_image(
    id: Optional[int] = None,
    *,
    family: Optional[Family] = None,
    legacy: bool = False,
    diameter_px: float = 100.0,
    margin_px: Optional[float] = None,
) -> npt.NDArray[np.uint8]: ...
def templates() -> list[tuple[str, float, float, float, str]]: ...
@overload
def validate(
    manifest: StrPath,
    images: Sequence[Union[StrPath, ImageArray]],
    camera: Optional[Camera] = None,
    *,
    annotate: Literal[False] = False,
) -> dict[str, Any]: ...
@overload
def validate(
    manifest: StrPath,
    images: Sequence[Union[StrPath, ImageArray]],
    camera: Optional[Camera] = None,
    *,
    annotate: Literal[True],
) -> tuple[dict[str, Any], list[npt.NDArray[np.uint8]]]: ...
def simulate(
    *,
    manifest: Optional[StrPath] = None,
    page: Optional[int] = None,
    print_scale: Optional[Quantity] = None,
    family: Optional[Family] = None,
    ids: Optional[Sequence[int]] = None,
    diameter: Optional[Length] = None,
    layout: Optional[Literal["grid", "scatter"]] = None,
    camera: Optional[Camera] = None,
    size: Optional[tuple[int, int]] = None,
    fov: Optional[Quantity] = None,
    camera_distance: Optional[Length] = None,
    tilt: Optional[Quantity] = None,
    pan: Optional[Quantity] = None,
    roll: Optional[Quantity] = None,
    background: Optional[Literal["grey", "table", "clutter"]] = None,
    gradient: float = 1.0,
    gradient_angle: Optional[Quantity] = None,
    exposure: Optional[float] = None,
    dark: bool = False,
    blur: Optional[Quantity] = None,
    motion_blur: Optional[Quantity] = None,
    motion_angle: Optional[Quantity] = None,
    noise: float = 0.0,
    jpeg: Optional[int] = None,
    blot: Sequence[int] = (),
    seed: int = 1,
) -> tuple[npt.NDArray[np.uint8], dict[str, Any]]: ...
