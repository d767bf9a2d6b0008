"""Turned / mirrored sketches and their ground-truth points: the same transform on both."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation.augment import (
    DIHEDRAL,
    Orientation,
    parse_augment,
    transform_correspondences,
    transform_image,
    transform_map,
    transform_points,
    transformed_shape,
)


def _unique_image(rows=7, cols=11):
    # Every pixel has its own value, so "the same content" means "the same source pixel".
    return np.arange(1, rows * cols + 1, dtype=np.int64).reshape(rows, cols)


@pytest.mark.parametrize("orientation", DIHEDRAL, ids=lambda o: o.name)
def test_dihedral_is_a_pixel_permutation_and_points_follow_their_pixel(orientation):
    image = _unique_image()
    turned = transform_image(image, orientation, fill=0)
    assert sorted(turned.ravel().tolist()) == sorted(image.ravel().tolist())
    points = [(r, c) for r in range(image.shape[0]) for c in range(image.shape[1])]
    for (row, col), (new_row, new_col) in zip(points, transform_points(points, image.shape, orientation)):
        assert turned[new_row, new_col] == image[row, col]


def test_dihedral_matches_numpy_rot90_and_fliplr():
    image = _unique_image()
    assert np.array_equal(transform_image(image, Orientation(90)), np.rot90(image, 1))
    assert np.array_equal(transform_image(image, Orientation(270)), np.rot90(image, 3))
    assert np.array_equal(transform_image(image, Orientation(0, mirrored=True)), np.fliplr(image))
    assert np.array_equal(transform_image(image, Orientation(90, mirrored=True)), np.rot90(np.fliplr(image), 1))


@pytest.mark.parametrize("angle", [15, 30, 45, 100, 217.5, -30])
def test_any_angle_grows_the_canvas_fills_obstacle_and_points_keep_their_content(angle):
    image = _unique_image(23, 31)
    orientation = Orientation(angle)
    turned = transform_image(image, orientation, fill=0)
    assert turned.shape == transformed_shape(image.shape, orientation)
    assert turned.shape[0] * turned.shape[1] > image.size
    assert turned[0, 0] == 0 or angle % 90 == 0  # a corner of the canvas is new space
    present = set(turned.ravel().tolist())
    points = [(r, c) for r in range(image.shape[0]) for c in range(image.shape[1])]
    moved = transform_points(points, image.shape, orientation)
    kept = 0
    for (row, col), (new_row, new_col) in zip(points, moved):
        assert 0 <= new_row < turned.shape[0] and 0 <= new_col < turned.shape[1]
        if image[row, col] in present:
            kept += 1
            assert turned[new_row, new_col] == image[row, col]
    # Nearest-neighbour resampling drops few pixels; most points land on a copy of themselves.
    assert kept >= 0.8 * len(points)


def test_turning_back_returns_the_image_and_a_point_within_a_pixel():
    image = np.zeros((40, 60), np.uint8)
    image[5:30, 10:50] = 255
    there = transform_image(image, Orientation(30))
    back = transform_image(there, Orientation(-30))
    rows, cols = back.shape
    # The twice-turned canvas is larger; the original sits at its centre.
    top, left = (rows - 40) // 2, (cols - 60) // 2
    assert np.mean(back[top : top + 40, left : left + 60] == image) > 0.97


def test_parse_augment():
    assert [o.name for o in parse_augment("dihedral")] == [
        "rot0",
        "rot90",
        "rot180",
        "rot270",
        "mirror-rot0",
        "mirror-rot90",
        "mirror-rot180",
        "mirror-rot270",
    ]
    assert [o.name for o in parse_augment("angles=0,15,375")] == ["rot0", "rot15"]
    for bad in ("angles=", "angles=a", "rotate", "angles=inf"):
        with pytest.raises(ParameterError):
            parse_augment(bad)


def test_transform_map_and_correspondences_move_together():
    from ursim_core.correspondences import Clique, Correspondences, MapRef
    from ursim_core.io.maps import Map

    free = np.zeros((20, 30), bool)
    free[2:6, 3:9] = True
    the_map = Map(free=free, image=np.where(free, 255, 0).astype(np.uint8))
    clique = Clique(id=1, sketch_points=[(3, 4)], metric_points=[(1, 1)], sketch_regions=[1], metric_regions=[1])
    corr = Correspondences(sketch=MapRef(), metric=MapRef(), cliques=[clique])
    for orientation in (*DIHEDRAL, Orientation(33)):
        turned = transform_map(the_map, orientation)
        moved = transform_correspondences(corr, free.shape, orientation).cliques[0]
        row, col = moved.sketch_points[0]
        assert turned.free[row, col] and turned.image[row, col] == 255
        assert turned.free.sum() >= 0.9 * free.sum()
        assert moved.metric_points == ((1, 1),)
        assert moved.sketch_regions == () or orientation.is_identity
