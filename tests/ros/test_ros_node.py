"""The rclpy node itself; skipped where rclpy is not installed."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS 2) is not installed")


def test_node_matches_a_map_and_publishes_a_goal(tmp_path):
    from geometry_msgs.msg import PointStamped
    from rclpy.parameter import Parameter

    from ursim_core.io.maps import map_from_array
    from ursim_core.io.occupancy_grid import occupancy_grid_from_map
    from ursim_ros.node import UrsimSketchNode

    grey = np.zeros((52, 200), np.uint8)
    grey[1:51, 1:99], grey[1:51, 101:199], grey[20:30, 99:101] = 255, 255, 255
    Image.fromarray(grey).save(tmp_path / "sketch.png")
    rclpy.init()
    try:
        node = UrsimSketchNode(
            parameter_overrides=[
                Parameter("sketch_path", value=str(tmp_path / "sketch.png")),
                Parameter("use_action", value=False),
            ]
        )
        published = []
        node.goal_publisher.publish = published.append
        grid = occupancy_grid_from_map(map_from_array(grey > 0), resolution=0.05)

        node.navigator.set_map(grid)
        tap = PointStamped()
        tap.header.frame_id = "sketch"
        tap.point.x, tap.point.y = 50.0, 25.0
        node.on_tap(tap)
        assert len(published) == 1 and published[0].header.frame_id == "map"
        node.destroy_node()
    finally:
        rclpy.shutdown()
