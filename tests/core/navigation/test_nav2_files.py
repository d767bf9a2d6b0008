"""PoseStamped-like JSON and nav2's RViz-panel waypoint file."""

from __future__ import annotations

import math

import pytest
import yaml

from ursim_core.errors import FormatError, ParameterError
from ursim_core.navigation import load_waypoints_yaml, pose_stamped, save_waypoints_yaml, waypoints_yaml


def test_pose_stamped_quaternion_is_the_yaw():
    message = pose_stamped((1.0, -2.0, math.pi / 2))
    assert message["header"]["frame_id"] == "map"
    orientation = message["pose"]["orientation"]
    assert (orientation["z"], orientation["w"]) == pytest.approx((math.sqrt(0.5), math.sqrt(0.5)))


def test_waypoint_file_has_the_panels_layout(tmp_path):
    poses = [(1.0, 2.0, 0.0), (3.5, -1.25, math.pi / 2), (0.0, 0.0, -2.0)]
    document = yaml.safe_load(waypoints_yaml(poses))
    assert list(document["waypoints"]) == ["waypoint0", "waypoint1", "waypoint2"]
    second = document["waypoints"]["waypoint1"]
    assert second["pose"] == [3.5, -1.25, 0.0]
    # [w, x, y, z], as the panel's loader reads it.
    assert second["orientation"] == pytest.approx([math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)])
    save_waypoints_yaml(poses, tmp_path / "wps.yaml")
    loaded = load_waypoints_yaml(tmp_path / "wps.yaml")
    assert [list(p) for p in loaded] == [pytest.approx(list(p)) for p in poses]


def test_empty_and_bad_waypoint_files(tmp_path):
    with pytest.raises(ParameterError):
        waypoints_yaml([])
    (tmp_path / "bad.yaml").write_text("waypoints:\n  waypoint0: {pose: [1, 2]}\n")
    with pytest.raises(FormatError, match="waypoints.waypoint0"):
        load_waypoints_yaml(tmp_path / "bad.yaml")
    (tmp_path / "other.yaml").write_text("goals: []\n")
    with pytest.raises(FormatError, match="no 'waypoints'"):
        load_waypoints_yaml(tmp_path / "other.yaml")


def test_a_waypoint_file_that_is_a_pipe_or_missing_is_refused_naming_it(tmp_path):
    # It was read with read_text: a named pipe blocked the reader forever.
    import os

    pipe = tmp_path / "wps.yaml"
    os.mkfifo(pipe)
    with pytest.raises(FormatError, match="named pipe") as raised:
        load_waypoints_yaml(pipe)
    assert raised.value.path == pipe
    with pytest.raises(FileNotFoundError):
        load_waypoints_yaml(tmp_path / "gone.yaml")
