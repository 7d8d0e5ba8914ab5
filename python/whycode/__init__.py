"""WhyCode circular fiducial markers: ID families, print-ready rendering,
detection with 6-DoF pose, validation of printed sheets and simulation.

Fields and messages are those of the ``whycode`` command line: a marker's
``as_dict()`` is the object ``whycode detect --format json`` prints, and
``validate()`` returns the report ``whycode validate --format json`` prints;
``calibrate()`` writes through ``Camera.save`` what ``whycode calibrate`` writes.
"""

from ._whycode import (
    Arena,
    Camera,
    Code,
    Decoded,
    Detections,
    Detector,
    Family,
    FrameReader,
    Marker,
    WhycodeError,
    WhycodeOSError,
    WhycodeValueError,
    __version__,
    calibrate,
    draw,
    family_counts,
    load_image,
    read_frames,
    render_marker,
    render_marker_image,
    render_sheet,
    simulate,
    templates,
    validate,
)

__all__ = [
    "Arena",
    "Camera",
    "Code",
    "Decoded",
    "Detections",
    "Detector",
    "Family",
    "FrameReader",
    "Marker",
    "WhycodeError",
    "WhycodeOSError",
    "WhycodeValueError",
    "__version__",
    "calibrate",
    "draw",
    "family_counts",
    "load_image",
    "read_frames",
    "render_marker",
    "render_marker_image",
    "render_sheet",
    "simulate",
    "templates",
    "validate",
]
