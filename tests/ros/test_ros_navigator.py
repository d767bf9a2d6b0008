"""The ROS node's computations, without ROS: map in as an OccupancyGrid, goals, routes, markers."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import ursim_ros
from ursim_core.correspondences import Clique, Correspondences, save_correspondences
from ursim_core.errors import ParameterError
from ursim_core.io.maps import map_from_array, world_to_pixel
from ursim_core.io.occupancy_grid import OccupancyGrid, occupancy_grid_from_map
from ursim_ros.navigator import SketchNavigator


def rooms(n_rooms=3, width=60, height=50, door=10):
    grey = np.zeros((height + 2, n_rooms * (width + 4) + 2), np.uint8)
    for room in range(n_rooms):
        left = 1 + room * (width + 4)
        grey[1 : height + 1, left : left + width] = 255
        if room:
            grey[height // 2 - door // 2 : height // 2 + door // 2, left - 4 : left] = 255
    return grey


@pytest.fixture
def navigator(tmp_path):
    Image.fromarray(rooms()).save(tmp_path / "sketch.png")
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(25, 30)], metric_points=[(35, 45)], extra={"label": "office"}),
            Clique(id=2, sketch_points=[(25, 95)], metric_points=[(35, 140)]),
            Clique(id=3, sketch_points=[(25, 160)], metric_points=[(35, 235)]),
        )
    )
    save_correspondences(corr, tmp_path / "corr.json")
    return SketchNavigator(tmp_path / "sketch.png", correspondences=tmp_path / "corr.json")


def robot_grid():
    occupancy = np.where(rooms(width=90, height=70) > 0, 0, 100).astype(np.int8)
    occupancy[:, :2] = -1  # some unknown space
    the_map = map_from_array(occupancy == 0)
    the_map = type(the_map)(free=the_map.free, occupancy=occupancy, resolution=0.05, origin=(3.0, -1.0, 0.3))
    return occupancy_grid_from_map(the_map)


def test_message_dict_in_goal_out(navigator):
    assert not navigator.ready
    with pytest.raises(ParameterError, match="no map"):
        navigator.goal_for_tap(30, 25)
    grid = OccupancyGrid.from_message(robot_grid().to_message_dict())
    navigator.set_map(grid)
    assert navigator.ready
    goal = navigator.goal_for_tap(x=30, y=25)  # x = column, y = row
    assert goal.ok and goal.label == "office" and goal.clique_id == 1
    row, col = world_to_pixel(navigator.metric_map, goal.pose[0], goal.pose[1])
    assert (round(row), round(col)) == goal.pixel
    assert col < 95  # the left room of the robot map


def test_route_and_markers(navigator):
    navigator.set_map(robot_grid())
    route = navigator.route_for([(20, 25), (180, 25)])
    assert len(route.waypoints) == 3
    markers = navigator.markers()
    texts = [m["text"] for m in markers if m["type"] == "text"]
    assert len(texts) == 3 and "office" in texts
    strips = [m for m in markers if m["type"] == "line_strip"]
    assert all(len(m["points"]) >= 4 for m in strips)
    assert len({m["id"] for m in markers}) == len(markers)
    assert all(math.isfinite(v) for m in strips for p in m["points"] for v in p)


def test_empty_sketch_parameter_is_a_clear_error():
    with pytest.raises(ParameterError, match="sketch_path"):
        SketchNavigator("")


@pytest.mark.skipif(ursim_ros.rclpy_available(), reason="rclpy is installed: the node runs")
def test_without_rclpy_the_node_says_how_to_install_it():
    result = subprocess.run([sys.executable, "-m", "ursim_ros"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert result.stderr.startswith("error: the URSIM ROS 2 node needs rclpy") and "Jazzy" in result.stderr
    with pytest.raises(ImportError, match="needs rclpy"):
        import ursim_ros.node  # noqa: F401


def test_the_sketch_is_segmented_and_matched_as_ursim_match_does(tmp_path):
    # The navigator segmented the sketch with plain segment(): not in its canonical pose, no
    # resamplings for the vote, another pipeline than ursim match and ursim goal run.
    from ursim_core.io import load_map
    from ursim_core.matching import segment_for_matching

    Image.fromarray(np.rot90(rooms())).save(tmp_path / "sketch.png")  # drawn turned
    navigator = SketchNavigator(tmp_path / "sketch.png")
    expected = segment_for_matching(load_map(tmp_path / "sketch.png"), side="sketch")
    assert navigator.sketch_seg.params.get("canonical") is True
    assert np.array_equal(navigator.sketch_seg.labels, expected.labels)
    navigator.set_map(robot_grid())
    goal = navigator.goal_for_tap(x=25, y=160)  # the turned sketch's first room (column 25, row 160)
    assert goal.ok and goal.metric_region is not None
