"""The "goal" and "route" tools on the sketch view.

Goal: a click on the sketch places a goal; the metric view shows it (disc and heading), the
sketch view the tapped point. Route: a press-drag on the sketch draws a polyline; on release
the metric view shows the ordered waypoints and the path through them. Esc leaves the tool.
The tools only translate view strokes into :class:`~ursim_gui.model.navigation.NavigationModel`
calls and repaint the overlays when the model says so.
"""

from __future__ import annotations

from PySide6.QtCore import QObject, Signal

from ursim_gui.model.navigation import TOOLS
from ursim_gui.views.navigation_items import NavigationOverlay

__all__ = ["NavigationTools"]


class NavigationTools(QObject):
    """Goal / route tools over ``views`` ({"sketch": MapView, "metric": MapView}).

    Signals
    -------
    mode_changed(str) : "goal", "route" or "" (off)
    message(str) : for the status bar
    """

    mode_changed = Signal(str)
    message = Signal(str)

    def __init__(self, model, views: dict, parent=None):
        super().__init__(parent)
        self.model = model
        self.views = views
        self.mode = ""
        self.overlays = {side: NavigationOverlay(view.scene()) for side, view in views.items()}
        views["sketch"].stroke_drawn.connect(self._stroke)
        model.changed.connect(lambda _what: self.refresh())
        model.message.connect(self.message.emit)

    def set_mode(self, mode: str) -> None:
        """Turn a tool of :data:`~ursim_gui.model.navigation.TOOLS` on, or both off with ''."""
        if mode and mode not in TOOLS:
            raise ValueError(f"mode must be one of {TOOLS} or '', got {mode!r}")
        if mode == self.mode:
            return
        self.mode = mode
        self.views["sketch"].set_stroke_mode(bool(mode))
        self.mode_changed.emit(mode)
        if mode == "goal":
            self.message.emit("Goal tool: click a place on the sketch (Esc leaves the tool)")
        elif mode == "route":
            self.message.emit("Route tool: drag a route on the sketch (Esc leaves the tool)")

    def _stroke(self, points: list) -> None:
        if self.mode == "goal" and points:
            self.model.tap(*points[-1])
        elif self.mode == "route" and points:
            self.model.draw_route(points)

    def refresh(self) -> None:
        """Redraw both overlays from the model."""
        for side, overlay in self.overlays.items():
            # Markers in map pixels, sized to the map so they read alike on a 400 px sketch and a 4000 px grid.
            rect = self.views[side].sceneRect()
            overlay.marker = max(4.0, 0.012 * max(rect.width(), rect.height()))
        goals, route = self.model.goals, self.model.route
        self.overlays["sketch"].show([g.sketch_point for g in goals], self.model.route_points)
        marks = [g.pixel for g in goals]
        headings = [g.pose[2] if g.pose is not None else 0.0 for g in goals]
        line = []
        if route is not None:
            line = [w.pixel for w in route.waypoints]
            marks += line
            headings += [w.pose[2] if w.pose is not None else 0.0 for w in route.waypoints]
        self.overlays["metric"].show(marks, line, headings=headings)
        for view in self.views.values():
            view.viewport().update()
