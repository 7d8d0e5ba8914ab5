"""Fixtures of the peer tests: the binaries, simulated frames with ground
truth, one DDS domain per test (so that no test sees another's leftovers),
the CycloneDDS peer, whycode_node processes, and the figures printed at
the end of the run."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest

import peer as P

ROOT = Path(__file__).resolve().parents[3]
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))

# The frames: 640x480, a 60 degree lens, 50 mm markers of the 12-bit
# family (170 IDs; 150 does not fit the original node's int8 id).
FAMILY = ["--bits", "12", "--distance", "2"]
IDS = [3, 17, 42, 77, 150]
DIAMETER_M = 0.05
SEQUENCE_FRAMES = 30

_FIGURES: list[str] = []
_DOMAINS = itertools.count(11)


def pytest_configure(config):
    config.addinivalue_line("markers", "figures: prints measured figures")


def pytest_terminal_summary(terminalreporter):
    if _FIGURES:
        terminalreporter.section("whycode_node figures")
        for line in _FIGURES:
            terminalreporter.write_line(line)


@pytest.fixture(scope="session")
def figures():
    return _FIGURES


@pytest.fixture(scope="session")
def node_bin() -> Path:
    path = Path(os.environ.get("WHYCODE_NODE", TARGET / "release" / "whycode_node"))
    assert path.is_file(), f"{path}: build it with cargo build --release -p whycode-ros2"
    return path


@pytest.fixture(scope="session")
def whycode_bin() -> Path:
    path = Path(os.environ.get("WHYCODE_BIN", TARGET / "release" / "whycode"))
    assert path.is_file(), f"{path}: build it with cargo build --release --bin whycode"
    return path


def scene_args(k: int, n: int) -> list[str]:
    """Frame k of n of a slow camera move past a board of markers: nearer,
    turning and tilting, as a tracked sequence sees it."""
    s = k / max(n - 1, 1)
    return [
        "--size", "640x480", "--fov", "60deg",
        *FAMILY,
        "--ids", ",".join(map(str, IDS)),
        "--diameter", "50mm",
        "--camera-distance", f"{0.95 - 0.3 * s:.4f}m",
        "--tilt", f"{10 + 25 * s:.3f}deg",
        "--pan", f"{-15 + 30 * s:.3f}deg",
        "--roll", f"{60 * s:.3f}deg",
        "--noise", "2",
        "--seed", str(k + 1),
    ]


@pytest.fixture(scope="session")
def sequence(whycode_bin, tmp_path_factory) -> list[P.Scene]:
    out = tmp_path_factory.mktemp("sequence")
    return [
        P.simulate(whycode_bin, out, f"f{k:02}", scene_args(k, SEQUENCE_FRAMES))
        for k in range(SEQUENCE_FRAMES)
    ]


@pytest.fixture(scope="session")
def scene(sequence) -> P.Scene:
    """One frame of the sequence, for tests of one thing at a time."""
    return sequence[SEQUENCE_FRAMES // 2]


@pytest.fixture(scope="session")
def other_scene(whycode_bin, tmp_path_factory) -> P.Scene:
    """Other markers, for a second camera."""
    out = tmp_path_factory.mktemp("other")
    return P.simulate(
        whycode_bin,
        out,
        "other",
        [
            "--size", "640x480", *FAMILY, "--ids", "5,9,100", "--diameter", "50mm",
            "--camera-distance", "0.6m", "--tilt", "-20deg", "--roll", "-40deg",
        ],
    )


@pytest.fixture(scope="session")
def big_scene(whycode_bin, tmp_path_factory) -> P.Scene:
    out = tmp_path_factory.mktemp("big")
    return P.simulate(
        whycode_bin,
        out,
        "big",
        ["--size", "1920x1080", *FAMILY, "--ids", "3,17,42", "--diameter", "50mm",
         "--camera-distance", "0.8m", "--tilt", "20deg"],
    )


@dataclass
class SheetScene:
    """A printed sheet seen through the lens, with the files the node's
    boards and arena parameters take (all made by the command line)."""

    scene: P.Scene
    manifest: Path
    arena: Path
    # Each marker's centre on the page, metres (x right, y down the page).
    on_page: dict[int, tuple[float, float]]
    corners: tuple[int, int, int, int]


@pytest.fixture(scope="session")
def sheet_scene(whycode_bin, tmp_path_factory) -> SheetScene:
    out = tmp_path_factory.mktemp("sheet")
    manifest = out / "sheet.json"
    subprocess.run(
        [str(whycode_bin), "sheet", *FAMILY, "--ids", "1-12", "--diameter", "40mm", "--template", "a4",
         "--no-check", "-o", str(out / "sheet.svg")],
        check=True, capture_output=True,
    )
    scene = P.simulate(
        whycode_bin, out, "sheetview",
        ["--manifest", str(manifest), "--size", "640x480", "--fov", "60deg", "--camera-distance", "0.45m",
         "--tilt", "15deg", "--pan", "-5deg", "--roll", "10deg", "--noise", "1.5", "--seed", "9"],
    )
    cam = scene.truth["camera"]
    camera = out / "camera.yaml"
    camera.write_text(
        f"image_width: {scene.width}\nimage_height: {scene.height}\ncamera_name: sim\n"
        f"camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{cam['fx']}, 0.0, {cam['cx']}, 0.0, {cam['fy']}, {cam['cy']}, 0.0, 0.0, 1.0]\n"
        f"distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: {list(cam['distortion'])}\n"
    )
    on_page = {m["id"]: (m["x_mm"] / 1000, m["y_mm"] / 1000) for m in json.loads(manifest.read_text())["markers"]}
    # The sheet's corner markers as the arena: origin bottom left, +x bottom
    # right, +y top left (z up, out of the page, towards the camera).
    corners = (10, 12, 3, 1)
    size = f"{on_page[12][0] - on_page[10][0]:.6f},{on_page[10][1] - on_page[1][1]:.6f}"
    arena = out / "arena.yaml"
    (out / "sheetview.png").write_bytes(scene.png)
    subprocess.run(
        [str(whycode_bin), "arena", *FAMILY, "--ids", ",".join(map(str, corners)), "--size", size, "--camera", str(camera),
         str(out / "sheetview.png"), "-o", str(arena)],
        check=True, capture_output=True,
    )
    return SheetScene(scene, manifest, arena, on_page, corners)


@pytest.fixture
def domain() -> int:
    return next(_DOMAINS)


@pytest.fixture
def peer(domain):
    p = P.Peer(domain)
    yield p
    p.close()


@pytest.fixture
def start_node(node_bin, domain, tmp_path):
    """Starts whycode_node on the test's domain; every node is stopped at
    the end, and none may have panicked."""
    nodes: list[P.NodeProcess] = []
    counter = itertools.count()

    def start(*args: str, env: dict | None = None, domain_id: int | None = None) -> P.NodeProcess:
        node = P.NodeProcess(
            node_bin,
            ["--ros-args", *args],
            domain if domain_id is None else domain_id,
            tmp_path / f"node{next(counter)}.log",
            env,
        )
        nodes.append(node)
        return node

    yield start
    for node in nodes:
        node.stop()
        assert "panicked" not in node.log(), node.log()


def node_args(*extra: str, image: str = "/camera/image_raw") -> list[str]:
    """The arguments of a node reading the test frames from `image`."""
    return [
        "-p", "bits:=12",
        "-p", f"diameter:={DIAMETER_M}",
        "-r", f"image:={image}",
        *extra,
    ]
