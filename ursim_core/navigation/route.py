"""From a route drawn on the sketch to waypoints in the robot's map: :func:`plan_route`.

The polyline is sampled every pixel, so a region it crosses between two vertices is not missed.
Each sample gives a sketch region (the 10 px rule of :func:`~ursim_core.navigation.goal.locate`);
each matched sketch region gives its metric region (the largest one matched, as ``locate``).
Consecutive duplicates are dropped; where two consecutive metric regions are not adjacent in
the metric region graph, the shortest path between them (edge length: distance between interior
points) fills the gap, so the robot is sent through connected places. Every metric region of the
route becomes one waypoint at its interior point, heading towards the next waypoint, ready for
nav2's ``NavigateThroughPoses`` or ``FollowWaypoints``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import networkx as nx
import numpy as np

from ursim_core.correspondences import regions_at_points
from ursim_core.errors import ParameterError
from ursim_core.navigation.goal import MatchTable, match_table

__all__ = ["Route", "Waypoint", "plan_route", "sample_polyline"]


@dataclass(frozen=True)
class Waypoint:
    """One stop of a route: a metric region, its interior pixel and, when georeferenced, a pose.

    Examples
    --------
    >>> from ursim_core.io import Map
    >>> from ursim_core.segmentation import Segmentation, region_table
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :10], labels[:, 10:] = 1, 2  # two rooms
    >>> seg = Segmentation(labels, regions=region_table(labels))
    >>> route = plan_route({1: 1, 2: 2}, seg, seg, Map(free=labels > 0, resolution=0.1), [(5, 2), (5, 18)])
    >>> route.waypoints[0]  # heading 0: towards +x, where the next waypoint is
    Waypoint(metric_region=1, pixel=(4, 4), pose=(0.45, 0.55, 0.0), sketch_region=1, label=None, filled=False)
    >>> route.waypoints[1].to_dict()["pose"]  # JSON: rounded to 6 decimals
    [1.45, 0.55, 0.0]
    """

    metric_region: int
    pixel: tuple[int, int]
    pose: tuple[float, float, float] | None = None
    sketch_region: int | None = None
    label: str | None = None
    filled: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {
            "metric_region": self.metric_region,
            "pixel": list(self.pixel),
            "pose": None if self.pose is None else [round(v, 6) for v in self.pose],
            "sketch_region": self.sketch_region,
            "label": self.label,
            "filled": self.filled,
        }


@dataclass(frozen=True)
class Route:
    """The result of :func:`plan_route`.

    Attributes
    ----------
    waypoints : tuple of Waypoint
        In order. ``filled`` marks regions added to connect the route (no sketch region).
    sketch_regions : tuple of int
        The sketch regions the polyline crosses, consecutive duplicates removed.
    skipped : tuple of int
        Crossed sketch regions without a match (left out of the route).
    gaps : tuple of (int, int)
        Consecutive metric regions that no path of the region graph connects (the route is
        broken there; the robot's planner may still find a way).

    Examples
    --------
    >>> from ursim_core.segmentation import Segmentation, region_table
    >>> labels = np.zeros((10, 30), np.int32)
    >>> labels[:, :10], labels[:, 10:20], labels[:, 20:] = 1, 2, 3  # three rooms in a row
    >>> seg = Segmentation(labels, regions=region_table(labels))
    >>> route = plan_route([(1, 1), (3, 3)], seg, seg, None, [(5, 2), (5, 28)])  # room 2 unmatched
    >>> route.sketch_regions, route.skipped, route.metric_regions, route.path, route.gaps
    ((1, 2, 3), (2,), (1, 2, 3), [(4, 4), (4, 14), (4, 24)], ())
    """

    waypoints: tuple[Waypoint, ...] = ()
    sketch_regions: tuple[int, ...] = ()
    skipped: tuple[int, ...] = ()
    gaps: tuple[tuple[int, int], ...] = ()

    @property
    def metric_regions(self) -> tuple[int, ...]:
        return tuple(w.metric_region for w in self.waypoints)

    @property
    def path(self) -> list[tuple[int, int]]:
        """The waypoints' pixels, for drawing the route on the metric view."""
        return [w.pixel for w in self.waypoints]

    def to_dict(self) -> dict[str, Any]:
        return {
            "waypoints": [w.to_dict() for w in self.waypoints],
            "sketch_regions": list(self.sketch_regions),
            "metric_regions": list(self.metric_regions),
            "skipped_sketch_regions": list(self.skipped),
            "gaps": [list(g) for g in self.gaps],
        }


def sample_polyline(points: Sequence[Sequence[float]], *, step: float = 1.0) -> np.ndarray:
    """Points along a polyline, at most ``step`` pixels apart, vertices included.

    >>> sample_polyline([(0, 0), (0, 3)]).tolist()
    [[0.0, 0.0], [0.0, 1.0], [0.0, 2.0], [0.0, 3.0]]
    """
    vertices = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(vertices) == 0:
        return vertices
    if not np.all(np.isfinite(vertices)):
        raise ParameterError("route points must be finite numbers")
    samples = [vertices[:1]]
    for start, end in zip(vertices[:-1], vertices[1:]):
        n = max(int(math.ceil(float(np.hypot(*(end - start))) / step)), 1)
        fractions = np.arange(1, n + 1, dtype=float)[:, None] / n
        samples.append(start + fractions * (end - start))
    return np.concatenate(samples)


def plan_route(
    match: Any,
    sketch_seg: Any,
    metric_seg: Any,
    metric_map: Any,
    points: Sequence[Sequence[float]],
    *,
    tolerance: float = 10,
    fill_gaps: bool = True,
) -> Route:
    """Metric regions and waypoints for a polyline drawn on the sketch.

    Parameters
    ----------
    match : MatchResult, Correspondences, MatchTable, mapping or pairs
        See :func:`~ursim_core.navigation.goal.match_table`; a Correspondences' region ids are
        taken from its points in ``sketch_seg`` and ``metric_seg``, as :func:`locate` does.
    sketch_seg, metric_seg : Segmentation
    metric_map : Map or None
        With a ``resolution``, waypoints get world poses.
    points : sequence of (row, col)
        The polyline in sketch pixels (one point is a single goal).
    tolerance : float, keyword-only
        As in :func:`~ursim_core.navigation.goal.locate`.
    fill_gaps : bool, keyword-only
        Connect non-adjacent consecutive metric regions along the region graph.

    Returns
    -------
    Route

    Raises
    ------
    ParameterError
        No point given.

    Examples
    --------
    >>> from ursim_core.segmentation.interface import Segmentation
    >>> from ursim_core.segmentation.graph import region_graph
    >>> labels = np.zeros((10, 30), np.int32)
    >>> labels[:, :10], labels[:, 10:20], labels[:, 20:] = 1, 2, 3
    >>> seg = Segmentation(labels=labels, graph=region_graph(labels))
    >>> route = plan_route([(1, 1), (3, 3)], seg, seg, None, [(5, 2), (5, 28)])
    >>> route.metric_regions, [w.filled for w in route.waypoints], route.skipped
    ((1, 2, 3), [False, True, False], (2,))
    """
    samples = sample_polyline(points)
    if len(samples) == 0:
        raise ParameterError("a route needs at least one point")
    table = match_table(match, sketch_seg, metric_seg, tolerance=tolerance)
    regions = regions_at_points(sketch_seg.labels, samples, tolerance=tolerance)
    sketch_sequence = _without_repeats(r for r in regions if r != 0)
    metric_graph = metric_seg.graph
    stops: list[tuple[int, int | None]] = []  # (metric region, sketch region)
    skipped = []
    for sketch_region in sketch_sequence:
        metrics = [r for r in table.metric_of.get(sketch_region, ()) if r in metric_graph]
        if not metrics:
            skipped.append(sketch_region)
            continue
        chosen = max(metrics, key=lambda r: (metric_graph.nodes[r]["size"], -r))
        if not stops or stops[-1][0] != chosen:
            stops.append((chosen, sketch_region))
    connected, gaps = _connect(stops, metric_graph) if fill_gaps else ([(m, s, False) for m, s in stops], [])
    waypoints = _waypoints(connected, metric_graph, metric_map, table)
    return Route(
        waypoints=tuple(waypoints),
        sketch_regions=tuple(sketch_sequence),
        skipped=tuple(dict.fromkeys(skipped)),
        gaps=tuple(gaps),
    )


def _without_repeats(values) -> list[int]:
    result: list[int] = []
    for value in values:
        if not result or result[-1] != value:
            result.append(int(value))
    return result


def _connect(stops, graph: nx.Graph):
    """Stops with shortest-path regions inserted between non-adjacent consecutive ones."""
    if not stops:
        return [], []

    def length(a, b, _data):
        (ra, ca), (rb, cb) = graph.nodes[a]["interior"], graph.nodes[b]["interior"]
        return math.hypot(ra - rb, ca - cb)

    connected = [(stops[0][0], stops[0][1], False)]
    gaps = []
    for (previous, _), (current, sketch_region) in zip(stops[:-1], stops[1:]):
        if not graph.has_edge(previous, current):
            try:
                path = nx.shortest_path(graph, previous, current, weight=length)
            except nx.NetworkXNoPath:
                gaps.append((previous, current))
                path = [previous, current]
            connected.extend((region, None, True) for region in path[1:-1])
        connected.append((current, sketch_region, False))
    return connected, gaps


def _waypoints(connected, graph: nx.Graph, metric_map, table: MatchTable) -> list[Waypoint]:
    pixels = [tuple(int(v) for v in graph.nodes[region]["interior"]) for region, _, _ in connected]
    georeferenced = metric_map is not None and getattr(metric_map, "resolution", None) is not None
    if georeferenced:
        from ursim_core.io.maps import pixel_to_world

        rows = np.array([p[0] for p in pixels], dtype=float)
        cols = np.array([p[1] for p in pixels], dtype=float)
        xs, ys = (np.atleast_1d(v) for v in pixel_to_world(metric_map, rows, cols))
    waypoints = []
    heading = 0.0
    for index, ((region, sketch_region, filled), pixel) in enumerate(zip(connected, pixels)):
        pose = None
        if georeferenced:
            if index + 1 < len(pixels):
                dx, dy = xs[index + 1] - xs[index], ys[index + 1] - ys[index]
                if dx or dy:
                    heading = math.atan2(dy, dx)
            pose = (float(xs[index]), float(ys[index]), float(heading))
        waypoints.append(
            Waypoint(
                metric_region=int(region),
                pixel=pixel,
                pose=pose,
                sketch_region=sketch_region,
                label=table.label_of.get(sketch_region) if sketch_region is not None else None,
                filled=filled,
            )
        )
    return waypoints
