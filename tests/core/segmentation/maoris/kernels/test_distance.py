"""MAORIS step 1's distance transform (kernels/distance.py, csrc/distance.c): exact, OpenCV's floats."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_core.segmentation.maoris.kernels import distance


def _opencv(free: np.ndarray) -> np.ndarray:
    return cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)


def _exact(free: np.ndarray) -> np.ndarray:
    """Brute force: the squared distance from every pixel to every obstacle pixel."""
    obstacles = np.argwhere(free == 0)
    rows, cols = np.indices(free.shape)
    squared = ((rows[..., None] - obstacles[:, 0]) ** 2 + (cols[..., None] - obstacles[:, 1]) ** 2).min(axis=-1)
    return np.sqrt(squared.astype(np.float32))


def _numba(free: np.ndarray, out: np.ndarray) -> None:
    """The numba kernel on a strided copy of ``free``: its one signature takes any layout (a
    contiguous mask would compile another, which test_kernel_startup forbids)."""
    strided = np.zeros((free.shape[0], 2 * free.shape[1] + 1), np.uint8)[:, : 2 * free.shape[1] : 2]
    strided[...] = free
    assert not strided.flags.c_contiguous
    distance.distance_transform(strided, out)


def _masks(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for index in range(count):
        rows, cols = rng.integers(4, 50, 2)
        free = (rng.random((rows, cols)) > rng.uniform(0.01, 0.6)).astype(np.uint8)
        if index % 3 == 0:  # rooms: wide free areas, some columns and rows without any obstacle
            free = cv2.dilate(free, np.ones((5, 5), np.uint8))
        if index % 4 == 0:
            free = free[1:, 2:]  # a strided view, as the segmentation's window of the map is
        yield free


def test_hand_worked_distances():
    row = np.array([[0, 1, 1, 1, 1]], np.uint8)
    out = np.empty(row.shape, np.float32)
    _numba(row, out)
    assert out.tolist() == [[0, 1, 2, 3, 4]]
    corner = np.ones((3, 3), np.uint8)
    corner[0, 0] = 0
    _numba(corner, out := np.empty((3, 3), np.float32))
    assert np.allclose(out, [[0, 1, 2], [1, 2**0.5, 5**0.5], [2, 5**0.5, 8**0.5]])


def test_distances_are_exact_and_floor_as_opencvs():
    """Exact squared distances, so each float is sqrt of an integer, correctly rounded. OpenCV's
    floats are off by an ulp or two at times (its parabolas' breakpoints are products with
    rounded inverses), never across an integer: the radii (``int(distance)``, all the
    segmentation reads of them) are the same."""
    for free in _masks(300, seed=1):
        got = np.empty(free.shape, np.float32)
        _numba(free, got)
        if (free == 0).any():
            assert np.array_equal(got, _exact(free))
        opencv = _opencv(free)
        assert np.array_equal(np.minimum(got, 1e9).astype(np.int64), np.minimum(opencv, 1e9).astype(np.int64))


def test_an_image_without_obstacles_and_an_empty_one():
    free = np.ones((4, 6), np.uint8)
    out = np.zeros(free.shape, np.float32)
    _numba(free, out)
    assert (out == np.float32(2.0**64)).all() and (_opencv(free) > 1e18).all()
    # Nothing to do (an empty array is contiguous to numba: its Python body, not a new signature).
    distance.distance_transform.py_func(np.ones((0, 5), np.uint8), np.empty((0, 5), np.float32))
    with pytest.raises(ValueError, match="differ in shape"):
        _numba(free, np.empty((4, 5), np.float32))


@pytest.fixture
def c_kernel(c_module):
    return c_module.distance_transform


def test_the_c_kernel_is_numbas_in_bands_and_parts_of_columns(c_kernel):
    """From 2**21 px the columns are swept in parts and the rows in bands, one thread each:
    the floats are numba's to the bit, also for columns and rows without any obstacle."""
    from ursim_core.synth import make_large_building

    free = make_large_building(1500, seed=5).free.view(np.uint8)
    free = np.ascontiguousarray(free)
    free[:, 700:760] = 1  # columns without an obstacle from top to bottom
    free[:40, :] = 1  # rows without one
    rng = np.random.default_rng(3)
    free[rng.random(free.shape) < 0.002] = 0
    assert free.size >= 1 << 21
    strided = np.zeros((free.shape[0], 2 * free.shape[1]), np.uint8)[:, ::2]
    strided[...] = free
    got, want = np.empty(free.shape, np.float32), np.empty(free.shape, np.float32)
    c_kernel(strided, got)
    distance.distance_transform(strided, want)
    assert np.array_equal(got.view(np.int32), want.view(np.int32))
    for free in _masks(100, seed=2):
        got, want = np.empty(free.shape, np.float32), np.empty(free.shape, np.float32)
        c_kernel(free, got)
        _numba(free, want)
        assert np.array_equal(got.view(np.int32), want.view(np.int32))


def test_sides_beyond_the_exact_arithmetic_are_refused(c_kernel):
    free = np.ones((1, distance.MAX_SIDE), np.uint8)
    out = np.empty(free.shape, np.float32)
    for kernel in (c_kernel, _numba):
        with pytest.raises(ValueError, match="2\\*\\*20"):
            kernel(free, out)
