"""What the ROS 2 node computes, without ROS: map in, goals and routes and region markers out.

:class:`SketchNavigator` holds the sketch (loaded and segmented once), receives the robot's map
as an :class:`~ursim_core.io.occupancy_grid.OccupancyGrid` (from ``/map``), segments and matches it
(or uses a correspondence file's cliques), and answers taps and routes with
:func:`~ursim_core.navigation.goal.locate` and :func:`~ursim_core.navigation.route.plan_route`.
Sketch points arrive as ROS points in the frame "sketch": ``x`` is the column, ``y`` the row
(image axes, pixels).
"""

from __future__ import annotations

import colorsys
from pathlib import Path
from typing import Any

from ursim_core.errors import ParameterError

__all__ = ["SketchNavigator", "region_markers"]


class SketchNavigator:
    """The node's state: sketch, robot map, match.

    Parameters
    ----------
    sketch_path : str or Path
        The sketch image.
    sketch_preset, metric_preset : str, keyword-only
        MAORIS presets (default: the matcher's, ``MATCH_PRESETS``).
    correspondences : str or Path, keyword-only
        Use these cliques instead of matching (region ids re-assigned from their points).
    target : {"interior", "mirror"}, keyword-only
        Where in the matched region a tap sends the robot.
    """

    def __init__(
        self,
        sketch_path: str | Path,
        *,
        sketch_preset: str | None = None,
        metric_preset: str | None = None,
        correspondences: str | Path | None = None,
        target: str = "interior",
    ):
        from ursim_core.io.maps import load_map
        from ursim_core.matching.config import MATCH_PRESETS
        from ursim_core.matching.from_maps import segment_for_matching

        if not str(sketch_path):
            raise ParameterError("the parameter sketch_path is empty: give the sketch image", field="sketch_path")
        self.sketch_preset = sketch_preset or MATCH_PRESETS["sketch"]
        self.metric_preset = metric_preset or MATCH_PRESETS["metric"]
        self.target = target
        self.sketch_map = load_map(sketch_path)
        # Segmented as ursim match segments a sketch (its canonical pose, its resamplings for the
        # vote), once: each map received is matched against it.
        self.sketch_seg = segment_for_matching(self.sketch_map, side="sketch", preset=self.sketch_preset)
        self.correspondences = None
        if correspondences:
            from ursim_core.correspondences import load_correspondences

            self.correspondences = load_correspondences(Path(correspondences))
        self.metric_map = None
        self.metric_seg = None
        self.table = None

    @property
    def ready(self) -> bool:
        """True once a map has been received and matched."""
        return self.table is not None

    def set_map(self, grid) -> None:
        """Take the robot's map (an OccupancyGrid, e.g. ``OccupancyGrid.from_message(msg)``) and match."""
        from ursim_core.io.occupancy_grid import map_from_occupancy_grid
        from ursim_core.matching.from_maps import segment_for_matching
        from ursim_core.navigation.goal import match_table

        metric_map = map_from_occupancy_grid(grid.data, grid.width, grid.height, grid.resolution, grid.origin)
        metric_seg = segment_for_matching(metric_map, side="metric", preset=self.metric_preset)
        if self.correspondences is not None:
            from ursim_core.correspondences import assign_regions

            assigned = assign_regions(self.correspondences, self.sketch_seg.labels, metric_seg.labels)
            table = match_table(assigned)
        else:
            from ursim_core.matching.pipeline import match

            table = match_table(match(self.sketch_seg, metric_seg))
        self.metric_map, self.metric_seg, self.table = metric_map, metric_seg, table

    def _require_map(self) -> None:
        if not self.ready:
            raise ParameterError("no map received yet on /map: cannot place a goal", field="map")

    def goal_for_tap(self, x: float, y: float, *, yaw: float = 0.0):
        """The :class:`~ursim_core.navigation.goal.Goal` of a tap at sketch pixel (x = col, y = row)."""
        from ursim_core.navigation.goal import locate

        self._require_map()
        return locate(self.table, self.sketch_seg, self.metric_seg, self.metric_map, y, x, target=self.target, yaw=yaw)

    def route_for(self, points_xy):
        """The :class:`~ursim_core.navigation.route.Route` of sketch points given as (x = col, y = row)."""
        from ursim_core.navigation.route import plan_route

        self._require_map()
        return plan_route(self.table, self.sketch_seg, self.metric_seg, self.metric_map, [(y, x) for x, y in points_xy])

    def markers(self) -> list[dict[str, Any]]:
        """Plain-data markers of the matched metric regions (see :func:`region_markers`)."""
        self._require_map()
        return region_markers(self.table, self.metric_seg, self.metric_map)


def region_markers(table, metric_seg, metric_map) -> list[dict[str, Any]]:
    """Outline and name of every matched metric region, in world coordinates.

    One ``line_strip`` (the region's outer boundary) and one ``text`` (the clique's label, else
    ``"region N"``, at the interior point) per matched metric region; colours by region. The node
    turns them into ``visualization_msgs/Marker`` values; kept as dicts so they are tested
    without ROS.
    """
    from ursim_core.correspondences.exporters import region_polygons
    from ursim_core.io.maps import pixel_to_world

    matched = sorted({m for metrics in table.metric_of.values() for m in metrics if m in metric_seg.graph})
    label_of_metric = {}
    for sketch_region, metrics in table.metric_of.items():
        for metric in metrics:
            if sketch_region in table.label_of:
                label_of_metric.setdefault(metric, table.label_of[sketch_region])
    markers = []
    for index, region in enumerate(matched):
        red, green, blue = colorsys.hsv_to_rgb((index * 0.618034) % 1.0, 0.8, 0.95)
        colour = (red, green, blue, 1.0)
        polygons = region_polygons(metric_seg.labels, region)
        if polygons:
            outer = max((rings[0] for rings in polygons), key=len)
            xs, ys = pixel_to_world(metric_map, [p[0] for p in outer], [p[1] for p in outer])
            markers.append(
                {
                    "ns": "ursim_regions",
                    "id": 2 * index,
                    "type": "line_strip",
                    "points": [(float(x), float(y)) for x, y in zip(xs, ys)],
                    "color": colour,
                    "scale": 2.0 * float(metric_map.resolution),
                }
            )
        row, col = metric_seg.graph.nodes[region]["interior"]
        x, y = pixel_to_world(metric_map, row, col)
        markers.append(
            {
                "ns": "ursim_regions",
                "id": 2 * index + 1,
                "type": "text",
                "position": (float(x), float(y)),
                "text": label_of_metric.get(region, f"region {region}"),
                "color": colour,
                "scale": 10.0 * float(metric_map.resolution),
            }
        )
    return markers
