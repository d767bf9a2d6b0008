"""Goals and routes as ROS / nav2 data: PoseStamped-like JSON and nav2's waypoint file.

- :func:`pose_stamped` gives the fields of a ``geometry_msgs/PoseStamped`` as plain data (frame
  "map"), what ``ursim goal`` prints and what the ROS node publishes.
- :func:`waypoints_yaml` writes the YAML that nav2's RViz panel saves and loads ("Save WPs" /
  "Load WPs" of ``nav2_rviz_plugins``): a ``waypoints`` map of ``waypoint0``, ``waypoint1``, ...
  each with ``pose: [x, y, z]`` and ``orientation: [w, x, y, z]`` (the panel's order, w first).
  The panel appends ``.yaml`` to the name it is given; give it the name without the suffix.

Source check: the save / load / loop buttons came with ros-navigation/navigation2 PR #3165
("Feature - load, save and loop waypoints", merged 2023-01-06, Iron and later). The indexed
upstream copies of ``nav2_rviz_plugins/src/nav2_panel.cpp`` predate it, but a fork carrying it
(YazawaKenichi/navigation2 at 7f7c97eb, ``Nav2Panel::handleGoalSaver``) writes exactly this: a
``waypoints`` map, keys ``"waypoint" + std::to_string(i)``, each with ``pose`` = {x, y, z} and
``orientation`` = {w, x, y, z} of the pose (that fork adds a ``wait`` key of its own, which
upstream's loader does not read); its ``handleGoalLoader`` reads the same ``pose`` and ``orientation`` keys.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from ursim_core.errors import FormatError, ParameterError
from ursim_core.io.atomic import atomic_write_text

__all__ = ["pose_stamped", "waypoints_yaml", "save_waypoints_yaml", "load_waypoints_yaml", "quaternion_xyzw"]


def quaternion_xyzw(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``yaw`` about z.

    >>> quaternion_xyzw(0.0)
    (0.0, 0.0, 0.0, 1.0)
    """
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def pose_stamped(pose: Sequence[float], *, frame_id: str = "map", stamp: dict | None = None) -> dict[str, Any]:
    """A ``geometry_msgs/PoseStamped`` as plain data, from (x, y, yaw).

    Examples
    --------
    >>> pose_stamped((1.0, 2.0, 0.0))["pose"]
    {'position': {'x': 1.0, 'y': 2.0, 'z': 0.0}, 'orientation': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0}}
    """
    x, y, yaw = (float(v) for v in pose)
    qx, qy, qz, qw = quaternion_xyzw(yaw)
    return {
        "header": {"frame_id": frame_id, "stamp": stamp or {"sec": 0, "nanosec": 0}},
        "pose": {"position": {"x": x, "y": y, "z": 0.0}, "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}},
    }


def waypoints_yaml(poses: Iterable[Sequence[float]]) -> str:
    """The text of a nav2 RViz-panel waypoint file for (x, y, yaw) poses.

    >>> print(waypoints_yaml([(1.0, 2.0, 0.0)]), end="")
    waypoints:
      waypoint0:
        pose: [1.0, 2.0, 0.0]
        orientation: [1.0, 0.0, 0.0, 0.0]
    """
    lines = ["waypoints:"]
    count = 0
    for index, pose in enumerate(poses):
        x, y, yaw = (float(v) for v in pose)
        qx, qy, qz, qw = quaternion_xyzw(yaw)
        lines += [
            f"  waypoint{index}:",
            f"    pose: [{x!r}, {y!r}, 0.0]",
            f"    orientation: [{qw!r}, {qx!r}, {qy!r}, {qz!r}]",
        ]
        count += 1
    if count == 0:
        raise ParameterError("no pose to write: a waypoint file needs at least one georeferenced goal")
    return "\n".join(lines) + "\n"


def save_waypoints_yaml(poses: Iterable[Sequence[float]], path: str | Path) -> None:
    """Write :func:`waypoints_yaml` to ``path`` atomically.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "route.yaml"
    >>> save_waypoints_yaml([(1.0, 2.0, 0.0)], path)  # (x, y, yaw) in the map frame
    >>> print(path.read_text(), end="")  # the orientation quaternion is [w, x, y, z]
    waypoints:
      waypoint0:
        pose: [1.0, 2.0, 0.0]
        orientation: [1.0, 0.0, 0.0, 0.0]
    """
    atomic_write_text(Path(path), waypoints_yaml(poses))


#: Far above any waypoint file (about 200 bytes a waypoint), far below what would hurt to read.
MAX_WAYPOINT_BYTES = 16 * 1024**2


def load_waypoints_yaml(path: str | Path) -> list[tuple[float, float, float]]:
    """Read a nav2 RViz-panel waypoint file back as (x, y, yaw) poses, in file order.

    Raises :class:`~ursim_core.errors.FormatError` naming the file and the field on bad input.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "route.yaml"
    >>> save_waypoints_yaml([(1.0, 2.0, math.pi / 2), (3.0, 2.0, 0.0)], path)
    >>> [tuple(round(v, 4) for v in pose) for pose in load_waypoints_yaml(path)]  # (x, y, yaw)
    [(1.0, 2.0, 1.5708), (3.0, 2.0, 0.0)]
    >>> _ = path.write_text("goals: []\\n")
    >>> load_waypoints_yaml(path)
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: ...route.yaml: field 'waypoints': not a nav2 waypoint file: no 'waypoints' map
    """
    import yaml

    from ursim_core.io.occupancy_grid import yaw_from_quaternion
    from ursim_core.io.reading import decode_text, read_regular_file

    path = Path(path)
    # Bounded, and never a named pipe (which would block the reader); a file not found is also a
    # FileNotFoundError.
    raw = read_regular_file(path, max_bytes=MAX_WAYPOINT_BYTES, error=FormatError, what="waypoint file")
    try:
        document = yaml.safe_load(decode_text(raw, path, error=FormatError, what="waypoint file"))
    except (yaml.YAMLError, ValueError, RecursionError) as error:
        raise FormatError(f"cannot read the waypoint file: {' '.join(str(error).split())}", path=path) from None
    waypoints = document.get("waypoints") if isinstance(document, dict) else None
    if not isinstance(waypoints, dict):
        raise FormatError("not a nav2 waypoint file: no 'waypoints' map", path=path, field="waypoints")
    poses = []
    for index in range(len(waypoints)):
        name = f"waypoint{index}"
        item = waypoints.get(name)
        try:
            x, y, _z = (float(v) for v in item["pose"])
            w, qx, qy, qz = (float(v) for v in item["orientation"])
        except (TypeError, KeyError, ValueError):
            raise FormatError(
                "expected pose: [x, y, z] and orientation: [w, x, y, z]", path=path, field=f"waypoints.{name}"
            ) from None
        poses.append((x, y, yaw_from_quaternion(qx, qy, qz, w)))
    return poses
