"""Arena coordinates from Python against the CLI on the same photo: the
arena file `Arena.measure` makes is the one `whycode arena` writes, and
`Detector(arena=...)` gives every marker the `arena` object `whycode detect
--arena` prints."""

from pathlib import Path
from typing import Any, Callable

import pytest

import whycode


@pytest.mark.parametrize("with_camera", [False, True])
def test_arena_matches_the_cli(with_camera: bool, tmp_path: Path, cli: Callable[..., Any],
                               cli_json: Callable[..., Any]) -> None:
    camera = whycode.Camera.ideal(1280, 960, 60.0)
    (tmp_path / "cam.yaml").write_text(camera.to_ros_yaml())
    # Eight markers in a 4 x 2 grid, 100 mm apart: 5 bottom left, 8 bottom
    # right, 4 top right, 1 top left: a 0.3 m x 0.1 m rectangle.
    cli("simulate", "--ids", "1-8", "--diameter", "50mm", "--camera", "cam.yaml",
        "--camera-distance", "0.6m", "--tilt", "20deg", "--seed", "3", "-o", "view.png")
    image = whycode.load_image(tmp_path / "view.png")
    camera_args = ["--camera", "cam.yaml"] if with_camera else []
    cli("arena", "--ids", "5,8,4,1", "--size", "0.3m,0.1m", *camera_args, "view.png",
        "-o", "arena.yaml")
    arena = whycode.Arena.measure(image, ("0.3m", "0.1m"), ids=[5, 8, 4, 1],
                                  camera=camera if with_camera else None)
    assert arena.to_yaml() == (tmp_path / "arena.yaml").read_text()
    assert arena.ids == (5, 8, 4, 1) and arena.size == (0.3, 0.1)
    assert (arena.camera is not None) == with_camera

    diameter = ["--diameter", "50mm"] if with_camera else []
    [frame] = cli_json("detect", "--arena", "arena.yaml", *diameter, "--format", "json",
                       "view.png")
    for given in (arena, tmp_path / "arena.yaml", str(tmp_path / "arena.yaml")):
        detector = whycode.Detector(arena=given, diameter="50mm" if with_camera else None)
        found = detector.detect(image)
        assert [m.as_dict() for m in found] == frame["markers"]
    assert len(found) == 8
    corner = next(m for m in found if m.id == 8)
    assert corner.arena is not None
    assert corner.arena["x"] == pytest.approx(0.3, abs=2e-3)
    assert corner.arena["y"] == pytest.approx(0.0, abs=2e-3)


def test_arena_refusals_are_value_errors(tmp_path: Path, cli: Callable[..., Any]) -> None:
    image, _ = whycode.simulate(ids=range(1, 9), diameter="0.05m", seed=3)
    with pytest.raises(whycode.WhycodeValueError, match="corner ID 99 is not among"):
        whycode.Arena.measure(image, (0.3, 0.1), ids=[5, 8, 4, 99])
    with pytest.raises(whycode.WhycodeValueError, match="ids: give four IDs"):
        whycode.Arena.measure(image, (0.3, 0.1), ids=[5, 8, 4])
    (tmp_path / "bad.yaml").write_text("format: whycode-arena\n")
    with pytest.raises(whycode.WhycodeValueError, match="bad.yaml: not an arena file"):
        whycode.Detector(arena=tmp_path / "bad.yaml")
    with pytest.raises(whycode.WhycodeOSError):
        whycode.Detector(arena=tmp_path / "missing.yaml")
