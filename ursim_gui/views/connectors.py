"""Connector lines between matched regions, drawn over the two side-by-side views.

A transparent child widget covers the splitter that holds both views and ignores the
mouse; it maps each region's interior point from scene to its own coordinates at paint
time, so lines follow zoom and pan without any bookkeeping. A line is drawn only when
both ends are visible in their views.
"""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, QPoint, Qt
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QWidget

__all__ = ["ConnectorOverlay"]


class ConnectorOverlay(QWidget):
    """Lines between region pairs of two :class:`~ursim_gui.views.map_view.MapView`.

    Parameters
    ----------
    host : QWidget
        The widget containing both views (the overlay covers it exactly).
    sketch_view, metric_view : MapView
    """

    def __init__(self, host: QWidget, sketch_view, metric_view):
        super().__init__(host)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents, True)
        self.setAttribute(Qt.WidgetAttribute.WA_NoSystemBackground, True)
        self.setObjectName("connector_overlay")
        self._views = (sketch_view, metric_view)
        self._links: list[tuple[int, int, tuple[int, int, int]]] = []
        host.installEventFilter(self)
        for view in self._views:
            view.viewport_changed.connect(self.update)
        self.setGeometry(host.rect())
        self.setVisible(False)

    def set_links(self, links) -> None:
        """Pairs to connect: iterable of (sketch_region, metric_region, (r, g, b))."""
        self._links = list(links)
        self.update()

    def links(self) -> list:
        return list(self._links)

    def visible_segments(self) -> list[tuple[QPoint, QPoint]]:
        """End points (in overlay coordinates) of the lines that are drawn now."""
        segments = []
        for sketch_region, metric_region, _colour in self._links:
            ends = [self._map(view, region) for view, region in zip(self._views, (sketch_region, metric_region))]
            if all(end is not None for end in ends):
                segments.append((ends[0], ends[1]))
        return segments

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Resize:
            self.setGeometry(self.parentWidget().rect())
            self.raise_()
        return False

    def paintEvent(self, event) -> None:
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        for sketch_region, metric_region, colour in self._links:
            ends = [self._map(view, region) for view, region in zip(self._views, (sketch_region, metric_region))]
            if any(end is None for end in ends):
                continue
            painter.setPen(QPen(QColor(255, 255, 255, 200), 4.0))
            painter.drawLine(ends[0], ends[1])
            painter.setPen(QPen(QColor(*colour), 2.0))
            painter.drawLine(ends[0], ends[1])
            painter.setBrush(QColor(*colour))
            for end in ends:
                painter.drawEllipse(end, 3, 3)

    def _map(self, view, region: int) -> QPoint | None:
        point = view.region_scene_point(region)
        if point is None:
            return None
        in_viewport = view.mapFromScene(point)
        if not view.viewport().rect().contains(in_viewport):
            return None
        return view.viewport().mapTo(self.parentWidget(), in_viewport)
