"""Every array layout the issue names, and refusals with clear errors."""

import numpy as np
import pytest

import whycode


@pytest.fixture(scope="module")
def grey() -> np.ndarray:
    image, _ = whycode.simulate(ids=range(1, 7), size=(480, 360), camera_distance="0.6m",
                                tilt="15deg", noise=2)
    return image


@pytest.fixture(scope="module")
def reference(grey: np.ndarray) -> list[dict[str, object]]:
    found = [m.as_dict() for m in whycode.Detector().detect(grey)]
    assert sorted(m["id"] for m in found) == [1, 2, 3, 4, 5, 6]  # type: ignore[type-var]
    return found


def dicts(image: np.ndarray) -> list[dict[str, object]]:
    return [m.as_dict() for m in whycode.Detector().detect(image)]


def test_grey_layouts_give_the_same_markers(grey: np.ndarray, reference: list) -> None:
    assert dicts(np.asfortranarray(grey)) == reference
    assert dicts(grey[:, :, None]) == reference
    readonly = grey.copy()
    readonly.flags.writeable = False
    assert dicts(readonly) == reference
    # equal channels have the grey's own luma
    assert dicts(np.repeat(grey[:, :, None], 3, axis=2)) == reference
    bgra = np.dstack([grey, grey, grey, np.full_like(grey, 255)])
    assert dicts(bgra) == reference
    assert dicts(np.asfortranarray(bgra)) == reference


def test_views_are_read_through_their_strides(grey: np.ndarray) -> None:
    padded = np.zeros((grey.shape[0] + 20, grey.shape[1] + 30), np.uint8)
    padded[10:-10, 15:-15] = grey
    view = padded[10:-10, 15:-15]
    assert not view.flags.c_contiguous
    assert dicts(view) == dicts(np.ascontiguousarray(view))
    half = grey[::2, ::2]
    assert dicts(half) == dicts(np.ascontiguousarray(half))
    flipped = grey[::-1, ::-1]
    flipped_found = whycode.Detector().detect(flipped)
    assert sorted(m.id for m in flipped_found) == [1, 2, 3, 4, 5, 6]
    bgr = np.repeat(grey[:, :, None], 3, axis=2)
    assert dicts(bgr[:, :, ::-1]) == dicts(bgr)


def test_bgr_order_is_opencvs(grey: np.ndarray) -> None:
    # Pure blue in BGR has little luma, pure red more: a BGR array read as
    # RGB would swap them.
    blue = np.zeros((8, 8, 3), np.uint8)
    blue[..., 0] = 255
    red = np.zeros((8, 8, 3), np.uint8)
    red[..., 2] = 255
    assert whycode.Detector().detect(blue) == [] and whycode.Detector().detect(red) == []


def test_16_bit_arrays_are_stretched_like_16_bit_files(grey: np.ndarray) -> None:
    # As the loader reads a 16-bit file: the brightest value present becomes 255.
    for wide in (grey.astype(np.uint16) * 257, grey.astype(np.uint16) * 4 + 3):
        stretched = np.floor(wide * (255.0 / wide.max()) + 0.5).astype(np.uint8)
        assert dicts(wide) == dicts(stretched)
        assert len(dicts(wide)) == 6
        assert dicts(np.dstack([wide, wide, wide])) == dicts(stretched)


@pytest.mark.parametrize("shape", [(0, 0), (0, 10), (10, 0), (1, 1), (2, 2), (1, 500), (0, 0, 3)])
def test_tiny_and_empty_images_find_nothing(shape: tuple[int, ...]) -> None:
    for image in (np.zeros(shape, np.uint8), np.full(shape, 200, np.uint16)):
        assert whycode.Detector().detect(image) == []
        assert whycode.Detector(tracking=True).detect(image) == []


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int16, np.int32, np.uint32,
                                   np.int8, np.bool_, np.complex64])
def test_other_dtypes_are_refused_by_name(dtype: type) -> None:
    with pytest.raises(whycode.WhycodeValueError, match=f"dtype {np.dtype(dtype).name}"):
        whycode.Detector().detect(np.zeros((20, 20), dtype))


