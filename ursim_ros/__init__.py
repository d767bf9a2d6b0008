"""Optional ROS 2 node of URSIM Studio: tap on the sketch, the robot goes there.

The node (:mod:`ursim_ros.node`) needs ROS 2's ``rclpy`` and message packages (``nav_msgs``,
``geometry_msgs``, ``visualization_msgs``; ``nav2_msgs`` for the navigation actions). They are
never a dependency of URSIM Studio: install ROS 2 into a Python that URSIM Studio supports
(3.11-3.13): Jazzy or Kilted from apt on Ubuntu 24.04 (Python 3.12; ``source
/opt/ros/jazzy/setup.bash``), or RoboStack (Humble or Jazzy, Python 3.11/3.12) in a conda
environment; Humble from apt runs Python 3.10 and does not fit. Then install URSIM Studio into
that same Python. Everything the node computes is in :mod:`ursim_ros.navigator`,
which needs no ROS and is tested everywhere.

>>> import ursim_ros
>>> isinstance(ursim_ros.rclpy_available(), bool)
True
"""

from __future__ import annotations

import importlib.util

__all__ = ["RCLPY_MISSING", "rclpy_available", "require_rclpy"]

RCLPY_MISSING = (
    "the URSIM ROS 2 node needs rclpy, which this Python cannot import. URSIM Studio needs Python "
    "3.11-3.13, so: ROS 2 Jazzy or Kilted from apt (Ubuntu 24.04, Python 3.12: apt install "
    "ros-jazzy-rclpy ros-jazzy-nav2-msgs, then 'source /opt/ros/jazzy/setup.bash'), or RoboStack in "
    "conda (Humble or Jazzy for Python 3.11/3.12: conda install -c robostack-staging ros-jazzy-rclpy "
    "ros-jazzy-nav2-msgs); then install ursim-studio into that same Python"
)


def rclpy_available() -> bool:
    """True when ``rclpy`` can be imported (without importing it)."""
    try:
        return importlib.util.find_spec("rclpy") is not None
    except (ImportError, ValueError):
        return False


def require_rclpy() -> None:
    """Raise ImportError with :data:`RCLPY_MISSING` when rclpy is missing."""
    if not rclpy_available():
        raise ImportError(RCLPY_MISSING)
