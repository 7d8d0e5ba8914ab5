"""Calibration and boards through the bindings against the command line on
the same simulated photos: the same camera file byte for byte, the same
board poses, the same one-line refusals."""

import json
from pathlib import Path
from typing import Any, Callable

import pytest

import whycode

# A 1280x960 camera with a strongly barrel-distorting lens (issue 20's).
LENS = """image_width: 1280
image_height: 960
camera_name: lens
camera_matrix:
  rows: 3
  cols: 3
  data: [1000.0, 0.0, 643.0, 0.0, 1001.0, 478.0, 0.0, 0.0, 1.0]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.26, 0.085, 0.0004, -0.0003, -0.012]
"""

# (tilt, pan, roll) in degrees and distance in metres: the sheet turned
# about both axes, every way round, close enough that its corners reach
# towards the image's (the simulator keeps the page centred).
VIEWS = [
    (25, 0, 35, 0.3),
    (-25, 5, -35, 0.3),
    (0, 28, 55, 0.31),
    (5, -28, -55, 0.31),
    (20, 20, 30, 0.33),
    (-20, -20, -30, 0.33),
    (30, -15, 60, 0.35),
    (-15, 30, -60, 0.35),
    (32, 10, 90, 0.38),
    (10, -32, -90, 0.38),
]
FAMILY = whycode.Family(10, 2)


@pytest.fixture
def photos(tmp_path: Path, cli: Callable[..., Any]) -> list[str]:
    """The sheet's manifest (sheet.json), the lens (lens.yaml) and its
    photos, simulated by the command line in the test's folder."""
    (tmp_path / "lens.yaml").write_text(LENS)
    cli("sheet", "--bits", "10", "--ids", "1-24", "--diameter", "30mm", "--no-check",
        "-o", "sheet.svg")
    names = []
    for k, (tilt, pan, roll, distance) in enumerate(VIEWS):
        name = f"view{k:02}.png"
        cli("simulate", "--manifest", "sheet.json", "--camera", "lens.yaml",
            "--camera-distance", f"{distance}m", "--tilt", f"{tilt}deg", "--pan", f"{pan}deg",
            "--roll", f"{roll}deg", "--blur", "0.6px", "--noise", "1.5", "--seed", str(k + 1),
            "-o", name)
        names.append(name)
    return names