@pytest.mark.parametrize("bad, message", [
    (np.zeros(10, np.uint8), "shape"),
    (np.zeros((4, 4, 2), np.uint8), "shape"),
    (np.zeros((2, 4, 4, 3), np.uint8), "shape"),
    ([[0, 1], [2, 3]], "expected a numpy array, got list"),
    (None, "expected a numpy array"),
])
def test_non_images_are_refused(bad: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        whycode.Detector().detect(bad)  # type: ignore[arg-type]


def test_render_marker_image_is_detected() -> None:
    family = whycode.Family(10, 3)
    for code in family:
        image = whycode.render_marker_image(code.id, family=family, diameter_px=80)
        [marker] = whycode.Detector(family).detect(image)
        assert marker.id == code.id and marker.code == code.code
        assert abs(2 * marker.axes[0] - 80) < 2
    [legacy] = whycode.Detector(legacy=True).detect(whycode.render_marker_image(legacy=True))
    assert legacy.id == 0 and legacy.yaw is None


def test_a_whycode_detector_reports_legacy_markers_as_unknown() -> None:
    legacy = whycode.render_marker_image(legacy=True)
    found = whycode.Detector().detect(legacy)
    [marker] = found
    assert marker.id == 0 and marker.unknown == "no_code_ring" and found.legacy_looking == 1
    found = whycode.Detector().detect(whycode.render_marker_image(3))
    assert [m.id for m in found] == [3] and found.legacy_looking == 0
    assert found[0].unknown is None


def test_timings_give_each_stage_of_the_last_frame(grey: np.ndarray,
                                                    reference: list) -> None:
    assert whycode.Detector().last_timings() is None
    detector = whycode.Detector(timings=True)
    assert detector.last_timings() is None
    assert [m.as_dict() for m in detector.detect(grey)] == reference
    timings = detector.last_timings()
    assert timings is not None and timings["frames"] == 1
    stages = timings["stages_ms"]
    assert list(stages) == ["prepare", "follow", "threshold", "scan", "shade", "fallback",
                            "describe", "pose", "finish"]
    assert all(ms >= 0 for ms in stages.values())
    assert abs(sum(stages.values()) - timings["total_ms"]) < 1e-3  # each rounded to 0.1 us
    assert timings["total_ms"] > 0


def test_a_calibration_for_another_resolution_is_rescaled_or_refused() -> None:
    small = whycode.Camera.ideal(640, 360, 70.0)
    image, truth = whycode.simulate(ids=range(1, 5), diameter="0.05m", camera=small,
                                    camera_distance="0.9m", noise=2, seed=4)
    assert image.shape == (360, 640)
    # The same sensor calibrated at twice the resolution: the detector
    # rescales it, and the poses are those of the calibration that fits.
    full = whycode.Camera.ideal(1280, 720, 70.0)
    direct = whycode.Detector(diameter="50mm", camera=small).detect(image)
    rescaled = whycode.Detector(diameter="50mm", camera=full).detect(image)
    assert len(direct) == 4 and len(rescaled) == 4
    for a, b in zip(direct, rescaled):
        assert a.position is not None and b.position is not None
        assert np.allclose(a.position, b.position, atol=1e-6)
        true = next(t for t in truth["markers"] if t["id"] == a.id)
        assert abs(b.position[2] - true["position"][2]) < 0.01
    # Another aspect ratio is another camera: refused, never a wrong pose.
    other = whycode.Camera.ideal(1280, 960, 70.0)
    with pytest.raises(ValueError, match="image is 640x360 but the camera calibration is for 1280x960"):
        whycode.Detector(diameter="50mm", camera=other).detect(image)


def rodrigues(rvec: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(rvec))
    k = rvec / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def test_markers_carry_what_opencv_users_draw_and_solve_with() -> None:
    camera = whycode.Camera.ideal(640, 480, 60.0)
    image, _ = whycode.simulate(ids=range(1, 4), diameter="0.05m", camera=camera,
                                camera_distance="0.6m", tilt="25deg", noise=2, seed=5)
    found = whycode.Detector(diameter="50mm", camera=camera).detect(image)
    assert len(found) == 3
    for m in found:
        d = m.as_dict()
        assert m.bits == d["bits"] == 8
        assert -np.pi <= m.angle <= np.pi
        rvec, tvec, rotation, position = m.rvec, m.tvec, m.rotation, m.position
        assert rvec is not None and tvec is not None
        assert rotation is not None and position is not None
        assert np.allclose(rodrigues(rvec), rotation, atol=1e-9)
        assert np.array_equal(tvec, position)
    assert [m.rvec for m in whycode.Detector().detect(image)] == [None] * 3


def test_draw_returns_bgr_over_the_colours_given() -> None:
    image, _ = whycode.simulate(ids=range(1, 4), size=(320, 240), camera_distance="0.5m", seed=2)
    markers = whycode.Detector().detect(image)
    assert len(markers) == 3
    drawn = whycode.draw(image, markers)
    assert drawn.shape == (240, 320, 3) and drawn.dtype == np.uint8
    untouched = np.all(drawn == image[:, :, None], axis=2)
    assert 0 < np.count_nonzero(~untouched) < untouched.size // 4
    # A BGR frame keeps its colours where nothing is drawn, in its order.
    bgr = np.dstack([image, image // 2, image // 4])
    over = whycode.draw(bgr, markers)
    assert np.array_equal(over[untouched], bgr[untouched])
    assert np.array_equal(whycode.draw(bgr, []), bgr)
    # The known-ID outline is green in BGR order: (60, 200, 40) somewhere.
    assert np.any(np.all(over == [60, 200, 40], axis=2))


def test_tracked_markers_keep_their_track_numbers() -> None:
    detector = whycode.Detector(tracking=True)
    numbers = []
    for seed in (1, 1, 1):
        image, _ = whycode.simulate(ids=range(1, 4), size=(320, 240), camera_distance="0.5m",
                                    seed=seed)
        found = sorted(detector.detect(image), key=lambda m: m.id)
        numbers.append([m.track for m in found])
        assert [m.as_dict()["track"] for m in found] == numbers[-1]
    assert numbers[0] == numbers[1] == numbers[2]
    assert len(set(numbers[0])) == 3 and None not in numbers[0]
    assert all(m.track is None for m in whycode.Detector().detect(image))
