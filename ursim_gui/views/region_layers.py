"""The region layers of a map view's scene: overlay, outlines, graph, marks, ids, badges.

Pixel layers are whole-image QImages built with one numpy pass each (lookup table for
the overlay, neighbour comparison for outlines). Marks (hover highlight, selection,
anchors) are per-region outline paths computed lazily on the region's bounding box and
cached, so hovering only adds or removes a few small items.
"""

from __future__ import annotations

import contextlib

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QImage, QPainterPath, QPen
from PySide6.QtWidgets import QGraphicsPathItem, QGraphicsScene

from ursim_gui.model.region_style import outline_mask, region_label_positions, region_mask
from ursim_gui.views.map_items import (
    ImageItem,
    LabelItem,
    lut_qimage,
    mask_qimage,
    pack_premultiplied,
    region_outline_path,
)

__all__ = ["RegionLayers", "MIN_ID_REGION_PX", "MARK_STYLES"]

#: A region's id is drawn only when the region is at least this many screen pixels
#: across, so zoomed-out maps with many regions stay readable (and cheap to paint).
MIN_ID_REGION_PX = 28
#: Up to this many recoloured regions are patched in place; more re-index the image.
_MAX_PATCHED_REGIONS = 64
_Z_OVERLAY, _Z_OUTLINE, _Z_GRAPH, _Z_MARKS, _Z_LABELS = 1, 2, 3, 4, 5
#: The laid sketch's outlines sit over the map's own outlines, under the graph and the marks.
_Z_LAID = 2.5
#: kind -> (fill, outline colour, pen style, z offset above the marks base)
MARK_STYLES = {
    "anchors": (QColor(0, 0, 0, 0), QColor(215, 0, 150), Qt.PenStyle.DashLine, 0.1),
    "selection": (QColor(255, 255, 255, 90), QColor(0, 90, 255), Qt.PenStyle.SolidLine, 0.2),
    "highlight": (QColor(255, 200, 0, 150), QColor(230, 120, 0), Qt.PenStyle.SolidLine, 0.3),
}


def cosmetic_pen(colour: QColor, width: float) -> QPen:
    """A pen of constant on-screen width at every zoom."""
    pen = QPen(colour, width)
    pen.setCosmetic(True)
    return pen


