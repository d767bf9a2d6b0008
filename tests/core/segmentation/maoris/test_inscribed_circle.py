"""MAORIS steps 1-2 (ursim_core.segmentation.maoris.inscribed_circle): inscribed circles, quantisation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from ursim_core.errors import ParameterError
from ursim_core.segmentation.maoris import inscribed_circle_image, inscribed_circle_radii, quantize

# --------------------------------------------------------------------------
# Reference implementations, deliberately naive


def brute_force_radii(free: np.ndarray, max_radius: int = 500) -> np.ndarray:
    """Paint, for every free q, the disc of radius r-1 centred at q-(1,1) (the C++ loop)."""
    rows, cols = free.shape
    # Without any obstacle the distance is unbounded (cv2 returns 1.8e19): every radius is the cap.
    distance = np.full(free.shape, float(max_radius)) if free.all() else ndi.distance_transform_edt(free)
    out = np.zeros(free.shape, int)
    for q_row, q_col in zip(*np.nonzero(free)):
        radius = min(int(distance[q_row, q_col]), max_radius)
        centre_row, centre_col, reach = q_row - 1, q_col - 1, radius - 1
        for p_row in range(max(centre_row - reach, 0), min(centre_row + reach + 1, rows)):
            for p_col in range(max(centre_col - reach, 0), min(centre_col + reach + 1, cols)):
                if (p_row - centre_row) ** 2 + (p_col - centre_col) ** 2 <= reach**2 and free[p_row, p_col]:
                    out[p_row, p_col] = max(out[p_row, p_col], radius)
    return out


# --------------------------------------------------------------------------
# Step 1: inscribed circles


@pytest.mark.parametrize(
    "shape_name",
    ["rectangle", "l_shape", "blobs", "touching_border"],
)
def test_inscribed_radii_equal_brute_force(shape_name):
    free = np.zeros((34, 41), bool)
    if shape_name == "rectangle":
        free[3:30, 5:38] = True
    elif shape_name == "l_shape":
        free[2:32, 2:12] = True
        free[22:32, 2:39] = True
    elif shape_name == "blobs":
        rng = np.random.default_rng(7)
        free = ndi.binary_opening(rng.random((34, 41)) < 0.7, iterations=1)
    else:  # free space reaching the image border (no obstacle margin there)
        free[:, 10:] = True
        free[15:20, 20:25] = False
    np.testing.assert_array_equal(inscribed_circle_radii(free), brute_force_radii(free))


def test_inscribed_radii_respects_max_radius():
    free = np.zeros((40, 40), bool)
    free[2:38, 2:38] = True
    np.testing.assert_array_equal(inscribed_circle_radii(free, max_radius=5), brute_force_radii(free, 5))
    assert inscribed_circle_radii(free, max_radius=5).max() == 5


def corridors_and_rooms(name: str) -> np.ndarray:
    """Maps whose disc centres form long equal-radius runs (corridor and room ridges)
    and diagonal chains of growing radius (room corners)."""
    if name == "horizontal_corridors":  # 9 and 8 rows wide: one ridge row, then two
        free = np.zeros((26, 90), bool)
        free[3:12, 2:88] = True
        free[15:23, 5:80] = True
        free[12:15, 30:33] = True
    elif name == "vertical_corridors":
        free = corridors_and_rooms("horizontal_corridors").T.copy()
    elif name == "rooms_odd_and_even":  # 21 x 33 and 22 x 30, and a door
        free = np.zeros((28, 72), bool)
        free[3:24, 2:35] = True
        free[3:25, 39:69] = True
        free[10:15, 35:39] = True
    elif name == "touching_border":  # a corridor across the image, a room and a corridor off its edges
        free = np.zeros((40, 50), bool)
        free[15:24, :] = True
        free[:12, 5:30] = True
        free[24:, 38:45] = True
    elif name == "diagonal_corridor":
        rows, cols = np.indices((40, 40))
        free = (abs(rows - cols) <= 5) & (rows > 1) & (rows < 38)
    else:  # no obstacle at all
        free = np.ones((12, 30), bool)
    return free


@pytest.mark.parametrize("max_radius", [500, 3, 2])
@pytest.mark.parametrize(
    "shape_name",
    [
        "horizontal_corridors",
        "vertical_corridors",
        "rooms_odd_and_even",
        "touching_border",
        "diagonal_corridor",
        "no_obstacle",
    ],
)
def test_inscribed_radii_of_corridors_and_rooms_equal_brute_force(shape_name, max_radius):
    # max_radius 3 and 2 are below the corridors' half-width: the capped radius
    # makes wide plateaus of equal radius, painted as rectangles.
    free = corridors_and_rooms(shape_name)
    np.testing.assert_array_equal(
        inscribed_circle_radii(free, max_radius=max_radius), brute_force_radii(free, max_radius)
    )


def test_inscribed_radii_shift_leaves_bottom_and_right_border_unlabelled():
    free = np.zeros((20, 20), bool)
    free[2:18, 2:18] = True
    radii = inscribed_circle_radii(free)
    # The C++ centres each disc at q - (1, 1): the last free row and column stay 0.
    assert not radii[17, 2:18].any() and not radii[2:18, 17].any()
    assert radii[2:17, 2:17].all()


def test_inscribed_image_is_min_max_normalised():
    free = np.zeros((30, 50), bool)
    free[2:28, 2:48] = True
    image = inscribed_circle_image(free)
    assert image.dtype == np.uint8
    assert image.max() == 255 and image[~free].max() == 0
    radii = inscribed_circle_radii(free)
    np.testing.assert_array_equal(image, np.rint(radii * 255.0 / radii.max()).astype(np.uint8))


def test_inscribed_on_empty_map_is_zero():
    assert not inscribed_circle_radii(np.zeros((5, 6), bool)).any()
    assert not inscribed_circle_image(np.zeros((5, 6), bool)).any()


# --------------------------------------------------------------------------
# Step 2: quantisation


def test_quantize_rounds_up_to_multiples():
    values = np.array([[0, 1, 4, 5, 6, 249, 250, 251, 255]], np.uint8)
    assert quantize(values).tolist() == [[0, 5, 5, 5, 10, 250, 250, 255, 255]]
    assert quantize(values, quantum=10).tolist() == [[0, 10, 10, 10, 10, 250, 250, 255, 255]]


def test_quantize_normalises_first():
    values = np.array([[0, 50, 100]], np.float32)
    assert quantize(values).tolist() == [[0, 130, 255]]  # 127.5 -> 128 -> 130


@pytest.mark.parametrize(
    ("dtype", "lo", "hi"),
    [
        (dtype, lo, hi)
        for dtype in (np.uint8, np.int16, np.uint16, np.int32, np.int64)
        for lo, hi in ((0, 0), (0, 1), (0, 70), (3, 200), (0, 255), (0, 256), (17, 900), (-5, 40))
        if np.iinfo(dtype).min <= lo and hi <= np.iinfo(dtype).max
    ],
)
def test_normalisation_of_integer_images_matches_opencv_on_floats(dtype, lo, hi):
    # Integer images go through a lookup table; it must be cv2.normalize of the float image, bit for bit.
    values = np.random.default_rng(hi).integers(lo, hi + 1, size=(23, 29)).astype(dtype)
    values[0, 0], values[-1, -1] = lo, hi
    as_float = values.astype(np.float32)
    expected = cv2.normalize(as_float, None, 0, 255, cv2.NORM_MINMAX, cv2.CV_8U)
    for quantum in (1, 5, 7):
        rounded = np.minimum(-(-expected.astype(np.int32) // quantum) * quantum, 255)
        np.testing.assert_array_equal(quantize(values, quantum=quantum), rounded)
        np.testing.assert_array_equal(quantize(as_float, quantum=quantum), rounded)


@pytest.mark.parametrize("dtype", [np.uint8, np.int32, np.uint16])
def test_quantize_and_normalise_leave_their_input_alone(dtype):
    # The lookup writes its result over its own 8-bit temporary, never over the caller's image.
    values = (np.arange(240).reshape(12, 20) % 200).astype(dtype)
    kept = values.copy()
    quantized = quantize(values)
    np.testing.assert_array_equal(values, kept)
    assert not np.shares_memory(quantized, values)
    from ursim_core.segmentation.maoris.inscribed_circle import _normalise_to_uint8, _quantization_table

    result = _normalise_to_uint8(values)
    np.testing.assert_array_equal(values, kept)
    assert not np.shares_memory(result, values)
    _quantization_table(values, 5)
    np.testing.assert_array_equal(values, kept)


def test_quantize_rejects_bad_quantum():
    with pytest.raises(ParameterError, match="quantum"):
        quantize(np.zeros((2, 2), np.uint8), quantum=0)
