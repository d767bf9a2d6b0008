"""Graphics items of a map view: numpy-backed image layers, labels and region outlines.

Kept apart from :mod:`ursim_gui.views.map_view` so the view module only deals with
interaction and layer bookkeeping.
"""

from __future__ import annotations

import cv2
import numpy as np
from PySide6.QtCore import QPointF, QRect, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QFont, QFontMetricsF, QImage, QPainter, QPainterPath, QPen
from PySide6.QtWidgets import QGraphicsItem, QStyleOptionGraphicsItem

from ursim_gui.model.region_style import region_mask

__all__ = [
    "ImageItem",
    "LabelItem",
    "grey_to_qimage",
    "pack_premultiplied",
    "argb_qimage",
    "lut_qimage",
    "mask_qimage",
    "region_outline_path",
]


def grey_to_qimage(grey: np.ndarray) -> tuple[QImage, np.ndarray]:
    """A ``Grayscale8`` QImage sharing memory with ``grey`` (returned to keep it alive)."""
    grey = np.ascontiguousarray(grey, dtype=np.uint8)
    rows, cols = grey.shape
    return QImage(grey.data, cols, rows, grey.strides[0], QImage.Format.Format_Grayscale8), grey


def pack_premultiplied(table: np.ndarray) -> np.ndarray:
    """RGBA ``uint8`` rows -> premultiplied ``0xAARRGGBB`` ``uint32`` values.

    That is the pixel value of ``QImage.Format_ARGB32_Premultiplied`` on every
    endianness, the format the raster engine draws without conversion; doing the
    premultiplication on a (small) lookup table keeps an overlay at one gather.
    """
    table = np.asarray(table, dtype=np.uint32).reshape(-1, 4)
    alpha = table[:, 3]
    rgb = (table[:, :3] * alpha[:, None] + 127) // 255
    return (alpha << 24) | (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]


def argb_qimage(pixels: np.ndarray) -> tuple[QImage, np.ndarray]:
    """A QImage over a ``uint32`` array of premultiplied ``0xAARRGGBB`` pixels (no copy)."""
    pixels = np.ascontiguousarray(pixels, dtype=np.uint32)
    rows, cols = pixels.shape
    return QImage(pixels.data, cols, rows, pixels.strides[0], QImage.Format.Format_ARGB32_Premultiplied), pixels


def lut_qimage(labels: np.ndarray, table: np.ndarray) -> tuple[QImage, np.ndarray]:
    """QImage of a label image coloured by an RGBA lookup table: one ``uint32`` gather.

    Labels beyond the table are drawn transparent.
    """
    packed = pack_premultiplied(table)
    if labels.size and int(labels.max()) >= len(packed):
        packed = np.concatenate([packed, np.zeros(int(labels.max()) + 1 - len(packed), np.uint32)])
    return argb_qimage(packed[labels])


def mask_qimage(mask: np.ndarray, rgba: tuple[int, int, int, int]) -> tuple[QImage, np.ndarray]:
    """QImage that is ``rgba`` where ``mask`` is True and transparent elsewhere."""
    value = pack_premultiplied(np.array([rgba]))[0]
    return argb_qimage(np.where(mask, value, np.uint32(0)))


class ImageItem(QGraphicsItem):
    """An image layer drawn pixel for pixel (nearest neighbour), exposed part only.

    One scene unit is one map pixel, so pixel (row, col) covers x in [col, col + 1)
    and y in [row, row + 1).
    """

    def __init__(self, parent: QGraphicsItem | None = None):
        super().__init__(parent)
        self._image = QImage()
        self._keepalive: np.ndarray | None = None
        self.setFlag(QGraphicsItem.GraphicsItemFlag.ItemUsesExtendedStyleOption, True)
        # Big layers are scaled once per zoom level, not on every hover repaint.
        self.setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)

    def set_image(self, image: QImage, keepalive: np.ndarray | None = None) -> None:
        """Show ``image``; ``keepalive`` is the numpy buffer the image points into."""
        self.prepareGeometryChange()
        self._image = image
        self._keepalive = keepalive
        self.update()

    def image(self) -> QImage:
        return self._image

    def pixels(self) -> np.ndarray | None:
        """The numpy buffer the image points into (edits show after ``update``)."""
        return self._keepalive

    def boundingRect(self) -> QRectF:
        return QRectF(0, 0, self._image.width(), self._image.height())

    def paint(self, painter: QPainter, option: QStyleOptionGraphicsItem, widget=None) -> None:
        if self._image.isNull():
            return
        # Whole pixels only: a fractional source rect would resample and blur the edges.
        exposed = option.exposedRect.toAlignedRect().intersected(QRect(0, 0, self._image.width(), self._image.height()))
        if exposed.isEmpty():
            return
        painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, False)
        painter.drawImage(QRectF(exposed), self._image, QRectF(exposed))


class LabelItem(QGraphicsItem):
    """A small text tag with a rounded background that keeps its size at any zoom.

    Parameters
    ----------
    text : str
        The text.
    background, foreground : QColor
        Fill and text colours.
    offset : (dx, dy)
        Shift in screen pixels from the anchor point, so badges can sit beside ids.
    """

    _FONT_POINT_SIZE = 8

    def __init__(self, text: str, background: QColor, foreground: QColor, offset: tuple[float, float] = (0.0, 0.0)):
        super().__init__()
        self.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations, True)
        self.setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        self._text = text
        self._background = background
        self._foreground = foreground
        self._font = QFont()
        self._font.setPointSize(self._FONT_POINT_SIZE)
        self._font.setBold(True)
        metrics = QFontMetricsF(self._font)
        width = metrics.horizontalAdvance(text) + 6
        height = metrics.height() + 2
        self._rect = QRectF(offset[0] - width / 2, offset[1] - height / 2, width, height)

    def text(self) -> str:
        return self._text

    def boundingRect(self) -> QRectF:
        return self._rect.adjusted(-1, -1, 1, 1)

    def paint(self, painter: QPainter, option, widget=None) -> None:
        painter.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        painter.setPen(QPen(QColor(40, 40, 40, 160), 0.8))
        painter.setBrush(QBrush(self._background))
        painter.drawRoundedRect(self._rect, 3, 3)
        painter.setFont(self._font)
        painter.setPen(self._foreground)
        painter.drawText(self._rect, Qt.AlignmentFlag.AlignCenter, self._text)


def region_outline_path(labels: np.ndarray, region: int, bbox=None) -> QPainterPath:
    """Outline of one region as a painter path in scene coordinates (holes included).

    ``cv2.findContours`` traces pixel centres, which would lose one-pixel-wide parts
    and sit half a pixel inside; tracing the mask upscaled by 2 keeps thin parts and
    puts the outline within a quarter pixel of the region's pixel edges.
    """
    mask, (row0, col0) = region_mask(labels, region, bbox)
    path = QPainterPath()
    path.setFillRule(Qt.FillRule.OddEvenFill)
    if mask.size == 0:
        return path
    doubled = cv2.resize(np.pad(mask, 1).astype(np.uint8), None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST)
    contours, _ = cv2.findContours(doubled, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    for contour in contours:
        points = contour[:, 0, :].astype(np.float64)
        # Doubled pixel k is centred at (k + 0.5) / 2 in original pixels; the pad adds one.
        xs = (points[:, 0] + 0.5) / 2.0 - 1 + col0
        ys = (points[:, 1] + 0.5) / 2.0 - 1 + row0
        path.moveTo(QPointF(xs[0], ys[0]))
        for x, y in zip(xs[1:], ys[1:]):
            path.lineTo(QPointF(x, y))
        path.closeSubpath()
    return path
