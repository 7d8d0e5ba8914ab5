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
ROUNDS = 10


def median_ns(call, repeats: int = REPEATS) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter_ns()
        call()
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times)


def main() -> None:
    grey, _ = whycode.simulate(ids=range(1, 5), size=(640, 480), camera_distance="1.0m",
                               tilt="20deg", background="table", noise=2)
    detector = whycode.Detector()
    assert len(detector.detect(grey)) == 4
    layouts = {
        "uint8 grey, contiguous (no copy)": grey,
        "uint8 grey, Fortran order": np.asfortranarray(grey),
        "uint8 BGR": np.dstack([grey] * 3),
        "uint16 grey": grey.astype(np.uint16) * 257,
    }
    # Rust and Python timed in alternating rounds, so load from other
    # processes on the machine hits both alike; the overhead is the median
    # of the rounds' differences.
    print(f"{'input (640x480, 4 markers)':36} {'Rust':>9} {'Python':>9} {'overhead (median, range)':>30}")
    layouts["uint8 grey, no markers"] = np.zeros((480, 640), np.uint8)
    for name, image in layouts.items():
        rust_rounds, python_rounds = [], []
        for _ in range(ROUNDS):
            rust_rounds.append(
                detector._rust_detect_ns(image, REPEATS // ROUNDS))  # type: ignore[attr-defined]
            python_rounds.append(
                median_ns(lambda: detector.detect(image), REPEATS // ROUNDS))  # type: ignore[arg-type]
        diffs = sorted(p - r for p, r in zip(python_rounds, rust_rounds))
        print(f"{name:36} {statistics.median(rust_rounds) / 1000:7.1f}us "
              f"{statistics.median(python_rounds) / 1000:7.1f}us "
              f"{statistics.median(diffs) / 1000:12.1f} us ({diffs[0] / 1000:.1f} .. {diffs[-1] / 1000:.1f})")

if __name__ == "__main__":
    main()
