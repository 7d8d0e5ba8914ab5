"""OpenCV ArUco (DICT_4X4_50) on the detector bar's frames, for the comparison.

Reads every .pgm in DIR (sorted by name) and prints one JSON line per frame:
{"file", "ms", "tags": [{"id", "center", "corners"}]}. OpenCV's default
detector parameters, one thread, as the bar compares single streams; "ms" is
the time of the detectMarkers call alone, after one untimed warm-up call on
the first frame.

Needs opencv-python-headless (see docs/benchmarks.md):
    python3 -m venv target/bench-venv
    target/bench-venv/bin/pip install opencv-python-headless pupil-apriltags numpy
"""

import argparse
import json
import pathlib
import time

import cv2


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=pathlib.Path)
    args = parser.parse_args()

    cv2.setNumThreads(1)
    detector = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50),
        cv2.aruco.DetectorParameters(),
    )
    files = sorted(args.dir.glob("*.pgm"))
    warmed = False
    for path in files:
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise SystemExit(f"{path}: not an image OpenCV reads")
        if not warmed:
            detector.detectMarkers(image)
            warmed = True
        start = time.perf_counter()
        corners, ids, _ = detector.detectMarkers(image)
        ms = 1000.0 * (time.perf_counter() - start)
        tags = []
        if ids is not None:
            for ident, quad in zip(ids.ravel(), corners):
                quad = quad.reshape(4, 2)
                tags.append(
                    {
                        "id": int(ident),
                        "center": [float(quad[:, 0].mean()), float(quad[:, 1].mean())],
                        "corners": [[float(x) for x in c] for c in quad],
                    }
                )
        print(json.dumps({"file": path.name, "ms": ms, "tags": tags}), flush=True)


if __name__ == "__main__":
    main()
