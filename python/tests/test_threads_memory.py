"""Threads and lifetimes: no crash, no wrong result, no leak."""

import gc
import threading
from typing import Callable

import numpy as np
import pytest

import whycode

THREADS = 8
CALLS = 200


@pytest.fixture(scope="module")
def frame() -> tuple[np.ndarray, list[dict[str, object]]]:
    image, _ = whycode.simulate(ids=range(1, 10), size=(320, 240), camera_distance="0.9m",
                                tilt="20deg", noise=2, seed=5)
    expected = [m.as_dict() for m in whycode.Detector().detect(image)]
    assert len(expected) == 9
    return image, expected


def hammer(work: Callable[[int], None]) -> None:
    errors: list[BaseException] = []

    def run(k: int) -> None:
        try:
            work(k)
        except BaseException as e:  # noqa: B902 - reported below
            errors.append(e)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[0]


def test_a_shared_detector_serves_eight_threads(frame: tuple) -> None:
    image, expected = frame
    shared = whycode.Detector()

    def work(k: int) -> None:
        # Each thread also hands over its own layout of the same pixels.
        own = [image, np.asfortranarray(image), np.dstack([image] * 3)][k % 3]
        for _ in range(CALLS):
            assert [m.as_dict() for m in shared.detect(own)] == expected

    hammer(work)


def test_separate_detectors_in_eight_threads(frame: tuple) -> None:
    image, expected = frame

    def work(k: int) -> None:
        detector = whycode.Detector(tracking=k % 2 == 1)
        for _ in range(CALLS):
            found = detector.detect(image)
            if detector.tracking:
                assert sorted(m.id for m in found) == sorted(int(m["id"]) for m in expected)
            else:
                assert [m.as_dict() for m in found] == expected

    hammer(work)


def test_a_shared_tracking_detector_takes_turns(frame: tuple) -> None:
    image, expected = frame
    shared = whycode.Detector(tracking=True)
    ids = sorted(int(m["id"]) for m in expected)

    def work(k: int) -> None:
        for _ in range(CALLS // 4):
            assert sorted(m.id for m in shared.detect(image)) == ids

    hammer(work)


def resident_kib() -> int:
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * 4


@pytest.mark.skipif(not hasattr(__import__("os"), "sysconf"), reason="needs /proc")
def test_ten_thousand_create_drop_cycles_do_not_grow(frame: tuple) -> None:
    image, _ = frame
    small = image[:120, :160]

    def cycle() -> None:
        family = whycode.Family(8, 2)
        detector = whycode.Detector(family, tracking=True)
        found = detector.detect(small)
        for m in found:
            m.as_dict()
        whycode.Camera.ideal(160, 120)

    for _ in range(1000):
        cycle()
    gc.collect()
    before = resident_kib()
    for _ in range(10_000):
        cycle()
    gc.collect()
    grown = resident_kib() - before
    # A leak of even 1 kB per cycle would show as 10 MB.
    assert grown < 2_000, f"resident memory grew by {grown} KiB over 10,000 cycles"
