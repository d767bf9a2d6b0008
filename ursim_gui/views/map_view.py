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
from PySide6.QtCore import QEvent, QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QImage, QPainter, QPalette, QPixmapCache, QTransform
from PySide6.QtWidgets import QApplication, QGraphicsScene, QGraphicsView, QStyle

from ursim_gui.views.map_items import ImageItem, grey_to_qimage
from ursim_gui.views.orientation_bar import OrientationBar
from ursim_gui.views.region_layers import MIN_ID_REGION_PX, RegionLayers

__all__ = [
    "MapView",
    "MAX_ZOOM",
    "MIN_ID_REGION_PX",
    "DRAWN_MARGIN",
    "drawn_area",
    "oriented_transform",
]

#: Largest zoom factor (3200 %).
MAX_ZOOM = 32.0
#: Around a map's drawn part, the view fits this share of its longer side as a margin.
DRAWN_MARGIN = 0.05
# Pixels left free around a fitted map on each axis (QGraphicsView.fitInView leaves 4).
_FIT_PADDING = 4
_PIXMAP_CACHE_KB = 192 * 1024
_WHEEL_STEP = 1.25
_BUTTONS_FROM_CORNER_PX = 6


def oriented_transform(angle: float, mirrored: bool, factor: float = 1.0) -> QTransform:
    """The transform that shows a map mirrored (left-right) first, then turned ``angle`` degrees
    counter-clockwise, at ``factor``: the sketch view's, and the reading tiles'."""
    transform = QTransform()
    if angle:
        transform.rotate(-angle)  # Qt turns clockwise for a positive angle (y down)
    # Called after rotate, the scale applies to the points first: the mirror comes before the turn.
    transform.scale(-factor if mirrored else factor, factor)
    return transform


