"""The bindings against the CLI on the same files: same bytes, same JSON
(to the last digit: dicts of floats compare exactly)."""

import json
import os
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np
import pytest

import whycode

# The original project's files, beside the repository; absent on a user's
# machine (the test skips), required where .ci/run or a CI system runs it.
COMPAT = Path(__file__).resolve().parents[2] / ".." / "shared" / "compat"
REQUIRED = os.environ.get("WHYCODE_REQUIRE_FIXTURES") == "1" or os.environ.get("CI", "") not in ("", "false")


@pytest.fixture
def sheet(tmp_path: Path, cli: Callable[..., Any], monkeypatch: pytest.MonkeyPatch) -> Path:
    """A 16-marker sheet written by the bindings (checked against the CLI's)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "cli").mkdir()
    pages, manifest = whycode.render_sheet(range(1, 17), diameter="40mm", output="swarm.pdf")
    cli("sheet", "--bits", "8", "--distance", "2", "--ids", "1-16", "--diameter", "40mm",
        "-o", "cli/swarm.pdf")
    assert (tmp_path / "swarm.pdf").read_bytes() == (tmp_path / "cli/swarm.pdf").read_bytes()
    assert pages == [(tmp_path / "swarm.pdf").read_bytes()]
    written = (tmp_path / "swarm.json").read_text()
    assert written == (tmp_path / "cli/swarm.json").read_text()
    assert manifest == json.loads(written)
    return tmp_path / "swarm.json"


def test_sheet_svg_and_png_pages_match_the_cli(tmp_path: Path, cli: Callable[..., Any],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "py").mkdir()
    for ext in ("svg", "png"):
        pages, manifest = whycode.render_sheet(range(1, 31), family=whycode.Family(8, 1),
                                               diameter="30mm", output=f"py/s.{ext}", dpi=100)
        cli("sheet", "--bits", "8", "--distance", "1", "--ids", "1-30", "--diameter", "30mm",
            "--dpi", "100", "-o", f"s.{ext}")
        assert len(pages) == manifest["pages"] >= 1
        for k, page in enumerate(pages, start=1):
            suffix = "" if len(pages) == 1 else f"-{k}"
            assert page == (tmp_path / f"py/s{suffix}.{ext}").read_bytes()
            assert page == (tmp_path / f"s{suffix}.{ext}").read_bytes()
        assert (tmp_path / "py/s.json").read_bytes() == (tmp_path / "s.json").read_bytes()
        assert [m["id"] for m in manifest["markers"]] == list(range(1, 31))


@pytest.mark.parametrize("ext", ["svg", "pdf", "png"])
def test_marker_bytes_match_the_cli(ext: str, tmp_path: Path, cli: Callable[..., Any]) -> None:
    data = whycode.render_marker(5, diameter="50mm", format=ext, cross=True, label=True)
    cli("marker", "--bits", "8", "--distance", "2", "--id", "5", "--diameter", "50mm",
        "--cross", "--label", "-o", f"m.{ext}")
    assert data == (tmp_path / f"m.{ext}").read_bytes()
    legacy = whycode.render_marker(legacy=True, diameter="122mm", format=ext)
    cli("marker", "--legacy", "--diameter", "122mm", "-o", f"w.{ext}")
    assert legacy == (tmp_path / f"w.{ext}").read_bytes()


def written_truth(path: Path, image: str) -> Any:
    """The CLI's ground truth less the digest of the image written with it
    (an in-memory truth has no file to name)."""
    truth = json.loads(path.read_text())
    files = truth.pop("files")
    assert [f["file"] for f in files] == [image]
    return truth


def test_simulate_detect_validate_match_the_cli(sheet: Path, tmp_path: Path,
                                                cli: Callable[..., Any],
                                                cli_json: Callable[..., Any]) -> None:
    image, truth = whycode.simulate(manifest=sheet, tilt="25deg", pan="-10deg", blur=1.5, noise=3, seed=7)
    cli("simulate", "--manifest", "swarm.json", "--tilt", "25deg", "--pan", "-10deg",
        "--blur", "1.5px", "--noise", "3", "--seed", "7", "-o", "view.png")
    assert np.array_equal(image, whycode.load_image(tmp_path / "view.png"))
    assert truth == written_truth(tmp_path / "view.json", "view.png")

    # detect: every marker object equal to the CLI's JSON
    [frame] = cli_json("detect", "--format", "json", "view.png")
    found = whycode.Detector().detect(whycode.load_image("view.png"))
    assert len(found) == len(frame["markers"]) >= 12
    assert [m.as_dict() for m in found] == frame["markers"]
    assert {m.id for m in found} <= {t["id"] for t in truth["markers"]}
    for m, record in zip(found, frame["markers"]):
        assert round(m.u, 3) == record["u"] and m.id == record["id"]

    # validate: the report is the CLI's JSON
    [report] = cli_json("validate", "--manifest", "swarm.json", "--format", "json", "view.png")
    assert whycode.validate("swarm.json", ["view.png"]) == report
    ours, pictures = whycode.validate("swarm.json", ["view.png"], annotate=True)
    assert ours == report
    assert pictures[0].shape == image.shape + (3,) and pictures[0].dtype == np.uint8
    # an array in place of the file: same verdict, named image1
    from_array = whycode.validate("swarm.json", [image])
    assert from_array["ok"] == report["ok"]
    assert json.dumps(from_array).replace('"image1"', '"view.png"') == json.dumps(report)


def test_pose_matches_the_cli(tmp_path: Path, cli: Callable[..., Any],
                              cli_json: Callable[..., Any]) -> None:
    camera = whycode.Camera.from_opencv(
        np.array([[800.0, 0, 321.5], [0, 805.0, 238.25], [0, 0, 1]]),
        np.array([-0.12, 0.05, 0.001, -0.0005, 0.0]), (640, 480))
    (tmp_path / "cam.yaml").write_text(camera.to_ros_yaml())
    assert whycode.Camera.load(tmp_path / "cam.yaml") == camera
    image, truth = whycode.simulate(family=whycode.Family(12, 2), ids=range(1, 10),
                                    diameter="0.05m", camera=camera, camera_distance="0.7m",
                                    tilt="30deg", noise=2, seed=3)
    cli("simulate", "--bits", "12", "--distance", "2", "--ids", "1-9", "--diameter", "50mm",
        "--camera", "cam.yaml", "--camera-distance", "0.7m", "--tilt", "30deg", "--noise", "2",
        "--seed", "3", "-o", "loose.png")
    assert np.array_equal(image, whycode.load_image(tmp_path / "loose.png"))
    [frame] = cli_json("detect", "--bits", "12", "--distance", "2", "--camera", "cam.yaml",
                       "--diameter", "50mm", "--format", "json", "loose.png")
    detector = whycode.Detector(whycode.Family(12, 2), diameter="50mm", camera=camera)
    found = detector.detect(image)
    assert [m.as_dict() for m in found] == frame["markers"]
    assert len(found) == 9
    for m in found:
        assert m.position is not None and m.rotation is not None and m.quaternion is not None
        assert m.rotation.shape == (3, 3)
        assert np.allclose(m.rotation @ m.rotation.T, np.eye(3), atol=1e-9)
        true = next(t for t in truth["markers"] if t["id"] == m.id)
        assert np.linalg.norm(m.position - np.array(true["position"])) < 0.01


@pytest.mark.parametrize("layout", ["grid", "scatter"])
def test_every_loose_layout_matches_the_cli(layout: Literal["grid", "scatter"], tmp_path: Path,
                                            cli: Callable[..., Any]) -> None:
    image, truth = whycode.simulate(ids=range(1, 9), layout=layout, size=(640, 480),
                                    camera_distance="0.9m", tilt="15deg", seed=4)
    cli("simulate", "--ids", "1-8", "--layout", layout, "--size", "640x480",
        "--camera-distance", "0.9m", "--tilt", "15deg", "--seed", "4", "-o", f"{layout}.png")
    assert np.array_equal(image, whycode.load_image(tmp_path / f"{layout}.png"))
    assert truth == written_truth(tmp_path / f"{layout}.json", f"{layout}.png")
    assert sorted(t["id"] for t in truth["markers"]) == list(range(1, 9))


def test_a_scatter_that_cannot_place_every_marker_is_refused_as_on_the_cli(
        tmp_path: Path, cli: Callable[..., Any]) -> None:
    # 16 markers of 20 cm at 30 cm from a small view cannot all fit.
    with pytest.raises(ValueError, match=r"^layout: only \d+ of 16 markers fit"):
        whycode.simulate(ids=range(1, 17), layout="scatter", size=(320, 240),
                         diameter="200mm", camera_distance="0.3m")
    out = cli("simulate", "--ids", "1-16", "--layout", "scatter", "--size", "320x240",
              "--diameter", "200mm", "--camera-distance", "0.3m", "-o", "s.png", ok=False)
    assert out.returncode == 1
    assert "--layout: only " in out.stderr and "of 16 markers fit" in out.stderr
    assert not (tmp_path / "s.png").exists()


def test_options_of_the_other_subject_are_refused_not_ignored(sheet: Path) -> None:
    with pytest.raises(ValueError, match="^diameter: describes loose markers"):
        whycode.simulate(manifest=sheet, diameter="30mm")
    with pytest.raises(ValueError, match="^print_scale: applies to a sheet's page"):
        whycode.simulate(ids=[1, 2], print_scale=0.97)


def test_quantities_are_read_as_the_cli_reads_them(cli: Callable[..., Any]) -> None:
    """A number means what it means typed on the command line without a
    unit, and a refusal carries the CLI's words."""
    for name, value, call in [
        ("tilt", "30", lambda: whycode.simulate(ids=[1], tilt=30)),
        ("camera_distance", "0.6", lambda: whycode.simulate(ids=[1], camera_distance=0.6)),
        ("diameter", "0.05", lambda: whycode.simulate(ids=[1], diameter=0.05)),
    ]:
        option = "--" + name.replace("_", "-")
        out = cli("simulate", "--ids", "1", option, value, "-o", "q.png", ok=False)
        assert out.returncode != 0
        with pytest.raises(ValueError) as err:
            call()
        message = str(err.value)
        assert message.startswith(f"{name}: '{value}' has no unit"), message
        assert message.removeprefix(f"{name}: ") in out.stderr, (message, out.stderr)
    with pytest.raises(ValueError, match="^diameter: '0.05' has no unit"):
        whycode.render_marker(1, diameter=0.05)
    # Where the command line takes bare metres or pixels, so does Python.
    image, _ = whycode.simulate(ids=[1, 2], size=(320, 240), camera_distance="0.5m",
                                tilt="20deg", blur=1, print_scale=None, seed=2)
    assert len(whycode.Detector().detect(image)) == 2
    with pytest.raises(ValueError, match="give camera too"):
        whycode.Detector(diameter=0.05)  # metres, as `detect --diameter 0.05`: no unit error
    assert whycode.simulate(ids=[1], size=(320, 240), blur="1px", seed=2)[0].tobytes() == \
        whycode.simulate(ids=[1], size=(320, 240), blur=1.0, seed=2)[0].tobytes()


