"""The compiled marker flooding gives scikit-image's watershed labels, ties included."""

from __future__ import annotations

import numpy as np
import pytest
from skimage.segmentation import watershed

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.segmentation.flooding import clearance_levels, flood_levels, watershed_flood


def _random_case(rng: np.random.Generator):
    """A small image of few distinct values (plateaus everywhere), many markers that
    share few labels (equal markers of several labels on one value), maybe a mask."""
    shape = tuple(int(side) for side in rng.integers(1, 36, 2))
    image = rng.integers(0, int(rng.integers(1, 6)), shape).astype(float)
    if rng.random() < 0.3:
        image = np.where(image == 0, rng.choice([-0.0, 0.0], shape), image - 2.5)  # signed zeros, negatives
    markers = np.zeros(shape, np.int32)
    count = int(rng.integers(1, max(2, markers.size // 3)))
    labels = rng.choice(np.array([-3, 1, 2, 3, 7]), count)
    markers.flat[rng.integers(0, markers.size, count)] = labels
    mask = None if rng.random() < 0.3 else rng.random(shape) < rng.choice([0.95, 0.8, 0.6])
    return image, markers, mask


@pytest.mark.parametrize("connectivity", [1, 2])
def test_random_images_with_ties_flood_as_scikit_image(connectivity):
    rng = np.random.default_rng(20261202 + connectivity)
    differing = []
    for case in range(400):
        image, markers, mask = _random_case(rng)
        expected = watershed(image, markers, connectivity=connectivity, mask=mask)
        got = watershed_flood(image, markers, mask=mask, connectivity=connectivity)
        assert got.dtype == np.int32
        if not np.array_equal(got, expected):
            differing.append(case)
    assert differing == []


def test_symmetric_plateaus_split_as_scikit_image():
    # Equal markers of two labels on a flat image: only the heap's order decides the
    # pixels half-way between them.
    for shape in ((9, 9), (10, 31), (31, 10)):
        image = np.zeros(shape)
        markers = np.zeros(shape, np.int32)
        markers[0, ::2] = 1
        markers[-1, 1::2] = 2
        markers[shape[0] // 2, shape[1] // 2] = 3
        for connectivity in (1, 2):
            expected = watershed(image, markers, connectivity=connectivity)
            np.testing.assert_array_equal(watershed_flood(image, markers, connectivity=connectivity), expected)


def test_clearance_floods_of_generated_buildings_are_scikit_images():
    import cv2
    from scipy import ndimage

    from ursim_core.synth import make_large_building

    for size, seed in ((300, 1), (500, 7)):
        free = make_large_building(size, seed=seed).free
        clearance = np.ascontiguousarray(
            cv2.distanceTransform(np.pad(free, 1).view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)[1:-1, 1:-1]
        )
        peaks = free & (clearance >= ndimage.maximum_filter(clearance, size=3))
        markers, count = ndimage.label(peaks, structure=np.ones((3, 3), bool))
        assert count > 10
        expected = watershed(-clearance, markers, mask=free)
        np.testing.assert_array_equal(flood_levels(clearance_levels(clearance, free), markers, free), expected)


def test_clearance_levels_rank_the_values_largest_first():
    rng = np.random.default_rng(3)
    roots = np.sqrt(np.arange(0, 80)).astype(np.float32)  # a distance transform's values
    for case in range(60):
        shape = tuple(int(side) for side in rng.integers(1, 25, 2))
        clearance = rng.choice(roots, shape)
        if case % 3 == 0:  # not square roots of integers: ranked by numpy instead
            clearance = (rng.random(shape) * 9).astype(np.float32)
        free = rng.random(shape) < 0.8
        keys = -clearance.astype(np.float64)
        expected = np.where(free, np.searchsorted(np.unique(keys[free]), keys), 0)
        np.testing.assert_array_equal(clearance_levels(clearance, free), expected)


def test_levels_beyond_the_kernels_words_are_flooded_by_scikit_image():
    levels = np.array([[0, 10**6, 5, 10**6, 0], [7, 7, 7, 7, 7]], np.uint32)  # not ranks: the fallback
    markers = np.asfortranarray(np.array([[1, 0, 0, 0, 2], [0, 0, 0, 0, 0]]))
    mask = np.ones(levels.shape, bool)
    expected = watershed(levels, markers, mask=mask)
    np.testing.assert_array_equal(flood_levels(levels, markers, mask), expected)
    ranks = np.searchsorted(np.unique(levels), levels).astype(np.uint32)
    np.testing.assert_array_equal(flood_levels(ranks, markers, mask), expected)


def test_bad_input_is_refused_with_a_typed_error():
    image, markers = np.zeros((3, 4)), np.zeros((3, 4), np.int32)
    with pytest.raises(ParameterError, match="connectivity"):
        watershed_flood(image, markers, connectivity=3)
    with pytest.raises(SegmentationError, match="NaN"):
        watershed_flood(np.full((3, 4), np.nan), markers)
    with pytest.raises(SegmentationError, match="shape"):
        watershed_flood(image, np.zeros((4, 3), np.int32))
    with pytest.raises(SegmentationError, match="-2"):
        watershed_flood(image, np.full((3, 4), np.iinfo(np.int32).min, np.int64))
    with pytest.raises(SegmentationError, match="float32"):
        clearance_levels(image, np.ones((3, 4), bool))


def test_ahead_of_time_flooding_gives_the_jit_labels(monkeypatch):
    from ursim_core.segmentation.maoris import compile_kernels, compiled
    from ursim_core.segmentation.watershed import watershed_labels
    from ursim_core.synth import make_large_building

    compile_kernels()
    free = make_large_building(400, seed=2).free
    labels = {}
    for way in ("ahead", "jit"):
        monkeypatch.setenv("URSIM_KERNELS", way)
        compiled.forget()
        assert compiled.kernels().source == way
        labels[way] = watershed_labels(free, min_size=0, door_ratio=1.0)
    compiled.forget()
    assert int(labels["jit"].max()) > 5
    np.testing.assert_array_equal(labels["ahead"], labels["jit"])
