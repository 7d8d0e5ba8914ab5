"""whycode vs pupil-apriltags (tag36h11) vs OpenCV ArUco (DICT_4X4_50,
DICT_APRILTAG_36h11) on the same simulated scenes.

Every scene is simulated once by whycode without noise or blur: a grid of
WhyCode markers seen by an ideal 1280x720 camera. For each peer family the
same frame gets, in place of every WhyCode marker, a tag rendered by OpenCV
(`cv2.aruco.generateImageMarker`) and warped with the marker's true pose so
that the tag's black square is as wide as the WhyCode disc (equal printed
footprint), on the same white margin. Then every frame of the scene gets
the same blur and the same noise. Times are medians per frame, one thread. Empty-clutter frames hold no marker at
all. A detection counts when its ID is the marker's and its centre lies
within half a marker diameter of the truth; a reported ID that is not the
marker's there is an ID error; anything reported on clutter is a false report.

    pip install opencv-python-headless pupil-apriltags
    python python/bench/compare.py [--quick]
"""

import argparse
import os
import statistics
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

import cv2
import numpy as np
import pupil_apriltags

import whycode

WIDTH, HEIGHT = 1280, 720
DIAMETER_M = 0.05


@dataclass
class Tally:
    visible: int = 0
    found: int = 0
    id_errors: int = 0
    clutter_frames: int = 0
    false_reports: int = 0
    times_ms: list[float] = field(default_factory=list)
    clutter_ms: list[float] = field(default_factory=list)


def square_corners(marker: dict, side_m: float, fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    """Image corners of a square of `side_m` centred on the marker, in its plane."""
    r = np.array(marker["rotation"])
    p = np.array(marker["position"])
    h = side_m / 2
    corners = []
    for sx, sy in ((-1, 1), (1, 1), (1, -1), (-1, -1)):
        q = p + r[:, 0] * sx * h + r[:, 1] * sy * h
        corners.append((fx * q[0] / q[2] + cx, fy * q[1] / q[2] + cy))
    return np.array(corners, np.float32)


def tag_frame(clean: np.ndarray, truth: dict, dictionary: "cv2.aruco.Dictionary",
              module_bits: int) -> np.ndarray:
    """`clean` with every WhyCode marker replaced by a tag of equal footprint."""
    cam = truth["camera"]
    frame = clean.copy()
    cells = module_bits + 2  # data bits plus the black border
    for k, m in enumerate(truth["markers"]):
        # white paper first: the marker's own margin (1.3 x diameter square)
        paper_side = DIAMETER_M * 1.3
        paper = square_corners(m, paper_side, cam["fx"], cam["fy"], cam["cx"], cam["cy"])
        region = cv2.boundingRect(paper.astype(np.int32))
        x, y, w, h = region
        patch = clean[max(y, 0):y + h, max(x, 0):x + w]
        if patch.size == 0:
            continue
        white, black = float(np.percentile(patch, 98)), float(np.percentile(patch, 2))
        px = 32  # pixels per tag cell in the rendered tag
        tag = cv2.aruco.generateImageMarker(dictionary, k, cells * px, borderBits=1)
        margin = int(round(cells * px * 0.15))
        tag = cv2.copyMakeBorder(tag, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255)
        side = tag.shape[0]
        source = np.array([[0, 0], [side, 0], [side, side], [0, side]], np.float32)
        target = square_corners(m, DIAMETER_M * side / (cells * px), cam["fx"], cam["fy"],
                                cam["cx"], cam["cy"])
        homography = cv2.getPerspectiveTransform(source, target)
        levels = (black + (white - black) * (tag.astype(np.float32) / 255.0))
        warped = cv2.warpPerspective(levels, homography, (frame.shape[1], frame.shape[0]),
                                     flags=cv2.INTER_AREA)
        mask = cv2.warpPerspective(np.ones_like(levels), homography,
                                   (frame.shape[1], frame.shape[0]), flags=cv2.INTER_LINEAR)
        frame = (frame * (1 - mask) + warped * mask).round().clip(0, 255).astype(np.uint8)
    return frame


def degrade(frame: np.ndarray, blur: float, noise: float, seed: int) -> np.ndarray:
    out = frame.astype(np.float32)
    if blur > 0:
        out = cv2.GaussianBlur(out, (0, 0), blur)
    if noise > 0:
        out += np.random.default_rng(seed).normal(0, noise, out.shape)
    return out.round().clip(0, 255).astype(np.uint8)


Detect = Callable[[np.ndarray], list[tuple[int, float, float]]]


def detectors() -> dict[str, tuple[Detect, "cv2.aruco.Dictionary | None", int]]:
    family = whycode.Family(8, 2)
    ours = whycode.Detector(family)

    def whycode_detect(image: np.ndarray) -> list[tuple[int, float, float]]:
        return [(m.id, m.u, m.v) for m in ours.detect(image)]

    apriltag = pupil_apriltags.Detector(families="tag36h11", nthreads=1)

    def apriltag_detect(image: np.ndarray) -> list[tuple[int, float, float]]:
        return [(d.tag_id, float(d.center[0]), float(d.center[1])) for d in apriltag.detect(image)]

    def aruco(name: int) -> Detect:
        detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(name),
                                           cv2.aruco.DetectorParameters())

        def run(image: np.ndarray) -> list[tuple[int, float, float]]:
            corners, ids, _ = detector.detectMarkers(image)
            if ids is None:
                return []
            return [(int(i), float(c[0][:, 0].mean()), float(c[0][:, 1].mean()))
                    for i, c in zip(ids.ravel(), corners)]

        return run

    tag36 = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    d4x4 = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    return {
        "whycode (8-bit, d2)": (whycode_detect, None, 0),
        "pupil-apriltags tag36h11": (apriltag_detect, tag36, 6),
        "cv2.aruco APRILTAG_36h11": (aruco(cv2.aruco.DICT_APRILTAG_36h11), tag36, 6),
        "cv2.aruco 4X4_50": (aruco(cv2.aruco.DICT_4X4_50), d4x4, 4),
    }


