"""Checked by `mypy --strict` in CI: the stubs describe the API as users call it."""

from typing import Any

import numpy as np
import numpy.typing as npt

import whycode


def ids_in(image: npt.NDArray[np.uint8], family: whycode.Family) -> list[int]:
    detector = whycode.Detector(family, diameter="40mm", camera=whycode.Camera.ideal(640, 480))
    markers: list[whycode.Marker] = detector.detect(image)
    poses = [m.position for m in markers if m.position is not None]
    assert all(p.shape == (3,) for p in poses)
    return [m.id for m in markers]


def calibrated(photos: list[str]) -> dict[str, Any]:
    camera, report = whycode.calibrate("sheet.json", photos, no_k3=True, print_scale=0.97)
    camera.save("camera.yaml")
    camera.save("camera.xml", format="opencv-xml", camera_name="left")
    detector = whycode.Detector(camera=camera, boards=["sheet.json"])
    found: whycode.Detections = detector.detect(whycode.load_image(photos[0]))
    markers: list[whycode.Marker] = found
    boards: list[dict[str, Any]] = found.boards
    return {"report": report, "markers": len(markers), "boards": boards}


def summary() -> dict[str, object]:
    family = whycode.Family(bits=8, distance=2)
    codes: list[str] = [c.binary for c in family]
    decoded: whycode.Decoded = family.decode(0b00000111)
    counts: dict[tuple[int, int], int] = whycode.family_counts([8], [2])
    svg: bytes = whycode.render_marker(1, diameter="50mm", format="svg")
    pages, manifest = whycode.render_sheet([1, 2], family=family, format="pdf")
    image, truth = whycode.simulate(ids=[1, 2], size=(640, 480))
    report: dict[str, Any] = whycode.validate("swarm.json", [image])
    annotated = whycode.validate("swarm.json", ["photo.png"], annotate=True)[1]
    camera = whycode.Camera.from_opencv(np.eye(3), None, (640, 480))
    try:
        whycode.load_image("missing.png")
    except whycode.WhycodeOSError as e:
        print(e.errno, str(e))
    return {
        "codes": codes,
        "status": decoded.status,
        "counts": counts,
        "svg": len(svg),
        "pages": len(pages),
        "manifest": manifest,
        "ids": ids_in(image, family),
        "truth": truth,
        "report": report,
        "annotated": [a.shape for a in annotated],
        "fx": camera.fx,
    }
