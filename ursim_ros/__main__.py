"""``python -m ursim_ros --ros-args -p sketch_path:=sketch.png``: run the node."""

import sys

from ursim_ros import RCLPY_MISSING, rclpy_available

if __name__ == "__main__":
    if not rclpy_available():
        print(f"error: {RCLPY_MISSING}", file=sys.stderr)
        sys.exit(1)
    from ursim_ros.node import main

    sys.exit(main())