def drawn_area(box, margin: float) -> QRectF:
    """The scene rectangle of a drawn part ``box`` (``(first row, end row, first col, end col)``, as
    ``ursim_core.matching.template.free_box`` gives the free space's) with ``margin`` times its
    longer side (at least a pixel) on every side; not clipped to the image.

    Examples
    --------
    >>> drawn_area((10, 20, 30, 70), 0.02).getRect()
    (29.0, 9.0, 42.0, 12.0)
    """
    first_row, end_row, first_col, end_col = box
    pad = max(1, round(margin * max(end_row - first_row, end_col - first_col)))
    return QRectF(first_col - pad, first_row - pad, end_col - first_col + 2 * pad, end_row - first_row + 2 * pad)


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
    turn_requested(float), mirror_requested(bool) : the sketch view's turn (degrees counter-clockwise)
        and mirror buttons, in its top left corner; they only ask: the holder of the orientation
        answers with :meth:`set_orientation`
    """

    region_hovered = Signal(int)
    region_clicked = Signal(int, bool)
    cursor_moved = Signal(int, int)
    zoom_changed = Signal(float)
    viewport_changed = Signal()
    files_dropped = Signal(list)
    #: A left-button stroke in stroke mode: list of (row, col) map pixels, press to release.
    stroke_drawn = Signal(list)
    turn_requested = Signal(float)
    mirror_requested = Signal(bool)

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
        self._follow_palette()
        self.setMouseTracking(True)
        self.setAcceptDrops(True)
        self.viewport().setAcceptDrops(True)
        self._base = ImageItem()
        self.scene().addItem(self._base)
        self.layers = RegionLayers(self.scene())
        self._hovered = 0
        self._fitted = False
        #: The scene rectangle a fit shows: the drawn part and its margin (the whole map when null).
        self._drawn = QRectF()
        self._press_pos = None
        self._panning = False
        self._stroke: list[tuple[int, int]] | None = None
        self.stroke_mode = False
        #: (degrees counter-clockwise, mirrored) the map is shown at.
        self.orientation = (0.0, False)
        self.placeholder = "Drop a map here or use the File menu"
        self.horizontalScrollBar().valueChanged.connect(self.viewport_changed)
        self.verticalScrollBar().valueChanged.connect(self.viewport_changed)
        #: The orientation buttons (:class:`~ursim_gui.views.orientation_bar.OrientationBar`) by key; none on the metric view.
        self.orientation_actions = {}
        self.orientation_bar = None
        if side == "sketch":
            # A child of the view, not of the viewport: Qt scrolls the viewport's children with the map.
            self.orientation_bar = OrientationBar(self, f"{side}_orientation_buttons")
            self.orientation_bar.turn_requested.connect(self.turn_requested)
            self.orientation_bar.mirror_requested.connect(self.mirror_requested)
            self.orientation_actions = self.orientation_bar.actions_by_key

    # ---- content -----------------------------------------------------------------
    def set_image(self, grey: np.ndarray | None, drawn=None) -> None:
        """Show a grey map image (``None`` clears the view) and fit its drawn part to the window.

        ``drawn``: the box of the drawn part, ``(first row, end row, first col, end col)`` (the free
        space's, ``ursim_core.matching.template.free_box``): a fit shows it with a margin of
        :data:`DRAWN_MARGIN`, so a sketch drawn small on a large sheet fills the view. None: the whole map.
        """
        self.set_segmentation(None, None)
        if grey is None:
            self._base.set_image(QImage())
            self.scene().setSceneRect(QRectF())
            self._drawn = QRectF()
        else:
            self._base.set_image(*grey_to_qimage(grey))
            self.scene().setSceneRect(QRectF(0, 0, grey.shape[1], grey.shape[0]))
            self._drawn = QRectF() if drawn is None else drawn_area(drawn, DRAWN_MARGIN) & self.sceneRect()
            self.fit_to_window()
        if self.orientation_bar is not None:
            self.orientation_bar.setVisible(grey is not None)  # nothing to turn without a map
        self.viewport().update()

    def has_image(self) -> bool:
        return not self._base.image().isNull()

    def map_image(self) -> QImage:
        """The map's own image as opened: no overlay, not turned (null when none is shown)."""
        return self._base.image()

    def set_segmentation(self, labels: np.ndarray | None, graph=None) -> None:
        """Use a label image and region graph (``None`` removes every overlay layer)."""
        self.layers.set_segmentation(labels, graph)
        self.layers.cull_ids(self.zoom_factor())

    def labels(self) -> np.ndarray | None:
        return self.layers.labels

    def set_region_colours(self, table: np.ndarray) -> None:
        """Colour the regions with an RGBA lookup table indexed by region id."""
        self.layers.set_colours(table)

    def set_overlay_opacity(self, opacity: float) -> None:
        self.layers.overlay.setOpacity(max(0.0, min(1.0, float(opacity))))

    def overlay_opacity(self) -> float:
        return self.layers.overlay.opacity()

    def set_outlines_visible(self, visible: bool) -> None:
        self.layers.outlines.setVisible(bool(visible))

    def set_laid_sketch(self, labels: np.ndarray | None, table: np.ndarray | None = None) -> None:
        """Outline the sketch's regions where the matcher laid them on this map (None: hide)."""
        self.layers.set_laid(labels, table)

    def has_laid_sketch(self) -> bool:
        return not self.layers.laid.image().isNull()

    def set_graph_visible(self, visible: bool) -> None:
        self.layers.graph_item.setVisible(bool(visible))

    def set_ids_visible(self, visible: bool) -> None:
        self.layers.set_ids_visible(visible, self.zoom_factor())

    def visible_ids(self) -> set[int]:
        """Region ids drawn at the current zoom."""
        return self.layers.visible_ids()

    def set_highlight(self, regions) -> None:
        """Highlight regions (the partners of the region hovered in the other view)."""
        self.layers.set_marks("highlight", regions)

    def set_selection(self, regions) -> None:
        self.layers.set_marks("selection", regions)

    def set_anchors(self, regions) -> None:
        """Mark the anchor regions of the last match with a dashed outline."""
        self.layers.set_marks("anchors", regions)

    def marked_regions(self, kind: str) -> set[int]:
        """Regions currently drawn as ``kind`` ('highlight', 'selection' or 'anchors')."""
        return self.layers.marked_regions(kind)

    def set_badges(self, badges: dict[int, tuple[str, QColor]]) -> None:
        """Small tags next to region ids, e.g. {region: ("TP", green)}."""
        self.layers.set_badges(badges)

    def badge_texts(self) -> dict[int, str]:
        """Badge text per region, as drawn."""
        return self.layers.badge_texts()

    def region_scene_point(self, region: int) -> QPointF | None:
        """Scene point inside ``region`` (its interior point), for connector lines."""
        return self.layers.region_point(region)

    def region_at(self, row: int, col: int) -> int:
        labels = self.layers.labels
        if labels is None or not (0 <= row < labels.shape[0] and 0 <= col < labels.shape[1]):
            return 0
        return int(labels[row, col])

    # ---- zoom ----------------------------------------------------------------------
    def zoom_factor(self) -> float:
        # The scale of the transform, whatever its rotation or mirror.
        transform = self.transform()
        if transform.m12() == 0.0:
            return abs(transform.m11())  # exact when not turned (hypot would round)
        return math.hypot(transform.m11(), transform.m12())

    def set_orientation(self, angle: float, mirrored: bool) -> None:
        """Show the map mirrored (left-right) and then turned ``angle`` degrees counter-clockwise.

        Only the view turns: scene coordinates stay the image's pixels, so clicks and
        points keep the original frame.
        """
        self.orientation = (float(angle), bool(mirrored))
        if self.orientation_bar is not None:
            self.orientation_bar.show_mirrored(self.orientation[1])
        self.setTransform(self._oriented(1.0))
        self.fit_to_window()

    def _oriented(self, factor: float) -> QTransform:
        return oriented_transform(*self.orientation, factor)

    def set_zoom(self, factor: float, anchor: QPointF | None = None) -> None:
        """Zoom to ``factor`` (clamped to [fit / 4, 32]).

        The scene point under ``anchor`` (a viewport position, default the centre)
        stays under it.
        """
        floor = min(1.0, self._fit_factor() / 4.0)
        factor = max(floor, min(MAX_ZOOM, float(factor)))
        if math.isclose(factor, self.zoom_factor(), rel_tol=1e-9):
            return
        self._fitted = False
        anchor = QPointF(self.viewport().rect().center()) if anchor is None else QPointF(anchor)
        fixed = self.mapToScene(anchor.toPoint())
        # Rebuilt from the orientation rather than scaled by a step: the factor is exact.
        self.setTransform(self._oriented(factor))
        moved = self.mapFromScene(fixed) - anchor.toPoint()
        self.horizontalScrollBar().setValue(self.horizontalScrollBar().value() + moved.x())
        self.verticalScrollBar().setValue(self.verticalScrollBar().value() + moved.y())
        self.layers.cull_ids(self.zoom_factor())
        self.zoom_changed.emit(self.zoom_factor())
        self.viewport_changed.emit()

    def fit_to_window(self) -> None:
        """Show the map's drawn part (the whole map when none was given, see :meth:`set_image`); it
        stays fitted when the view is resized until a zoom."""
        if not self.has_image():
            return
        self._fitted = True
        shown = self.sceneRect() if self._drawn.isEmpty() else self._drawn
        # Fitted to the viewport as it is with both scroll bars shown, whether they are or not. A
        # drawn part smaller than the sheet brings the bars, which shrink the viewport; fitted to
        # the viewport as it was (QGraphicsView.fitInView), each resize that followed fitted it
        # again at the other zoom, without end (a KTH campaign hung on sketch 20, round 57).
        available = self.maximumViewportSize()
        bar = self.style().pixelMetric(QStyle.PixelMetric.PM_ScrollBarExtent, None, self)
        width, height = available.width() - bar - _FIT_PADDING, available.height() - bar - _FIT_PADDING
        turned = self._oriented(1.0).mapRect(shown)
        if width > 0 and height > 0 and not turned.isEmpty():
            factor = min(MAX_ZOOM, width / turned.width(), height / turned.height())
            self.setTransform(self._oriented(factor))
            self.centerOn(shown.center())
        self.layers.cull_ids(self.zoom_factor())
        self.zoom_changed.emit(self.zoom_factor())
        self.viewport_changed.emit()

    def zoom_to_regions(self, regions, *, margin: float = 0.25) -> bool:
        """Zoom onto the bounding box of ``regions`` (graph ``bbox`` attributes), with a margin.

        False when none of them is in the segmentation (the view is left as it is).
        """
        graph = self.layers.graph
        boxes = [
            graph.nodes[r]["bbox"] for r in regions if graph is not None and r in graph and "bbox" in graph.nodes[r]
        ]
        if not boxes:
            return False
        top, left = min(b[0] for b in boxes), min(b[1] for b in boxes)
        bottom, right = max(b[2] for b in boxes), max(b[3] for b in boxes)
        pad = margin * max(bottom - top, right - left, 10)
        rect = QRectF(left - pad, top - pad, right - left + 2 * pad, bottom - top + 2 * pad)
        self._fitted = False
        self.fitInView(rect.intersected(self.sceneRect()), Qt.AspectRatioMode.KeepAspectRatio)
        self.layers.cull_ids(self.zoom_factor())
        self.zoom_changed.emit(self.zoom_factor())
        self.viewport_changed.emit()
        return True

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

    def set_stroke_mode(self, on: bool) -> None:
        """Left drags draw a stroke (``stroke_drawn``) instead of selecting or panning; middle still pans."""
        self.stroke_mode = bool(on)
        self._stroke = None
        self.viewport().setCursor(Qt.CursorShape.CrossCursor) if on else self.viewport().unsetCursor()

    def mousePressEvent(self, event) -> None:
        if self.stroke_mode and event.button() == Qt.MouseButton.LeftButton:
            self._stroke = [self._pixel_at(event.position())]
            event.accept()
            return
        if event.button() in (Qt.MouseButton.LeftButton, Qt.MouseButton.MiddleButton):
            self._press_pos = event.position()
            self._panning = event.button() == Qt.MouseButton.MiddleButton
            self._last_pos = event.position()
        event.accept()

    def mouseMoveEvent(self, event) -> None:
        position = event.position()
        if self._stroke is not None:
            point = self._pixel_at(position)
            if point != self._stroke[-1]:
                self._stroke.append(point)
            self._report_cursor(position)
            event.accept()
            return
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
        if self._stroke is not None and event.button() == Qt.MouseButton.LeftButton:
            stroke, self._stroke = self._stroke, None
            self.stroke_drawn.emit(stroke)
            event.accept()
            return
        if self._press_pos is not None and not self._panning and event.button() == Qt.MouseButton.LeftButton:
            row, col = self._pixel_at(event.position())
            additive = bool(
                event.modifiers() & (Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
            )
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
        if self.orientation_bar is not None:
            corner = self.viewport().geometry().topLeft()
            self.orientation_bar.move(corner.x() + _BUTTONS_FROM_CORNER_PX, corner.y() + _BUTTONS_FROM_CORNER_PX)
            self.orientation_bar.raise_()
        if self._fitted:
            self.fit_to_window()
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

    def _follow_palette(self) -> None:
        # The area around the map follows the theme (a light grey on light, dark on dark).
        window = self.palette().color(QPalette.ColorRole.Window)
        self.setBackgroundBrush(window.darker(106) if window.lightness() > 128 else window.darker(130))

    def changeEvent(self, event) -> None:
        if event.type() == QEvent.Type.PaletteChange:
            self._follow_palette()
        super().changeEvent(event)

    def drawForeground(self, painter: QPainter, rect: QRectF) -> None:
        if self.has_image():
            return
        painter.save()
        painter.resetTransform()
        painter.setPen(self.palette().color(QPalette.ColorRole.PlaceholderText))
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
