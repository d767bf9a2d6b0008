"""The ROS 2 node: ``/map`` in, a tap on the sketch out as a nav2 goal.

Run with ``python -m ursim_ros --ros-args -p sketch_path:=/path/sketch.png``. Needs rclpy (see
:mod:`ursim_ros`); importing this module without it raises ImportError with that message.

Parameters: ``sketch_path`` (required), ``correspondences`` (a JSON file: use its cliques instead
of matching), ``sketch_preset`` / ``metric_preset`` (MAORIS presets), ``target`` ("interior" or
"mirror"), ``use_action`` (True: send nav2's NavigateToPose / NavigateThroughPoses actions; False:
publish ``goal_pose``), ``sketch_frame`` (frame id of the taps, "sketch").

Topics: subscribes ``/map`` (nav_msgs/OccupancyGrid, transient local, as map_server publishes),
``sketch_tap`` (geometry_msgs/PointStamped in frame "sketch": x = column, y = row, pixels) and
``sketch_route`` (nav_msgs/Path of such points); publishes ``goal_pose`` (geometry_msgs/PoseStamped,
when ``use_action`` is False or nav2_msgs is missing) and ``ursim/regions``
(visualization_msgs/MarkerArray of the matched regions, transient local).
"""

from __future__ import annotations

from ursim_ros import require_rclpy

require_rclpy()

import rclpy  # noqa: E402
from geometry_msgs.msg import Point, PointStamped, PoseStamped  # noqa: E402
from nav_msgs.msg import OccupancyGrid as OccupancyGridMessage  # noqa: E402
from nav_msgs.msg import Path as PathMessage  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

from ursim_core.errors import UrsimError  # noqa: E402
from ursim_core.io.occupancy_grid import OccupancyGrid  # noqa: E402
from ursim_core.navigation.nav2_files import quaternion_xyzw  # noqa: E402
from ursim_ros.navigator import SketchNavigator  # noqa: E402

try:  # nav2's actions are optional: without them the node publishes goal_pose.
    from nav2_msgs.action import NavigateThroughPoses, NavigateToPose
    from rclpy.action import ActionClient
except ImportError:  # pragma: no cover - depends on the ROS installation
    NavigateToPose = NavigateThroughPoses = ActionClient = None

__all__ = ["UrsimSketchNode", "main"]

_LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)


