"""The state behind the GUI's "goal" and "route" tools, without Qt.

A :class:`NavigationSession` holds one match (sketch + metric segmentations, the match or the
cliques) and what the user did with the tools: the goals tapped on the sketch and the route
being drawn or finished. Views call its methods from mouse events and redraw when a listener
they subscribed is called; the session never knows about widgets (the labelme / napari split).

Typical wiring in a view::

    session = NavigationSession(table, sketch_seg, metric_seg, metric_map)
    session.subscribe(lambda what: metric_view.update())   # what: "goals" or "route"
    # goal tool: mouse release on the sketch view
    goal = session.tap(row, col)
    # route tool: press / move / release on the sketch view
    session.begin_route(row, col); session.extend_route(row, col); route = session.finish_route()
    # export buttons
    session.save_json(path); session.save_nav2_waypoints(path)
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ursim_core.errors import ParameterError
from ursim_core.io.atomic import atomic_write_text
from ursim_core.navigation.goal import Goal, locate, match_table
from ursim_core.navigation.nav2_files import pose_stamped, save_waypoints_yaml
from ursim_core.navigation.route import Route, plan_route

__all__ = ["NavigationSession", "NAVIGATION_FORMAT"]

#: ``format`` of the JSON written by :meth:`NavigationSession.save_json`.
NAVIGATION_FORMAT = "ursim-navigation"


class NavigationSession:
    """Goals and a route on one matched pair of maps.

    Parameters
    ----------
    match : MatchResult, Correspondences, MatchTable, mapping or pairs
        See :func:`~ursim_core.navigation.goal.match_table`; call :meth:`set_match` when the
        user edits the cliques. A Correspondences' stored region ids are used as they are (the
        app keeps them those of ``sketch_seg`` and ``metric_seg``, and a table built on every
        edit stays cheap): pass ``match_table(corr, sketch_seg, metric_seg)`` for a file saved
        with other segmentations.
    sketch_seg, metric_seg : Segmentation
    metric_map : Map or None
        With a resolution, goals and waypoints get world poses.
    target : {"interior", "mirror"}, keyword-only
        Passed to :func:`~ursim_core.navigation.goal.locate`.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.segmentation.interface import Segmentation
    >>> from ursim_core.segmentation.graph import region_graph
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :10] = 1; labels[:, 10:] = 2
    >>> seg = Segmentation(labels=labels, graph=region_graph(labels))
    >>> session = NavigationSession([(1, 1), (2, 2)], seg, seg, None)
    >>> seen = []; session.subscribe(seen.append)
    >>> session.tap(5, 3).metric_region, seen
    (1, ['goals'])
    >>> session.begin_route(5, 2); session.extend_route(5, 18); session.finish_route().metric_regions
    (1, 2)
    """

    def __init__(self, match: Any, sketch_seg, metric_seg, metric_map=None, *, target: str = "interior"):
        self.sketch_seg, self.metric_seg, self.metric_map = sketch_seg, metric_seg, metric_map
        self.target = target
        self.table = match_table(match)
        self.goals: list[Goal] = []
        self.route: Route | None = None
        self.route_points: list[tuple[float, float]] = []
        self._drawing = False
        self._listeners: list[Callable[[str], None]] = []

    # -- listeners -----------------------------------------------------------------------

    def subscribe(self, listener: Callable[[str], None]) -> None:
        """Call ``listener(what)`` after each change; ``what`` is ``"goals"`` or ``"route"``."""
        self._listeners.append(listener)

    def unsubscribe(self, listener: Callable[[str], None]) -> None:
        self._listeners.remove(listener)

    def _emit(self, what: str) -> None:
        for listener in list(self._listeners):
            listener(what)

    # -- goal tool -----------------------------------------------------------------------

    def tap(self, row: float, col: float, *, keep: bool = False) -> Goal:
        """Locate a tap; the goal replaces the previous one (or is added with ``keep``).

        A failed goal (``goal.ok`` False) is returned with its reason and nearest matched region
        for the status bar, and not kept.
        """
        goal = self._locate(row, col)
        if goal.ok:
            self.goals = [*self.goals, goal] if keep else [goal]
            self._emit("goals")
        return goal

    def _locate(self, row: float, col: float) -> Goal:
        return locate(self.table, self.sketch_seg, self.metric_seg, self.metric_map, row, col, target=self.target)

    def clear_goals(self) -> None:
        self.goals = []
        self._emit("goals")

    # -- route tool ----------------------------------------------------------------------

    def begin_route(self, row: float, col: float) -> None:
        """Start drawing a route at a sketch point (the previous route is dropped)."""
        self.route_points = [(float(row), float(col))]
        self.route = None
        self._drawing = True
        self._emit("route")

    def extend_route(self, row: float, col: float) -> None:
        """Add a point to the route being drawn (mouse move)."""
        if not self._drawing:
            raise ParameterError("extend_route() before begin_route()")
        point = (float(row), float(col))
        if point != self.route_points[-1]:
            self.route_points.append(point)
            self._emit("route")

    def finish_route(self) -> Route:
        """Finish the drawing and plan the route (ordered, connected metric regions and waypoints)."""
        if not self._drawing:
            raise ParameterError("finish_route() before begin_route()")
        self._drawing = False
        self.route = plan_route(self.table, self.sketch_seg, self.metric_seg, self.metric_map, self.route_points)
        self._emit("route")
        return self.route

    def clear_route(self) -> None:
        self.route, self.route_points, self._drawing = None, [], False
        self._emit("route")

    def set_match(self, match: Any) -> None:
        """New cliques or a new match: goals and the route are located again from their points."""
        self.table = match_table(match)
        taps = [goal.sketch_point for goal in self.goals]
        located = (self._locate(row, col) for row, col in taps)
        self.goals = [goal for goal in located if goal.ok]
        if self.route is not None:
            self.route = plan_route(self.table, self.sketch_seg, self.metric_seg, self.metric_map, self.route_points)
        self._emit("goals")
        self._emit("route")

    # -- export --------------------------------------------------------------------------

    def to_json(self) -> dict[str, Any]:
        """Goals and route as one JSON document (PoseStamped-like poses, frame "map")."""

        def stamped(pose, details):
            document = pose_stamped(pose) if pose is not None else {"header": {"frame_id": "map"}, "pose": None}
            document["ursim"] = details
            return document

        return {
            "format": NAVIGATION_FORMAT,
            "version": 1,
            "frame_id": "map",
            "goals": [stamped(g.pose, g.to_dict()) for g in self.goals],
            "route": None
            if self.route is None
            else {
                "sketch_points": [list(p) for p in self.route_points],
                "poses": [stamped(w.pose, w.to_dict()) for w in self.route.waypoints],
                **{k: v for k, v in self.route.to_dict().items() if k != "waypoints"},
            },
        }

    def save_json(self, path: str | Path) -> None:
        """Write :meth:`to_json` atomically."""
        atomic_write_text(Path(path), json.dumps(self.to_json(), indent=2) + "\n")

    def save_nav2_waypoints(self, path: str | Path) -> None:
        """Write the route (else the goals) as nav2's RViz-panel waypoint file.

        Raises :class:`~ursim_core.errors.ParameterError` when there is nothing to write or the
        metric map has no resolution (waypoints are in metres).
        """
        poses = [w.pose for w in self.route.waypoints] if self.route is not None else [g.pose for g in self.goals]
        if not poses:
            raise ParameterError("no goal or route to export: tap a goal or draw a route first")
        if any(pose is None for pose in poses):
            raise ParameterError(
                "the metric map has no resolution: nav2 waypoints need a map_server YAML map", field="resolution"
            )
        save_waypoints_yaml(poses, path)