def score(tally: Tally, found: list[tuple[int, float, float]], truth: dict,
          expected_id: Callable[[int, dict], int]) -> None:
    markers = [m for m in truth["markers"] if m["visible"]]
    tally.visible += len(markers)
    matched = set()
    for ident, u, v in found:
        near = [m for m in truth["markers"]
                if np.hypot(m["u"] - u, m["v"] - v) < m["diameter_px"] / 2]
        if not near:
            tally.id_errors += 1 if ident != 0 else 0
            continue
        m = near[0]
        if ident == expected_id(truth["markers"].index(m), m):
            if m["id"] not in matched:
                matched.add(m["id"])
                tally.found += 1
        elif ident != 0:
            tally.id_errors += 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer scenes")
    args = parser.parse_args()
    camera = whycode.Camera.ideal(WIDTH, HEIGHT, 60.0)
    sizes_px = [14, 20, 30, 60] if not args.quick else [20, 60]
    tilts = [0, 45, 65] if not args.quick else [45]
    conditions = [(0.0, 2.0), (1.5, 4.0), (0.0, 12.0)] if not args.quick else [(1.0, 4.0)]
    seeds = [1, 2] if not args.quick else [1]
    runners = detectors()
    tallies = {name: Tally() for name in runners}
    by_size = {(name, size): Tally() for name in runners for size in sizes_px}
    scene = 0
    for size in sizes_px:
        distance = camera.fx * DIAMETER_M / size
        for tilt in tilts:
            for blur, noise in conditions:
                for seed in seeds:
                    scene += 1
                    clean, truth = whycode.simulate(
                        ids=range(1, 13), diameter=f"{DIAMETER_M}m", camera=camera,
                        camera_distance=f"{distance}m", tilt=f"{tilt}deg",
                        pan=f"{10 * seed - 15}deg", roll=f"{17 * seed}deg",
                        background="table", seed=seed)
                    for name, (run, dictionary, bits) in runners.items():
                        frame = clean if dictionary is None else tag_frame(clean, truth, dictionary, bits)
                        frame = degrade(frame, blur, noise, seed * 1000 + scene)
                        start = time.perf_counter()
                        found = run(frame)
                        tallies[name].times_ms.append((time.perf_counter() - start) * 1000)
                        expected = ((lambda k, m: int(m["id"])) if dictionary is None
                                    else (lambda k, m: k))
                        score(tallies[name], found, truth, expected)
                        score(by_size[(name, size)], found, truth, expected)
    # Empty clutter: the scene's one marker is 1 km away (a twentieth of a
    # pixel), as far as a simulated camera may be.
    for seed in range(1, 21 if not args.quick else 6):
        clutter, _ = whycode.simulate(ids=[1], camera=camera, camera_distance="1000.0m",
                                      background="clutter", noise=3, seed=seed)
        for name, (run, _, _) in runners.items():
            start = time.perf_counter()
            found = run(clutter)
            tallies[name].clutter_ms.append((time.perf_counter() - start) * 1000)
            tallies[name].clutter_frames += 1
            tallies[name].false_reports += len(found)
    print(f"{scene} scenes x 12 markers ({WIDTH}x{HEIGHT}, marker sizes {sizes_px} px, "
          f"tilts {tilts} deg, blur/noise {conditions}), "
          f"{tallies[next(iter(tallies))].clutter_frames} empty clutter frames; one thread")
    print()
    print("| detector | detection rate | ID errors | false reports on clutter "
          "| ms per frame: scenes | ms per frame: clutter |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, t in tallies.items():
        print(f"| {name} | {100 * t.found / max(t.visible, 1):.1f} % ({t.found}/{t.visible}) "
              f"| {t.id_errors} | {t.false_reports} in {t.clutter_frames} frames "
              f"| {statistics.median(t.times_ms):.1f} | {statistics.median(t.clutter_ms):.1f} |")
    print()
    print("| detection rate by marker size | " + " | ".join(f"{s} px" for s in sizes_px) + " |")
    print("|---|" + "---:|" * len(sizes_px))
    for name in runners:
        cells = [by_size[(name, s)] for s in sizes_px]
        print(f"| {name} | " + " | ".join(f"{100 * t.found / max(t.visible, 1):.0f} %" for t in cells)
              + " |")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
    # pupil-apriltags' Detector.__del__ segfaults at interpreter shutdown in
    # about two runs of three here (faulthandler: bindings.py, __del__); the
    # table is printed, so leave without running finalizers.
    os._exit(0)
