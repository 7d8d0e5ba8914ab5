"""Every array layout the issue names, and refusals with clear errors."""

import numpy as np
import pytest

import whycode


@pytest.fixture(scope="module")
def grey() -> np.ndarray:
    image, _ = whycode.simulate(ids=range(1, 7), size=(480, 360), camera_distance=0.6,
                                tilt=15, noise=2)
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
