"""The goal and route tools' state, without Qt: a :class:`NavigationModel` over the annotation session.

It owns one :class:`~ursim_core.navigation.session.NavigationSession` built from the session's
segmentations, metric map and correspondences, and keeps it in step with them: after the
correspondences change (a relinked clique, a new match, an undo) the goals and the route are
located again from their sketch points; after a new segmentation or map they are cleared, with
a note saying why. Views repaint on :attr:`changed`; the status bar shows :attr:`message`.
"""

from __future__ import annotations

from pathlib import Path

from ursim_core.navigation.session import NavigationSession
from ursim_gui.model.signals import Signal

__all__ = ["NavigationModel", "TOOLS"]

#: What a left click / drag on the sketch does while a tool is on.
TOOLS = ("goal", "route")


class NavigationModel:
    """Goals and a route on the session's matched pair of maps.

    Parameters
    ----------
    session : AnnotationSession

    Attributes
    ----------
    changed : Signal
        ``(what)``, ``"goals"`` or ``"route"``: redraw the overlays.
    message : Signal
        ``(text)``: what a tap or a route gave, or why the goals were cleared.
    """

    def __init__(self, session) -> None:
        self.session = session
        self.changed = Signal("navigation_changed")
        self.message = Signal("navigation_message")
        self._nav: NavigationSession | None = None
        #: Sketch point (row, col) of the nearest matched region after an unmatched tap, else None.
        self.offer: tuple[int, int] | None = None
        session.correspondences_changed.connect(self._correspondences_changed)
        session.segmentation_changed.connect(lambda side: self._reset(f"the {side} segmentation changed"))
        session.map_changed.connect(lambda side: self._reset(f"the {side} map changed"))

    # -- state ---------------------------------------------------------------------------
    @property
    def ready(self) -> bool:
        """Both maps are segmented (a goal needs regions on both sides)."""
        return all(self.session.segmentation(side) is not None for side in ("sketch", "metric"))

    @property
    def goals(self):
        return [] if self._nav is None else list(self._nav.goals)

    @property
    def route(self):
        return None if self._nav is None else self._nav.route

    @property
    def route_points(self) -> list[tuple[float, float]]:
        return [] if self._nav is None else list(self._nav.route_points)

    def navigation(self) -> NavigationSession | None:
        """The core session (built on first use), None until both maps are segmented."""
        if self._nav is None and self.ready:
            self._nav = NavigationSession(
                self.session.correspondences,
                self.session.segmentation("sketch"),
                self.session.segmentation("metric"),
                self.session.map("metric"),
            )
            self._nav.subscribe(self.changed.emit)
        return self._nav

    # -- tools ---------------------------------------------------------------------------
    def tap(self, row: float, col: float):
        """The goal tool: locate a tap on the sketch; returns the core ``Goal`` (or None when not ready)."""
        nav = self.navigation()
        if nav is None:
            self.message.emit("Segment both maps before placing a goal")
            return None
        goal = nav.tap(row, col)
        self.offer = None if goal.ok or goal.nearest is None else tuple(goal.nearest.point)
        text = _goal_text(goal)
        if self.offer is not None:
            text += " (Shift+T places the goal there)"
        self.message.emit(text)
        return goal

    def accept_offer(self):
        """Place the goal at the nearest matched region offered after an unmatched tap (None without an offer)."""
        if self.offer is None:
            self.message.emit("No nearest region to go to: tap an unmatched region first")
            return None
        return self.tap(*self.offer)

    def draw_route(self, points) -> object | None:
        """The route tool: plan a route through sketch points (row, col) in drawing order."""
        nav = self.navigation()
        if nav is None or not points:
            self.message.emit("Segment both maps before drawing a route")
            return None
        nav.begin_route(*points[0])
        for row, col in points[1:]:
            nav.extend_route(row, col)
        route = nav.finish_route()
        self.message.emit(_route_text(route))
        return route

    def clear(self) -> None:
        if self._nav is not None:
            self._nav.clear_goals()
            self._nav.clear_route()

    # -- export --------------------------------------------------------------------------
    def has_content(self) -> bool:
        return bool(self.goals) or self.route is not None

    def save_json(self, path: str | Path) -> None:
        self._require().save_json(path)

    def save_nav2_waypoints(self, path: str | Path) -> None:
        self._require().save_nav2_waypoints(path)

    def _require(self) -> NavigationSession:
        from ursim_core.errors import ParameterError

        nav = self.navigation()
        if nav is None or not self.has_content():
            raise ParameterError("no goal or route to export: tap a goal or draw a route first")
        return nav

    # -- following the session -----------------------------------------------------------
    def _correspondences_changed(self, *_args) -> None:
        if self._nav is None:
            return
        before = len(self._nav.goals)
        self._nav.set_match(self.session.correspondences)
        lost = before - len(self._nav.goals)
        if lost:
            self.message.emit(f"{lost} goal(s) removed: their sketch region is no longer matched")

    def _reset(self, why: str) -> None:
        had = self._nav is not None and (self._nav.goals or self._nav.route is not None)
        self._nav = None
        self.changed.emit("goals")
        self.changed.emit("route")
        if had:
            self.message.emit(f"Goals and route cleared: {why}")


def _goal_text(goal) -> str:
    if not goal.ok:
        return f"No goal at {goal.failure_message()}"
    where = f"metric region {goal.metric_region}" + (f" “{goal.label}”" if goal.label else "")
    if goal.pose is not None:
        x, y, yaw = goal.pose
        return f"Goal in {where}: x {x:.2f} m, y {y:.2f} m, yaw {yaw:.2f} rad"
    row, col = goal.pixel
    return f"Goal in {where} at pixel ({row}, {col}) (the metric map has no resolution)"


def _route_text(route) -> str:
    text = f"Route through {len(route.waypoints)} metric region(s): " + " → ".join(
        str(w.metric_region) for w in route.waypoints
    )
    if route.skipped:
        text += f"; unmatched sketch regions skipped: {', '.join(map(str, route.skipped))}"
    return text
