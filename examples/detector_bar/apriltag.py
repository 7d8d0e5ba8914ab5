"""AprilTag (tag36h11) on the detector bar's frames, for the comparison.

Reads every .pgm in DIR (sorted by name) and prints one JSON line per frame:
{"file", "ms", "tags": [{"id", "hamming", "margin", "center", "corners",
"R", "t"}]}. One detector with one thread, as the bar compares single
streams; "ms" is the time of the detect call alone (pose included when
--fx is given), after one untimed warm-up call on the first frame.

Needs pupil-apriltags and numpy (see docs/benchmarks.md):
    python3 -m venv target/bench-venv
    target/bench-venv/bin/pip install pupil-apriltags numpy
"""

import argparse
import json
import os
import pathlib
import sys
import time

import numpy as np
from pupil_apriltags import Detector


def read_pgm(path):
    """A binary 8-bit PGM (P5) as a 2-D uint8 array."""
    data = path.read_bytes()
    fields = []
    pos = 0
    while len(fields) < 4:
        while data[pos : pos + 1].isspace():
            pos += 1
        if data[pos : pos + 1] == b"#":
            pos = data.index(b"\n", pos)
            continue
        end = pos
        while not data[end : end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    magic, width, height, maxval = fields
    if magic != b"P5" or int(maxval) > 255:
        sys.exit(f"{path}: not an 8-bit binary PGM")
    pixels = np.frombuffer(data, np.uint8, int(width) * int(height), pos + 1)
    return pixels.reshape(int(height), int(width))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=pathlib.Path)
    parser.add_argument("--fx", type=float)
    parser.add_argument("--fy", type=float)
    parser.add_argument("--cx", type=float)
    parser.add_argument("--cy", type=float)
    parser.add_argument("--tag-size", type=float, help="black square side, metres")
    parser.add_argument(
        "--quad-decimate",
        type=float,
        default=2.0,
        help="pupil-apriltags' default 2.0 halves the image for quad finding",
    )
    args = parser.parse_args()

    detector = Detector(
        families="tag36h11", nthreads=1, quad_decimate=args.quad_decimate
    )
    pose = args.fx is not None
    kwargs = {}
    if pose:
        kwargs = dict(
            estimate_tag_pose=True,
            camera_params=(args.fx, args.fy, args.cx, args.cy),
            tag_size=args.tag_size,
        )
    files = sorted(args.dir.glob("*.pgm"))
    warmed = False
    for path in files:
        image = read_pgm(path)
        if not warmed:
            detector.detect(image, **kwargs)
            warmed = True
        start = time.perf_counter()
        found = detector.detect(image, **kwargs)
        ms = 1000.0 * (time.perf_counter() - start)
        tags = []
        for d in found:
            tag = {
                "id": int(d.tag_id),
                "hamming": int(d.hamming),
                "margin": float(d.decision_margin),
                "center": [float(x) for x in d.center],
                "corners": [[float(x) for x in c] for c in d.corners],
            }
            if pose and d.pose_R is not None:
                tag["R"] = np.asarray(d.pose_R, float).tolist()
                tag["t"] = np.asarray(d.pose_t, float).ravel().tolist()
            tags.append(tag)
        print(json.dumps({"file": path.name, "ms": ms, "tags": tags}), flush=True)


if __name__ == "__main__":
    main()
    # pupil-apriltags' Detector.__del__ sometimes segfaults at interpreter
    # shutdown (as in python/bench/compare.py); every line is printed and
    # flushed, so leave without running finalizers.
    sys.stdout.flush()
    os._exit(0)