class RegionLayers:
    """Owns the scene items drawn over a map for one segmentation."""

    def __init__(self, scene: QGraphicsScene):
        self.scene = scene
        self.overlay = self._image_layer(_Z_OVERLAY)
        self.overlay.setOpacity(0.45)
        self.outlines = self._image_layer(_Z_OUTLINE)
        self.laid = self._image_layer(_Z_LAID)
        # (labels, their outline pixels' ids, colour table) last drawn on the laid layer.
        self._laid_drawn: tuple = (None, None, None)
        self.graph_item = QGraphicsPathItem()
        self.graph_item.setZValue(_Z_GRAPH)
        self.graph_item.setPen(cosmetic_pen(QColor(20, 60, 160, 200), 1.5))
        self.graph_item.setVisible(False)
        scene.addItem(self.graph_item)
        self.labels: np.ndarray | None = None
        self.graph = None
        self._paths: dict[int, QPainterPath] = {}
        self._marks: dict[str, list[QGraphicsPathItem]] = {kind: [] for kind in MARK_STYLES}
        self._ids: list[LabelItem] = []
        self._ids_visible = False
        self._badges: dict[int, LabelItem] = {}
        self._packed: np.ndarray | None = None
        self.positions: dict[int, tuple[float, float]] = {}

    def _image_layer(self, z: int) -> ImageItem:
        item = ImageItem()
        item.setZValue(z)
        self.scene.addItem(item)
        return item

    def set_segmentation(self, labels: np.ndarray | None, graph) -> None:
        self.labels, self.graph = labels, graph
        self.positions = region_label_positions(graph) if graph is not None else {}
        self._packed = None
        self._paths.clear()
        for kind in self._marks:
            self.set_marks(kind, ())
        self.set_badges({})
        self.overlay.set_image(QImage())
        if labels is None:
            self.outlines.set_image(QImage())
            self.graph_item.setPath(QPainterPath())
        else:
            self.outlines.set_image(*mask_qimage(outline_mask(labels), (30, 30, 40, 220)))
            self.graph_item.setPath(_graph_path(graph, labels.shape))
        self._rebuild_ids()

    def set_laid(self, labels: np.ndarray | None, table: np.ndarray | None = None) -> None:
        """Outline another map's regions laid on this one (``labels`` on this map's pixels),
        coloured by ``table`` (RGBA rows by region id); None clears the layer."""
        if labels is None or table is None:
            self._laid_drawn = (None, None, None)
            self.laid.set_image(QImage())
            return
        drawn_labels, edges, drawn_table = self._laid_drawn
        if labels is not drawn_labels:
            edges = np.where(outline_mask(labels), labels, 0)
        elif drawn_table is not None and np.array_equal(table, drawn_table):
            return  # an edit that recoloured no laid region: nothing to redraw
        self._laid_drawn = (labels, edges, np.array(table, copy=True))
        self.laid.set_image(*lut_qimage(edges, table))

    def set_colours(self, table: np.ndarray) -> None:
        """Colour the overlay with an RGBA table indexed by region id.

        An edit recolours a few regions: when few table rows changed, only those
        regions' pixels are rewritten (on their bounding boxes) and only their area is
        repainted, instead of re-indexing the whole label image.
        """
        if self.labels is None:
            return
        packed = pack_premultiplied(table)
        previous = self._packed
        if previous is not None and len(previous) == len(packed) and self.graph is not None:
            changed = np.nonzero(previous != packed)[0]
            if len(changed) <= _MAX_PATCHED_REGIONS:
                self._packed = packed
                for region in changed.tolist():
                    self._patch_region(region, packed[region])
                return
        self._packed = packed
        self.overlay.set_image(*lut_qimage(self.labels, table))

    def _patch_region(self, region: int, value: np.uint32) -> None:
        if region == 0 or region not in self.graph:
            return
        pixels = self.overlay.pixels()
        mask, (row0, col0) = region_mask(self.labels, region, self.graph.nodes[region].get("bbox"))
        pixels[row0 : row0 + mask.shape[0], col0 : col0 + mask.shape[1]][mask] = value
        self.overlay.update(QRectF(col0, row0, mask.shape[1], mask.shape[0]))

    def region_point(self, region: int) -> QPointF | None:
        if self.graph is None or region not in self.graph:
            return None
        attrs = self.graph.nodes[region]
        row, col = attrs.get("interior") or attrs["centroid"]
        return QPointF(col + 0.5, row + 0.5)

    # ---- marks ------------------------------------------------------------------
    def set_marks(self, kind: str, regions) -> None:
        regions = [int(region) for region in regions]
        if self._marks[kind] and set(regions) == self.marked_regions(kind):
            return  # unchanged: keep the items (edits re-send anchors and selection)
        for item in self._marks[kind]:
            self.scene.removeItem(item)
        self._marks[kind] = []
        if self.labels is None:
            return
        fill, line, style, z = MARK_STYLES[kind]
        pen = cosmetic_pen(line, 3.0 if kind == "anchors" else 2.5)
        pen.setStyle(style)
        for region in regions:
            if region <= 0 or (self.graph is not None and region not in self.graph):
                continue
            item = QGraphicsPathItem(self._path(int(region)))
            item.setBrush(QBrush(fill))
            item.setPen(pen)
            item.setZValue(_Z_MARKS + z)
            item.setData(0, int(region))
            self.scene.addItem(item)
            self._marks[kind].append(item)

    def marked_regions(self, kind: str) -> set[int]:
        return {item.data(0) for item in self._marks[kind]}

    @contextlib.contextmanager
    def hidden(self, *kinds: str):
        """Hide marks of ``kinds`` inside the block (figures show no selection or hover)."""
        items = [item for kind in kinds for item in self._marks[kind] if item.isVisible()]
        for item in items:
            item.setVisible(False)
        try:
            yield
        finally:
            for item in items:
                item.setVisible(True)

    @contextlib.contextmanager
    def ids_shown(self, zoom: float):
        """Show the region ids inside the block, culled for ``zoom`` (figures always name regions)."""
        was_visible = self._ids_visible
        self._ids_visible = True
        if not self._ids:
            self._rebuild_ids()
        before = [was_visible and item.isVisible() for item in self._ids]
        self.cull_ids(zoom)
        try:
            yield
        finally:
            self._ids_visible = was_visible
            for item, visible in zip(self._ids, before):
                item.setVisible(visible)

    def _path(self, region: int) -> QPainterPath:
        # Outlines are computed on first use and cached until the segmentation changes.
        if region not in self._paths:
            bbox = self.graph.nodes[region].get("bbox") if self.graph is not None and region in self.graph else None
            self._paths[region] = region_outline_path(self.labels, region, bbox)
        return self._paths[region]

    # ---- ids and badges ------------------------------------------------------------------
    def set_ids_visible(self, visible: bool, zoom: float) -> None:
        self._ids_visible = bool(visible)
        if self._ids_visible and not self._ids:
            self._rebuild_ids()
        self.cull_ids(zoom)

    def cull_ids(self, zoom: float) -> None:
        """Show the ids of regions big enough on screen at ``zoom``."""
        for item in self._ids:
            item.setVisible(self._ids_visible and item.data(1) * zoom >= MIN_ID_REGION_PX)

    def visible_ids(self) -> set[int]:
        return {item.data(0) for item in self._ids if item.isVisible()}

    def _rebuild_ids(self) -> None:
        for item in self._ids:
            self.scene.removeItem(item)
        self._ids = []
        # Built on demand: thousands of tags cost time and are hidden by default.
        if self.graph is None or not self._ids_visible:
            return
        for region, (row, col) in self.positions.items():
            # Above the interior point, badges below: connector lines end between them.
            item = LabelItem(str(region), QColor(255, 255, 255, 210), QColor(20, 20, 30), offset=(0, -10))
            item.setPos(col + 0.5, row + 0.5)
            item.setZValue(_Z_LABELS)
            bbox = self.graph.nodes[region].get("bbox")
            item.setData(0, region)
            item.setData(1, min(bbox[2] - bbox[0], bbox[3] - bbox[1]) if bbox else MIN_ID_REGION_PX)
            item.setVisible(False)
            self.scene.addItem(item)
            self._ids.append(item)

    def set_badges(self, badges: dict[int, tuple[str, QColor]]) -> None:
        if {
            region: text for region, (text, _colour) in badges.items() if region in self.positions
        } == self.badge_texts():
            return
        for item in self._badges.values():
            self.scene.removeItem(item)
        self._badges = {}
        for region, (text, colour) in badges.items():
            if region in self.positions:
                row, col = self.positions[region]
                item = LabelItem(text, colour, QColor("white"), offset=(0, 10))
                item.setPos(col + 0.5, row + 0.5)
                item.setZValue(_Z_LABELS)
                self.scene.addItem(item)
                self._badges[region] = item

    def badge_texts(self) -> dict[int, str]:
        return {region: item.text() for region, item in self._badges.items()}


def _graph_path(graph, shape) -> QPainterPath:
    """Region adjacency graph as one path: edges between centroids and node dots."""
    path = QPainterPath()
    if graph is None:
        return path
    centre = {
        n: (a["centroid"][1] + 0.5, a["centroid"][0] + 0.5)
        for n, a in graph.nodes(data=True)
        if a.get("centroid") is not None
    }
    for a, b in graph.edges():
        if a in centre and b in centre:
            path.moveTo(*centre[a])
            path.lineTo(*centre[b])
    radius = max(1.5, max(shape) / 250.0)
    for x, y in centre.values():
        path.addEllipse(QPointF(x, y), radius, radius)
    return path