class UrsimSketchNode(Node):
    """Matches the sketch to ``/map`` and turns taps and routes on the sketch into nav2 goals."""

    def __init__(self, **node_options):
        super().__init__("ursim_sketch", **node_options)
        for name, default in (
            ("sketch_path", ""),
            ("correspondences", ""),
            ("sketch_preset", ""),
            ("metric_preset", ""),
            ("target", "interior"),
            ("sketch_frame", "sketch"),
        ):
            self.declare_parameter(name, default)
        self.declare_parameter("use_action", True)
        value = lambda name: self.get_parameter(name).value
        self.sketch_frame = value("sketch_frame")
        self.navigator = SketchNavigator(
            value("sketch_path"),
            sketch_preset=value("sketch_preset") or None,
            metric_preset=value("metric_preset") or None,
            correspondences=value("correspondences") or None,
            target=value("target"),
        )
        self.map_frame = "map"
        self.use_action = bool(value("use_action")) and NavigateToPose is not None
        if value("use_action") and NavigateToPose is None:
            self.get_logger().warning("nav2_msgs is not installed: publishing goal_pose instead of sending actions")
        self.goal_publisher = self.create_publisher(PoseStamped, "goal_pose", 10)
        self.marker_publisher = self.create_publisher(MarkerArray, "ursim/regions", _LATCHED)
        if self.use_action:
            self.to_pose = ActionClient(self, NavigateToPose, "navigate_to_pose")
            self.through_poses = ActionClient(self, NavigateThroughPoses, "navigate_through_poses")
        self.create_subscription(OccupancyGridMessage, "/map", self.on_map, _LATCHED)
        self.create_subscription(PointStamped, "sketch_tap", self.on_tap, 10)
        self.create_subscription(PathMessage, "sketch_route", self.on_route, 10)
        self.get_logger().info(f"sketch {value('sketch_path')}: {self.navigator.sketch_seg.n_regions} regions")

    # -- callbacks -----------------------------------------------------------------------

    def on_map(self, message) -> None:
        try:
            grid = OccupancyGrid.from_message(message)
            self.navigator.set_map(grid)
        except UrsimError as error:
            self.get_logger().error(f"cannot use the map: {error}")
            return
        self.map_frame = grid.frame_id or "map"
        self.marker_publisher.publish(self.marker_array())
        regions = self.navigator.metric_seg.n_regions
        self.get_logger().info(
            f"map {grid.width}x{grid.height}: {regions} regions, {len(self.navigator.table.pairs)} matches"
        )

    def on_tap(self, message) -> None:
        if not self._in_sketch_frame(message.header.frame_id):
            return
        try:
            goal = self.navigator.goal_for_tap(message.point.x, message.point.y)
        except UrsimError as error:
            self.get_logger().warning(str(error))
            return
        if not goal.ok:
            self.get_logger().warning(goal.failure_message())
            return
        pose = self.pose_message(goal.pose)
        self.get_logger().info(f"goal in region {goal.metric_region}: x {goal.pose[0]:.2f} y {goal.pose[1]:.2f}")
        if self.use_action and self.to_pose.server_is_ready():
            request = NavigateToPose.Goal()
            request.pose = pose
            self.to_pose.send_goal_async(request)
        else:
            if self.use_action:
                self.get_logger().warning("no navigate_to_pose action server: publishing goal_pose instead")
            self.goal_publisher.publish(pose)

    def on_route(self, message) -> None:
        if not self._in_sketch_frame(message.header.frame_id):
            return
        try:
            route = self.navigator.route_for([(p.pose.position.x, p.pose.position.y) for p in message.poses])
        except UrsimError as error:
            self.get_logger().warning(str(error))
            return
        poses = [self.pose_message(w.pose) for w in route.waypoints]
        if not poses:
            self.get_logger().warning("the route crosses no matched sketch region")
            return
        if self.use_action and self.through_poses.server_is_ready():
            request = NavigateThroughPoses.Goal()
            try:
                request.poses = poses
            except (AssertionError, TypeError):  # newer nav2 wraps the poses in nav_msgs/Goals
                request.poses.goals = poses
            self.through_poses.send_goal_async(request)
        else:
            self.get_logger().warning("no navigate_through_poses action server: publishing the last pose on goal_pose")
            self.goal_publisher.publish(poses[-1])
        self.get_logger().info(f"route through regions {list(route.metric_regions)}")

    # -- messages ------------------------------------------------------------------------

    def _in_sketch_frame(self, frame_id: str) -> bool:
        if frame_id != self.sketch_frame:
            self.get_logger().warning(
                f"ignoring a point in frame '{frame_id}': sketch points use '{self.sketch_frame}'"
            )
            return False
        return True

    def pose_message(self, pose) -> PoseStamped:
        message = PoseStamped()
        message.header.frame_id = self.map_frame
        message.header.stamp = self.get_clock().now().to_msg()
        message.pose.position.x, message.pose.position.y = float(pose[0]), float(pose[1])
        qx, qy, qz, qw = quaternion_xyzw(pose[2])
        orientation = message.pose.orientation
        orientation.x, orientation.y, orientation.z, orientation.w = qx, qy, qz, qw
        return message

    def marker_array(self) -> MarkerArray:
        array = MarkerArray()
        clear = Marker()
        clear.action = Marker.DELETEALL
        array.markers.append(clear)
        stamp = self.get_clock().now().to_msg()
        for item in self.navigator.markers():
            marker = Marker()
            marker.header.frame_id = self.map_frame
            marker.header.stamp = stamp
            marker.ns, marker.id, marker.action = item["ns"], item["id"], Marker.ADD
            marker.color.r, marker.color.g, marker.color.b, marker.color.a = item["color"]
            marker.pose.orientation.w = 1.0
            if item["type"] == "line_strip":
                marker.type = Marker.LINE_STRIP
                marker.scale.x = item["scale"]
                marker.points = [Point(x=x, y=y, z=0.0) for x, y in item["points"]]
            else:
                marker.type = Marker.TEXT_VIEW_FACING
                marker.scale.z = item["scale"]
                marker.text = item["text"]
                marker.pose.position.x, marker.pose.position.y = item["position"]
            array.markers.append(marker)
        return array


def main(args=None) -> int:
    rclpy.init(args=args)
    try:
        node = UrsimSketchNode()
    except UrsimError as error:
        print(f"error: {error}")
        rclpy.shutdown()
        return 1
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
