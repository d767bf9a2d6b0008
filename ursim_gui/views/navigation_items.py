"""Overlay items of the goal and route tools: the drawn route on the sketch, goals and waypoints on the metric map.

Thin painters: they are handed points in map pixels (row, col) and draw them; the state is in
:class:`~ursim_gui.model.navigation.NavigationModel`. Scene units are pixels, so a marker's size
is in pixels of the map and the pens are cosmetic (constant width on screen).
"""

from __future__ import annotations

import math

from PySide6.QtCore import QPointF
from PySide6.QtGui import QBrush, QColor, QPainterPath, QPen
from PySide6.QtWidgets import QGraphicsItemGroup, QGraphicsPathItem

__all__ = ["NavigationOverlay", "GOAL_COLOUR", "ROUTE_COLOUR"]

GOAL_COLOUR = QColor(220, 30, 60)
ROUTE_COLOUR = QColor(20, 110, 230)
_Z = 50


def _point(row: float, col: float) -> QPointF:
    return QPointF(col + 0.5, row + 0.5)


def _pen(colour: QColor, width: float = 2.5) -> QPen:
    pen = QPen(colour, width)
    pen.setCosmetic(True)
    return pen


class NavigationOverlay(QGraphicsItemGroup):
    """Goal markers (disc + heading), a polyline and numbered waypoints over one map view."""

    def __init__(self, scene, *, marker: float = 6.0):
        super().__init__()
        self.setZValue(_Z)
        self.marker = marker
        self.line = QGraphicsPathItem(self)
        self.line.setPen(_pen(ROUTE_COLOUR))
        self.marks = QGraphicsPathItem(self)
        self.marks.setPen(_pen(QColor("white"), 1.5))
        self.marks.setBrush(QBrush(GOAL_COLOUR))
        self.headings = QGraphicsPathItem(self)
        self.headings.setPen(_pen(GOAL_COLOUR, 3.0))
        scene.addItem(self)
        self.goal_points: list[tuple[float, float]] = []
        self.line_points: list[tuple[float, float]] = []

    def show(self, goals=(), line=(), *, headings=None) -> None:
        """Draw ``goals`` (row, col) as markers and ``line`` (row, col) as a polyline.

        ``headings`` are yaw angles (radians, counter-clockwise from the map's x axis, y up) per goal.
        """
        self.goal_points, self.line_points = [tuple(g) for g in goals], [tuple(p) for p in line]
        path = QPainterPath()
        if self.line_points:
            path.moveTo(_point(*self.line_points[0]))
            for point in self.line_points[1:]:
                path.lineTo(_point(*point))
        self.line.setPath(path)
        marks, arrows = QPainterPath(), QPainterPath()
        for index, (row, col) in enumerate(self.goal_points):
            centre = _point(row, col)
            marks.addEllipse(centre, self.marker, self.marker)
            if headings is not None and index < len(headings):
                yaw = headings[index]
                arrows.moveTo(centre)
                # Image rows grow downwards while world y grows upwards: the y component flips.
                arrows.lineTo(centre + QPointF(math.cos(yaw), -math.sin(yaw)) * self.marker * 2.5)
        self.marks.setPath(marks)
        self.headings.setPath(arrows)
