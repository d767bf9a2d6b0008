"""OccupancyGrid <-> Map, checked against the loader rules of nav2's map_io."""

from __future__ import annotations

import math

import numpy as np
import pytest
from io_helpers import SHAPES, YAWS, random_grid

from ursim_core.errors import MapError
from ursim_core.io.maps import pixel_to_world
from ursim_core.io.occupancy_grid import (
    OccupancyGrid,
    map_from_occupancy_grid,
    occupancy_grid_from_map,
    quaternion_from_yaw,
    yaw_from_quaternion,
)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("yaw", YAWS)
def test_grid_to_map_to_grid_is_identity(shape, yaw):
    grid = random_grid(shape, seed=shape[0] * 31 + shape[1], values=np.arange(-1, 101), yaw=yaw)
    the_map = map_from_occupancy_grid(grid.data, grid.width, grid.height, grid.resolution, grid.origin)
    assert occupancy_grid_from_map(the_map) == grid
    # The rows are flipped: the grid's first row is the image's bottom row.
    assert np.array_equal(the_map.occupancy[-1], grid.data[: grid.width])
    assert np.array_equal(the_map.free, the_map.occupancy == 0)


def test_origin_forms_and_quaternion_to_yaw():
    qx, qy, qz, qw = quaternion_from_yaw(0.9)
    message = {
        "header": {"frame_id": "map"},
        "info": {
            "width": 2,
            "height": 1,
            "resolution": 0.1,
            "origin": {"position": {"x": 3.0, "y": 4.0, "z": 0.0}, "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}},
        },
        "data": [0, 100],
    }
    grid = OccupancyGrid.from_message(message)
    assert grid.origin == pytest.approx((3.0, 4.0, 0.9))
    assert OccupancyGrid.from_message(grid.to_message_dict()) == grid
    seven = map_from_occupancy_grid([0, 100], 2, 1, 0.1, (3.0, 4.0, 0.0, qx, qy, qz, qw))
    assert seven.origin == pytest.approx((3.0, 4.0, 0.9))
    # An unnormalised quaternion is normalised first, as tf2 does.
    assert yaw_from_quaternion(0, 0, 2 * qz, 2 * qw) == pytest.approx(0.9)


def test_cell_zero_lies_at_the_origin_in_world_coordinates():
    yaw = 0.6
    the_map = map_from_occupancy_grid([0] * 12, 4, 3, 0.5, (10.0, 20.0, yaw))
    x, y = pixel_to_world(the_map, 2, 0)  # bottom-left pixel = grid cell (0, 0)
    centre = np.array([0.25, 0.25])
    rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    assert (x, y) == pytest.approx(tuple(np.array([10.0, 20.0]) + rotation @ centre))


@pytest.mark.parametrize(
    "problem, call",
    [
        ("cells", lambda: map_from_occupancy_grid([0, 0, 0], 2, 2, 0.1)),
        ("no free cell", lambda: map_from_occupancy_grid([100, -1], 2, 1, 0.1)),
        ("tilts", lambda: map_from_occupancy_grid([0], 1, 1, 0.1, (0, 0, 0, 0.3, 0.0, 0.0, 0.95))),
        ("not a rotation", lambda: map_from_occupancy_grid([0], 1, 1, 0.1, (0, 0, 0, 0, 0, 0, 0))),
        ("resolution", lambda: map_from_occupancy_grid([0], 1, 1, 0.0)),
        ("int8", lambda: map_from_occupancy_grid([0, 300], 2, 1, 0.1)),
    ],
)
def test_bad_grids_raise_map_error(problem, call):
    with pytest.raises(MapError, match=problem):
        call()


def test_a_grid_whose_corners_overflow_is_refused():
    with pytest.raises(MapError, match="from the world origin") as raised:
        OccupancyGrid(data=[0] * 4, width=2, height=2, resolution=1e306, origin=(1.7e308, 0.0, 0.0))
    assert raised.value.field == "origin"


def test_a_2d_data_array_of_shape_height_width_is_the_grid():
    cells = np.array([[0, 0, 100], [-1, 0, 0]])  # (height 2, width 3), row 0 at the origin
    the_map = map_from_occupancy_grid(cells, 3, 2, 0.05)
    assert np.array_equal(the_map.occupancy, cells[::-1])
    assert np.array_equal(the_map.occupancy, map_from_occupancy_grid(cells.ravel(), 3, 2, 0.05).occupancy)


@pytest.mark.parametrize(
    "shape",
    [(3, 2), (1, 6), (6, 1), (1, 2, 3)],
    ids=["width-height-swapped", "one-row", "one-column", "3-d"],
)
def test_a_multi_dimensional_data_array_of_another_shape_is_refused(shape):
    # The same six cells: ravel() used to read them as a 2 x 3 grid, garbled.
    cells = np.zeros(shape, dtype=np.int64)
    with pytest.raises(MapError, match=r"field 'data'.*\(height, width\) is \(2, 3\).*swapped") as raised:
        map_from_occupancy_grid(cells, 3, 2, 0.05, path="scan.yaml")
    assert str(raised.value).startswith("scan.yaml: ") and "\n" not in str(raised.value)
