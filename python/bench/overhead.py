"""Per-call cost of the Python binding over the Rust detector (a benchmark,
not a test): medians on one 640x480 frame with a few markers, for each input
layout, against the Rust `detect` on the same pixels measured in the same run.

    python python/bench/overhead.py
"""

import statistics
import time

import numpy as np

import whycode

REPEATS = 2000


def median_ns(call, repeats: int = REPEATS) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter_ns()
        call()
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times)


def main() -> None:
    grey, _ = whycode.simulate(ids=range(1, 5), size=(640, 480), camera_distance=1.0,
                               tilt=20, background="table", noise=2)
    detector = whycode.Detector()
    assert len(detector.detect(grey)) == 4
    layouts = {
        "uint8 grey, contiguous (no copy)": grey,
        "uint8 grey, Fortran order": np.asfortranarray(grey),
        "uint8 BGR": np.dstack([grey] * 3),
        "uint16 grey": grey.astype(np.uint16) * 257,
    }
    rust = detector._rust_detect_ns(grey, REPEATS)  # type: ignore[attr-defined]
    print(f"Rust detect alone (640x480, 4 markers): median {rust / 1000:.1f} us")
    print(f"{'input':36} {'Python call':>12} {'overhead':>10}")
    for name, image in layouts.items():
        python = median_ns(lambda: detector.detect(image))  # type: ignore[arg-type]
        print(f"{name:36} {python / 1000:9.1f} us {(python - rust) / 1000:7.1f} us")
    empty = np.zeros((480, 640), np.uint8)
    rust_empty = detector._rust_detect_ns(empty, REPEATS)  # type: ignore[attr-defined]
    python_empty = median_ns(lambda: detector.detect(empty))
    print(f"{'uint8 grey, no markers':36} {python_empty / 1000:9.1f} us "
          f"{(python_empty - rust_empty) / 1000:7.1f} us")


if __name__ == "__main__":
    main()