def test_compat_files_match_the_cli(cli_json: Callable[..., Any]) -> None:
    if not COMPAT.is_dir():
        if REQUIRED:
            pytest.fail(f"the fixtures {COMPAT} are missing, and this run requires them")
        pytest.skip(f"the fixtures {COMPAT} are missing")
    many = COMPAT / "many.png"
    [frame] = cli_json("detect", "--legacy", "--format", "json", str(many))
    found = whycode.Detector(legacy=True).detect(whycode.load_image(many))
    assert [m.as_dict() for m in found] == frame["markers"]
    assert len(found) > 0 and all(m.id == 0 and m.code is None for m in found)


def write_pnm(path: Path, array: np.ndarray) -> None:
    """PGM/PPM writer (RGB order for colour, big-endian for 16 bits)."""
    height, width = array.shape[:2]
    magic = b"P6" if array.ndim == 3 else b"P5"
    maxval = 65535 if array.dtype == np.uint16 else 255
    data = array.astype(">u2").tobytes() if maxval == 65535 else array.tobytes()
    path.write_bytes(magic + f"\n{width} {height}\n{maxval}\n".encode() + data)


def test_colour_and_16_bit_arrays_match_the_cli_on_the_same_pixels(
        tmp_path: Path, cli_json: Callable[..., Any]) -> None:
    grey, _ = whycode.simulate(ids=range(1, 7), size=(480, 360), camera_distance="0.6m",
                               tilt="20deg", noise=2)
    rng = np.random.default_rng(1)
    tint = rng.integers(0, 30, size=grey.shape + (3,))
    bgr = np.clip(grey[..., None].astype(int) - tint, 0, 255).astype(np.uint8)
    write_pnm(tmp_path / "colour.ppm", bgr[..., ::-1])
    wide = (grey.astype(np.uint16) * 4 + rng.integers(0, 4, size=grey.shape)).astype(np.uint16)
    write_pnm(tmp_path / "wide.pgm", wide)
    detector = whycode.Detector()
    for name, array in (("colour.ppm", bgr), ("wide.pgm", wide)):
        [frame] = cli_json("detect", "--format", "json", name)
        assert [m.as_dict() for m in detector.detect(array)] == frame["markers"], name
        assert len(frame["markers"]) == 6
        assert np.array_equal(whycode.load_image(tmp_path / name).shape, grey.shape)