def test_calibrate_writes_the_cli_camera_and_reports_the_fit(
    photos: list[str], tmp_path: Path, cli: Callable[..., Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    cli("calibrate", "--manifest", "sheet.json", *photos, "-o", "cli.yaml")
    cli("calibrate", "--manifest", "sheet.json", *photos, "-o", "cli.xml")
    camera, report = whycode.calibrate("sheet.json", photos)
    camera.save("py.yaml")
    camera.save("py.xml")
    assert (tmp_path / "py.yaml").read_bytes() == (tmp_path / "cli.yaml").read_bytes()
    assert (tmp_path / "py.xml").read_bytes() == (tmp_path / "cli.xml").read_bytes()
    assert camera == whycode.Camera.load(tmp_path / "cli.yaml")

    # Never over what it was found from: the manifest, the pages it lists,
    # a photo; a camera loaded from a file may be saved over that file.
    pages = [f["file"] for f in json.loads((tmp_path / "sheet.json").read_text())["files"]]
    assert pages
    for source in ["sheet.json", *pages, photos[0]]:
        before = (tmp_path / source).read_bytes()
        with pytest.raises(ValueError, match="would overwrite"):
            camera.save(source)
        assert (tmp_path / source).read_bytes() == before
    whycode.Camera.load("py.yaml").save("py.yaml")

    # The lens comes back (the Rust round trip holds the figures; this
    # checks the report describes the fit that was written).
    truth = whycode.Camera.load(tmp_path / "lens.yaml")
    assert abs(camera.fx / truth.fx - 1) < 1e-3
    assert [v["label"] for v in report["views"]] == photos
    assert 0 < report["rms_px"] < 0.1
    assert all(0 < v["rms_px"] < 0.2 and v["markers"] >= 6 for v in report["views"])
    parameters = {p["name"]: p for p in report["parameters"]}
    assert list(parameters) == ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
    assert parameters["fx"]["value"] == pytest.approx(camera.fx, abs=1e-6)
    assert all(p["std_dev"] is not None and p["std_dev"] > 0 for p in parameters.values())
    assert sum(map(sum, report["coverage"])) == sum(v["markers"] for v in report["views"])
    assert all(isinstance(a, str) for a in report["advice"])

    # Arrays calibrate as their files do; options reach the fit as the
    # CLI's flags do.
    images = [whycode.load_image(tmp_path / p) for p in photos]
    held, held_report = whycode.calibrate("sheet.json", images, fix_aspect=True, no_k3=True)
    cli("calibrate", "--manifest", "sheet.json", *photos, "--fix-aspect", "--no-k3",
        "-o", "held.yml")
    held.save("held_py.yml")
    assert (tmp_path / "held_py.yml").read_bytes() == (tmp_path / "held.yml").read_bytes()
    assert held.fx == held.fy and held.distortion[4] == 0.0
    assert held_report["views"][0]["label"] == "image1"
    held_parameters = {p["name"]: p for p in held_report["parameters"]}
    assert held_parameters["fy"]["std_dev"] is None and held_parameters["k3"]["std_dev"] is None


def test_refusals_raise_the_cli_line(
    photos: list[str], tmp_path: Path, cli: Callable[..., Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    refused = cli("calibrate", "--manifest", "sheet.json", *photos[:2], "-o", "two.yaml", ok=False)
    assert refused.returncode != 0
    line = refused.stderr.strip()
    assert line.startswith("whycode: error: only 2 usable views (3 needed)"), line
    with pytest.raises(ValueError) as err:
        whycode.calibrate("sheet.json", photos[:2])
    assert f"whycode: error: {err.value}" == line
    assert isinstance(err.value, whycode.WhycodeValueError)

    with pytest.raises(ValueError, match="^print_scale: 97 is outside 0.2 to 5$"):
        whycode.calibrate("sheet.json", photos, print_scale=97)
    with pytest.raises(OSError):
        whycode.calibrate("missing.json", photos)
    with pytest.raises(ValueError, match="^format 'png' is not"):
        whycode.Camera.load("lens.yaml").save("lens.png", format="png")  # type: ignore[arg-type]
    # Saving never writes over what it would replace half-written, and a
    # missing folder is the operating system's refusal.
    with pytest.raises(OSError):
        whycode.Camera.load("lens.yaml").save("no/such/folder/camera.yaml")


def test_detector_boards_match_the_cli(
    photos: list[str], tmp_path: Path, cli_json: Callable[..., Any],
    monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    camera = whycode.Camera.load("lens.yaml")
    frames = cli_json("detect", "--bits", "10", "--camera", "lens.yaml", "--diameter", "30mm",
                      "--board", "sheet.json",
                      "--format", "json", *photos[:3])
    detector = whycode.Detector(FAMILY, diameter="30mm", camera=camera, boards=["sheet.json"])
    results = []
    for photo, frame in zip(photos[:3], frames):
        found = detector.detect(whycode.load_image(photo))
        results.append(found)
        assert isinstance(found, list) and isinstance(found, whycode.Detections)
        assert found.boards == frame["boards"]
        assert [m.as_dict() for m in found] == frame["markers"]
        board = found.boards[0]
        assert board["name"] == "sheet" and len(board["used"]) >= 20, board
        # The page's top-left corner, in front of the camera.
        assert 0.1 < board["position"][2] < 0.6, board

    # Without boards the result is the same list, with no poses.
    plain = whycode.Detector(FAMILY).detect(whycode.load_image(photos[0]))
    assert plain.boards == []
    assert sorted(m.id for m in plain) == sorted(m.id for m in results[0])

    with pytest.raises(ValueError, match="^boards: a board's pose needs the camera"):
        whycode.Detector(boards=["sheet.json"])
    with pytest.raises(OSError, match="missing.yaml"):
        whycode.Detector(camera=camera, boards=["missing.yaml"])
    (tmp_path / "bad.yaml").write_text("bundles: 3\n")
    with pytest.raises(ValueError, match="bad.yaml"):
        whycode.Detector(camera=camera, boards=["bad.yaml"])
