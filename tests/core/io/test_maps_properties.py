"""Property tests of ursim_core.io.maps on random inputs (hypothesis)."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from ursim_core.errors import MapError
from ursim_core.io.maps import Map, load_map, map_from_array, pixel_to_world, world_to_pixel

shapes = st.tuples(st.integers(1, 12), st.integers(1, 12))
thresholds = st.integers(0, 254)


@settings(deadline=None)  # a shared, loaded CI machine: no per-example time limit
@given(grey=arrays(np.uint8, shapes), threshold=thresholds)
def test_free_is_grey_above_threshold(grey, threshold):
    expected = grey > threshold
    if not expected.any():
        with pytest.raises(MapError, match="no free pixel"):
            map_from_array(grey, threshold=threshold)
        return
    loaded = map_from_array(grey, threshold=threshold)
    np.testing.assert_array_equal(loaded.free, expected)
    np.testing.assert_array_equal(loaded.image, grey)


@settings(deadline=None)  # a shared, loaded CI machine: no per-example time limit
@given(rgb=arrays(np.uint8, st.tuples(st.integers(1, 8), st.integers(1, 8), st.just(3))))
def test_colour_grey_equals_opencv_rgb2gray(rgb):
    rgb[0, 0] = 255  # keep one free pixel so the map is valid
    loaded = map_from_array(rgb)
    np.testing.assert_array_equal(loaded.image, cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))


@settings(deadline=None)  # a shared, loaded CI machine: no per-example time limit
@given(words=arrays(np.uint16, shapes))
def test_16_bit_is_rounded_division_by_257(words):
    words[0, 0] = 65535
    # 257 is odd, so v / 257 is never exactly halfway and rint has no tie to break.
    expected = np.rint(words / 257.0).astype(np.uint8)
    np.testing.assert_array_equal(map_from_array(words, threshold=0).image, expected)


@settings(deadline=None)  # a shared, loaded CI machine: no per-example time limit
@given(
    rgba=arrays(np.uint8, st.tuples(st.integers(1, 8), st.integers(1, 8), st.just(4))),
    threshold=thresholds,
)
def test_transparent_pixels_are_never_free(rgba, threshold):
    rgba[0, 0] = 255
    loaded = map_from_array(rgba, threshold=threshold)
    assert not (loaded.free & (rgba[..., 3] < 128)).any()
    assert (loaded.image[rgba[..., 3] < 128] == 0).all()
    np.testing.assert_array_equal(loaded.free, loaded.image > threshold)


@settings(deadline=None)  # a shared, loaded CI machine: no per-example time limit
@given(
    resolution=st.floats(0.001, 10.0),
    origin_x=st.floats(-1e4, 1e4),
    origin_y=st.floats(-1e4, 1e4),
    yaw=st.floats(-2 * math.pi, 2 * math.pi),
    n_rows=st.integers(1, 5000),
    row=st.floats(-100, 5100),
    col=st.floats(-100, 5100),
)
def test_pixel_world_round_trip(resolution, origin_x, origin_y, yaw, n_rows, row, col):
    grid = Map(free=np.ones((n_rows, 1), bool), resolution=resolution, origin=(origin_x, origin_y, yaw))
    x, y = pixel_to_world(grid, row, col)
    back_row, back_col = world_to_pixel(grid, x, y)
    # Errors come from the metre-scale coordinates (up to ~1e4 m), divided by the resolution.
    tolerance = 1e-9 * (1 + (abs(origin_x) + abs(origin_y)) / resolution + n_rows)
    assert back_row == pytest.approx(row, abs=tolerance)
    assert back_col == pytest.approx(col, abs=tolerance)


@settings(max_examples=40, deadline=None)
@given(
    grey=arrays(np.uint8, shapes),
    free_thresh=st.floats(0.0, 0.9),
    gap=st.floats(0.01, 0.5),
    negate=st.integers(0, 1),
)
def test_ros_trinary_matches_nav2_formula(grey, free_thresh, gap, negate):
    occupied_thresh = min(1.0, free_thresh + gap)
    shade = grey / 255.0
    occ = shade if negate else 1.0 - shade
    expected = np.where(occ > occupied_thresh, 100, np.where(occ < free_thresh, 0, -1))
    with tempfile.TemporaryDirectory() as folder:
        Image.fromarray(grey).save(Path(folder) / "map.png")
        yaml_path = Path(folder) / "map.yaml"
        # safe_dump writes floats in a form YAML reads back exactly (1e-05 becomes 1.0e-05).
        document = {
            "image": "map.png",
            "resolution": 0.05,
            "origin": [0.0, 0.0, 0.0],
            "negate": negate,
            "free_thresh": free_thresh,
            "occupied_thresh": occupied_thresh,
        }
        yaml_path.write_text(yaml.safe_dump(document))
        if not (expected == 0).any():
            with pytest.raises(MapError, match="no free cell"):
                load_map(yaml_path)
            return
        loaded = load_map(yaml_path)
    np.testing.assert_array_equal(loaded.occupancy, expected)
    np.testing.assert_array_equal(loaded.free, expected == 0)
