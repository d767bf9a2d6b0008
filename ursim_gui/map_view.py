"""One zoomable view of a map with its region overlay layers.

The view only renders what it is told (image, label image, colour table, highlighted
and selected regions) and reports user input as signals in map pixel terms; it holds no
annotation state. Scene units are map pixels: pixel (row, col) covers x in
[col, col + 1) and y in [row, row + 1), drawn nearest-neighbour at every zoom.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QBrush, QColor, QPainter, QPainterPath, QPen, QPixmapCache
from PySide6.QtWidgets import QApplication, QGraphicsPathItem, QGraphicsScene, QGraphicsView

from ursim_gui.map_items import (
    ImageItem,
    LabelItem,
    grey_to_qimage,
    lut_qimage,
    mask_qimage,
    region_outline_path,
)
from ursim_gui.overlay import outline_mask, region_label_positions

__all__ = ["MapView", "MAX_ZOOM"]

#: Largest zoom factor (3200 %).
MAX_ZOOM = 32.0
#: A region's id is drawn only when the region is at least this many screen pixels
#: across, so zoomed-out maps with many regions stay readable (and cheap to paint).
MIN_ID_REGION_PX = 28
_PIXMAP_CACHE_KB = 192 * 1024
_WHEEL_STEP = 1.25
_Z_BASE, _Z_OVERLAY, _Z_OUTLINE, _Z_GRAPH, _Z_MARKS, _Z_LABELS = 0, 1, 2, 3, 4, 5


class MapView(QGraphicsView):
    """QGraphicsView of one map (the sketch or the metric map).

    Signals
    -------
    region_hovered(int) : region under the cursor changed (0 = none)
    region_clicked(int, bool) : a click without drag on a region; bool = add to selection (Ctrl)
    cursor_moved(int, int) : pixel (row, col) under the cursor; (-1, -1) when it leaves the map
    zoom_changed(float) : new zoom factor (1.0 = 100 %)
    viewport_changed() : zoom or scroll changed (for connector lines)
    files_dropped(list) : paths dropped onto the view
    """

    region_hovered = Signal(int)
    region_clicked = Signal(int, bool)
    cursor_moved = Signal(int, int)
    zoom_changed = Signal(float)
    viewport_changed = Signal()
    files_dropped = Signal(list)

    def __init__(self, side: str, parent=None):
        super().__init__(parent)
        self.side = side
        # Layers are device-cached (one scaled copy per view and layer); Qt's default
        # 10 MB pixmap cache cannot hold them for two views at a large window size.
        QPixmapCache.setCacheLimit(max(QPixmapCache.cacheLimit(), _PIXMAP_CACHE_KB))
        self.setScene(QGraphicsScene(self))
        self.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, False)
        self.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        # Zoom anchoring is done by set_zoom itself (AnchorUnderMouse uses the last
        # mouse-move position, not the wheel event's).
        self.setTransformationAnchor(QGraphicsView.ViewportAnchor.NoAnchor)
        self.setResizeAnchor(QGraphicsView.ViewportAnchor.AnchorViewCenter)
        self.setViewportUpdateMode(QGraphicsView.ViewportUpdateMode.SmartViewportUpdate)
        self.setBackgroundBrush(QColor(236, 237, 240))
        self.setMouseTracking(True)
        self.setAcceptDrops(True)
        self.viewport().setAcceptDrops(True)
        self._base = self._add_image_layer(_Z_BASE)
        self._overlay = self._add_image_layer(_Z_OVERLAY)
        self._outlines = self._add_image_layer(_Z_OUTLINE)
        self._overlay.setOpacity(0.45)
        self._graph_item = QGraphicsPathItem()
        self._graph_item.setZValue(_Z_GRAPH)
        self._graph_item.setPen(_cosmetic_pen(QColor(20, 60, 160, 200), 1.5))
        self._graph_item.setVisible(False)
        self.scene().addItem(self._graph_item)
        self._labels: np.ndarray | None = None
        self._graph = None
        self._paths: dict[int, QPainterPath] = {}
        self._marks: dict[str, list] = {"highlight": [], "selection": [], "anchors": []}
        self._id_items: list[LabelItem] = []
        self._badge_items: dict[int, LabelItem] = {}
        self._ids_visible = False
        self._hovered = 0
        self._press_pos = None
        self._panning = False
        self.placeholder = "Drop a map here or use the File menu"
        self.horizontalScrollBar().valueChanged.connect(self.viewport_changed)
        self.verticalScrollBar().valueChanged.connect(self.viewport_changed)

    # ---- content -----------------------------------------------------------------
    def set_image(self, grey: np.ndarray | None) -> None:
        """Show a grey map image (``None`` clears the view) and fit it to the window."""
        self.set_segmentation(None, None)
        if grey is None:
            self._base.set_image(ImageItem().image())
            self.scene().setSceneRect(QRectF())
        else:
            self._base.set_image(*grey_to_qimage(grey))
            self.scene().setSceneRect(QRectF(0, 0, grey.shape[1], grey.shape[0]))
            self.fit_to_window()
        self.viewport().update()

    def has_image(self) -> bool:
        return not self._base.image().isNull()

    def set_segmentation(self, labels: np.ndarray | None, graph=None) -> None:
        """Use a label image and region graph (``None`` removes every overlay layer)."""
        self._labels, self._graph = labels, graph
        self._paths.clear()
        for kind in self._marks:
            self._set_marks(kind, {})
        self.set_badges({})
        empty = ImageItem().image()
        self._overlay.set_image(empty)
        if labels is None:
            self._outlines.set_image(empty)
            self._graph_item.setPath(QPainterPath())
        else:
            self._outlines.set_image(*mask_qimage(outline_mask(labels), (30, 30, 40, 220)))
            self._graph_item.setPath(_graph_path(graph, labels.shape))
        self._rebuild_ids()

    def labels(self) -> np.ndarray | None:
        return self._labels

    def set_region_colours(self, table: np.ndarray) -> None:
        """Colour the regions with an RGBA lookup table indexed by region id."""
        if self._labels is None:
            return
        self._overlay.set_image(*lut_qimage(self._labels, table))

    def set_overlay_opacity(self, opacity: float) -> None:
        self._overlay.setOpacity(max(0.0, min(1.0, float(opacity))))

    def overlay_opacity(self) -> float:
        return self._overlay.opacity()

    def set_outlines_visible(self, visible: bool) -> None:
        self._outlines.setVisible(bool(visible))

    def set_graph_visible(self, visible: bool) -> None:
        self._graph_item.setVisible(bool(visible))

    def set_ids_visible(self, visible: bool) -> None:
        self._ids_visible = bool(visible)
        if self._ids_visible and not self._id_items:
            self._rebuild_ids()
        self._cull_ids()

    def _cull_ids(self) -> None:
        zoom = self.zoom_factor()
        for item in self._id_items:
            item.setVisible(self._ids_visible and item.data(1) * zoom >= MIN_ID_REGION_PX)

    def visible_ids(self) -> set[int]:
        """Region ids drawn at the current zoom."""
        return {item.data(0) for item in self._id_items if item.isVisible()}

    def set_highlight(self, regions) -> None:
        """Highlight regions (the partners of the region hovered in the other view)."""
        self._set_marks("highlight", {r: (QColor(255, 200, 0, 150), QColor(230, 120, 0), Qt.PenStyle.SolidLine) for r in regions})

    def set_selection(self, regions) -> None:
        self._set_marks("selection", {r: (QColor(255, 255, 255, 90), QColor(0, 90, 255), Qt.PenStyle.SolidLine) for r in regions})

    def set_anchors(self, regions) -> None:
        """Mark the anchor regions of the last match with a dashed outline."""
        self._set_marks("anchors", {r: (QColor(0, 0, 0, 0), QColor(120, 0, 140), Qt.PenStyle.DashLine) for r in regions})

    def marked_regions(self, kind: str) -> set[int]:
        """Regions currently drawn as ``kind`` ('highlight', 'selection' or 'anchors')."""
        return {item.data(0) for item in self._marks[kind]}

    def set_badges(self, badges: dict[int, tuple[str, QColor]]) -> None:
        """Small tags next to region ids, e.g. {region: ("TP", green)}."""
        for item in self._badge_items.values():
            self.scene().removeItem(item)
        self._badge_items = {}
        positions = region_label_positions(self._graph) if self._graph is not None else {}
        for region, (text, colour) in badges.items():
            if region in positions:
                row, col = positions[region]
                item = LabelItem(text, colour, QColor("white"), offset=(0, 16))
                item.setPos(col + 0.5, row + 0.5)
                item.setZValue(_Z_LABELS)
                self.scene().addItem(item)
                self._badge_items[region] = item

    def badge_texts(self) -> dict[int, str]:
        """Badge text per region, as drawn."""
        return {region: item.text() for region, item in self._badge_items.items()}

    def region_scene_point(self, region: int) -> QPointF | None:
        """Scene point inside ``region`` (its interior point), for connector lines."""
        if self._graph is None or region not in self._graph:
            return None
        attrs = self._graph.nodes[region]
        row, col = attrs.get("interior") or attrs["centroid"]
        return QPointF(col + 0.5, row + 0.5)

    def region_at(self, row: int, col: int) -> int:
        if self._labels is None or not (0 <= row < self._labels.shape[0] and 0 <= col < self._labels.shape[1]):
            return 0
        return int(self._labels[row, col])

    # ---- zoom ----------------------------------------------------------------------
    def zoom_factor(self) -> float:
        return self.transform().m11()

    def set_zoom(self, factor: float, anchor: QPointF | None = None) -> None:
        """Zoom to ``factor`` (clamped to [fit / 4, 32]).

        The scene point under ``anchor`` (a viewport position, default the centre)
        stays under it.
        """
        floor = min(1.0, self._fit_factor() / 4.0)
        factor = max(floor, min(MAX_ZOOM, float(factor)))
        if math.isclose(factor, self.zoom_factor(), rel_tol=1e-9):
            return
        anchor = QPointF(self.viewport().rect().center()) if anchor is None else QPointF(anchor)
        fixed = self.mapToScene(anchor.toPoint())
        step = factor / self.zoom_factor()
        self.scale(step, step)
        moved = self.mapFromScene(fixed) - anchor.toPoint()
        self.horizontalScrollBar().setValue(self.horizontalScrollBar().value() + moved.x())
        self.verticalScrollBar().setValue(self.verticalScrollBar().value() + moved.y())
        self._cull_ids()
        self.zoom_changed.emit(self.zoom_factor())
        self.viewport_changed.emit()

    def fit_to_window(self) -> None:
        if self.has_image():
            self.fitInView(self.sceneRect(), Qt.AspectRatioMode.KeepAspectRatio)
            self._cull_ids()
            self.zoom_changed.emit(self.zoom_factor())
            self.viewport_changed.emit()

    def _fit_factor(self) -> float:
        rect = self.sceneRect()
        if rect.isEmpty():
            return 1.0
        viewport = self.viewport().rect()
        return max(1e-3, min(viewport.width() / rect.width(), viewport.height() / rect.height()))

    # ---- events ----------------------------------------------------------------------
    def wheelEvent(self, event) -> None:
        steps = event.angleDelta().y() / 120.0
        if steps and self.has_image():
            self.set_zoom(self.zoom_factor() * _WHEEL_STEP**steps, event.position())
        event.accept()

    def mousePressEvent(self, event) -> None:
        if event.button() in (Qt.MouseButton.LeftButton, Qt.MouseButton.MiddleButton):
            self._press_pos = event.position()
            self._panning = event.button() == Qt.MouseButton.MiddleButton
            self._last_pos = event.position()
        event.accept()

    def mouseMoveEvent(self, event) -> None:
        position = event.position()
        if self._press_pos is not None:
            moved = (position - self._press_pos).manhattanLength()
            if self._panning or moved >= QApplication.startDragDistance():
                self._panning = True
                delta = position - self._last_pos
                self.horizontalScrollBar().setValue(self.horizontalScrollBar().value() - round(delta.x()))
                self.verticalScrollBar().setValue(self.verticalScrollBar().value() - round(delta.y()))
                self.viewport().setCursor(Qt.CursorShape.ClosedHandCursor)
            self._last_pos = position
        self._report_cursor(position)
        event.accept()

    def mouseReleaseEvent(self, event) -> None:
        if self._press_pos is not None and not self._panning and event.button() == Qt.MouseButton.LeftButton:
            row, col = self._pixel_at(event.position())
            additive = bool(event.modifiers() & (Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier))
            self.region_clicked.emit(self.region_at(row, col), additive)
        self._press_pos = None
        self._panning = False
        self.viewport().unsetCursor()
        event.accept()

    def mouseDoubleClickEvent(self, event) -> None:
        self.mousePressEvent(event)

    def leaveEvent(self, event) -> None:
        self.cursor_moved.emit(-1, -1)
        if self._hovered:
            self._hovered = 0
            self.region_hovered.emit(0)
        super().leaveEvent(event)

    def scrollContentsBy(self, dx: int, dy: int) -> None:
        super().scrollContentsBy(dx, dy)
        self.viewport_changed.emit()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self.viewport_changed.emit()

    def dragEnterEvent(self, event) -> None:
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    dragMoveEvent = dragEnterEvent

    def dropEvent(self, event) -> None:
        paths = [Path(url.toLocalFile()) for url in event.mimeData().urls() if url.isLocalFile()]
        if paths:
            event.acceptProposedAction()
            self.files_dropped.emit(paths)

    def drawForeground(self, painter: QPainter, rect: QRectF) -> None:
        if self.has_image():
            return
        painter.save()
        painter.resetTransform()
        painter.setPen(QColor(110, 110, 120))
        painter.drawText(self.viewport().rect(), Qt.AlignmentFlag.AlignCenter, self.placeholder)
        painter.restore()

    # ---- helpers -------------------------------------------------------------------------
    def _pixel_at(self, position) -> tuple[int, int]:
        point = self.mapToScene(position.toPoint())
        return math.floor(point.y()), math.floor(point.x())

    def _report_cursor(self, position) -> None:
        row, col = self._pixel_at(position)
        rect = self.sceneRect()
        inside = self.has_image() and 0 <= row < rect.height() and 0 <= col < rect.width()
        self.cursor_moved.emit(row if inside else -1, col if inside else -1)
        region = self.region_at(row, col) if inside else 0
        if region != self._hovered:
            self._hovered = region
            self.region_hovered.emit(region)

    def _add_image_layer(self, z: int) -> ImageItem:
        item = ImageItem()
        item.setZValue(z)
        self.scene().addItem(item)
        return item

    def _region_path(self, region: int) -> QPainterPath:
        # Outlines are computed on first use and cached until the segmentation changes.
        if region not in self._paths:
            bbox = self._graph.nodes[region].get("bbox") if self._graph is not None and region in self._graph else None
            self._paths[region] = region_outline_path(self._labels, region, bbox)
        return self._paths[region]

    def _set_marks(self, kind: str, styles: dict) -> None:
        for item in self._marks[kind]:
            self.scene().removeItem(item)
        self._marks[kind] = []
        if self._labels is None:
            return
        z = _Z_MARKS + {"anchors": 0.1, "selection": 0.2, "highlight": 0.3}[kind]
        for region, (fill, line, style) in styles.items():
            if region <= 0:
                continue
            item = QGraphicsPathItem(self._region_path(int(region)))
            item.setBrush(QBrush(fill))
            pen = _cosmetic_pen(line, 2.5)
            pen.setStyle(style)
            item.setPen(pen)
            item.setZValue(z)
            item.setData(0, int(region))
            self.scene().addItem(item)
            self._marks[kind].append(item)

    def _rebuild_ids(self) -> None:
        for item in self._id_items:
            self.scene().removeItem(item)
        self._id_items = []
        # Built on demand: thousands of tags cost time and are hidden by default.
        if self._graph is None or not self._ids_visible:
            return
        for region, (row, col) in region_label_positions(self._graph).items():
            item = LabelItem(str(region), QColor(255, 255, 255, 210), QColor(20, 20, 30))
            item.setPos(col + 0.5, row + 0.5)
            item.setZValue(_Z_LABELS)
            bbox = self._graph.nodes[region].get("bbox")
            item.setData(0, region)
            item.setData(1, min(bbox[2] - bbox[0], bbox[3] - bbox[1]) if bbox else MIN_ID_REGION_PX)
            self.scene().addItem(item)
            self._id_items.append(item)
        self._cull_ids()


def _cosmetic_pen(colour: QColor, width: float) -> QPen:
    pen = QPen(colour, width)
    pen.setCosmetic(True)  # constant width on screen at every zoom
    return pen


def _graph_path(graph, shape) -> QPainterPath:
    """Region adjacency graph as one path: edges between centroids and node dots."""
    path = QPainterPath()
    if graph is None:
        return path
    centre = {n: (a["centroid"][1] + 0.5, a["centroid"][0] + 0.5) for n, a in graph.nodes(data=True) if a.get("centroid") is not None}
    for a, b in graph.edges():
        if a in centre and b in centre:
            path.moveTo(*centre[a])
            path.lineTo(*centre[b])
    radius = max(1.5, max(shape) / 250.0)
    for x, y in centre.values():
        path.addEllipse(QPointF(x, y), radius, radius)
    return path
