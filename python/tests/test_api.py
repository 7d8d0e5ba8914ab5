"""Families, cameras and errors: the CLI's values and one-line messages."""

import json
import subprocess
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import whycode


def test_family_matches_whycode_ids(cli: Callable[..., Any], tmp_path: Path) -> None:
    family = whycode.Family(12, 3)
    cli("ids", "--bits", "12", "--distance", "3", "--format", "json", "-o", "f.json")
    assert family.to_json() == (tmp_path / "f.json").read_text()
    assert whycode.Family.load(tmp_path / "f.json") == family
    stored = json.loads(family.to_json())
    assert [(c.id, c.code, c.binary, c.self_distance) for c in family] == [
        (c["id"], c["code"], c["binary"], c["self_distance"]) for c in stored["codes"]]
    assert len(family) == stored["count"] and family.min_distance == stored["min_distance"]
    assert family[1].code == stored["codes"][0]["code"]
    with pytest.raises(IndexError):
        family[0]


def test_decode_reads_rotations_and_errors() -> None:
    family = whycode.Family(8, 3)
    for code in family:
        for r in range(8):
            word = ((code.code >> r) | (code.code << (8 - r))) & 0xFF
            d = family.decode(word)
            assert (d.id, d.status, d.errors) == (code.id, "exact", 0)
            assert ((word << d.rotation) | (word >> (8 - d.rotation))) & 0xFF == code.code
        flipped = family.decode(code.code ^ 0b1000)
        assert (flipped.id, flipped.status, flipped.errors) == (code.id, "corrected", 1)
    with pytest.raises(ValueError, match="more than 8 bits"):
        family.decode(256)


def test_family_counts_match_generated_families(cli: Callable[..., Any]) -> None:
    counts = whycode.family_counts([4, 8, 12], [1, 2, 3, 5])
    assert counts[(8, 2)] == len(whycode.Family(8, 2)) == 16
    assert (4, 5) not in counts
    table = cli("ids", "--counts", "--bits", "4,8,12", "--distance", "1,2,3,5",
                "--format", "csv").stdout.splitlines()
    assert table[0] == "bits,distance,count"
    rows = {(int(b), int(d)): int(c) for b, d, c in (line.split(",") for line in table[1:])}
    assert rows == counts


def test_camera_from_opencv_arrays(tmp_path: Path) -> None:
    k = np.array([[700.0, 0.0, 320.0], [0.0, 700.0, 240.0], [0.0, 0.0, 1.0]])
    for dist in (np.zeros(4), np.zeros((1, 5)), np.array([0.1, -0.2, 0.0, 0.0, 0.05, 0, 0, 0]), None):
        camera = whycode.Camera.from_opencv(k, dist, (640, 480))
        assert (camera.fx, camera.cy, camera.width) == (700.0, 240.0, 640)
        assert np.array_equal(camera.camera_matrix, k)
    with pytest.raises(whycode.WhycodeValueError, match="k4"):
        whycode.Camera.from_opencv(k, [0.1, 0.0, 0.0, 0.0, 0.0, 0.3], (640, 480))
    with pytest.raises(ValueError, match="focal"):
        whycode.Camera.from_opencv(np.diag([-1.0, 700.0, 1.0]), None, (640, 480))
    with pytest.raises(ValueError, match="camera_matrix"):
        whycode.Camera.from_opencv(np.eye(2), None, (640, 480))


def cli_error(cli: Callable[..., Any], *args: str) -> str:
    done = cli(*args, ok=False)
    assert done.returncode == 1
    line = done.stderr.strip()
    assert line.startswith("whycode: error: ")
    return str(line[len("whycode: error: "):])


def test_errors_carry_the_cli_messages(cli: Callable[..., Any], tmp_path: Path,
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("bad.json").write_text('{"format": "whycode-family", "bits": 8}')
    Path("bad.yaml").write_text("camera_matrix: {data: [1, 2]}\nimage_width: 640\n")
    Path("bad.png").write_bytes(b"\x89PNG\r\n\x1a\nnot really")
    Path("x.png").write_bytes(whycode.render_marker(1, diameter="20mm", format="png"))

    with pytest.raises(whycode.WhycodeValueError) as family_error:
        whycode.Family.load("bad.json")
    assert str(family_error.value) == cli_error(cli, "ids", "--family", "bad.json")

    with pytest.raises(whycode.WhycodeValueError) as camera_error:
        whycode.Camera.load("bad.yaml")
    assert str(camera_error.value) == cli_error(
        cli, "detect", "--camera", "bad.yaml", "--diameter", "1", "x.png")

    with pytest.raises(whycode.WhycodeOSError) as missing:
        whycode.validate("missing.json", ["x.png"])
    assert isinstance(missing.value, OSError) and isinstance(missing.value, whycode.WhycodeError)
    assert str(missing.value) == cli_error(cli, "validate", "--manifest", "missing.json", "x.png")

    with pytest.raises(whycode.WhycodeError) as broken:
        whycode.load_image("bad.png")
    assert str(broken.value) in cli_error(cli, "detect", "bad.png")

    with pytest.raises(whycode.WhycodeValueError) as out_of_range:
        whycode.render_marker(17, diameter="50mm", format="svg")
    # The same message, each front end spelling the option its own way.
    assert str(out_of_range.value).startswith("id: ID 17 is not in")
    assert "--" + str(out_of_range.value) == cli_error(
        cli, "marker", "--bits", "8", "--id", "17", "--diameter", "50mm", "-o", "m.svg")
    with pytest.raises(whycode.WhycodeOSError, match="does not exist"):
        whycode.render_sheet([1], output="no/such/folder/s.pdf")
    assert not Path("no").exists()


def test_nothing_is_written_over_on_failure(tmp_path: Path) -> None:
    target = tmp_path / "keep.svg"
    target.write_text("old")
    with pytest.raises(whycode.WhycodeValueError):
        whycode.render_marker(99, diameter="50mm", output=target)
    assert target.read_text() == "old"
