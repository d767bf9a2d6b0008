"""Export a PNG figure: both maps as shown (overlays, marks) side by side, with a legend.

The maps are rendered from the views' scenes, so the figure shows exactly the layers the
user has switched on, plus the region ids (the legend names regions by id); the legend lists each clique's colour, regions, status and, with a
reference loaded, its TP / FP mark and the scores.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QBuffer, QByteArray, QIODevice, QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QFont, QFontMetricsF, QImage, QPainter, QPen

from ursim_core.io.atomic import atomic_write_bytes
from ursim_gui.model.wording import counted

__all__ = ["render_figure", "export_figure"]

_MARGIN, _GAP, _TITLE_H, _ROW_H, _SWATCH = 24, 36, 30, 20, 13


def _map_rect(view, origin: QPointF, height: float) -> QRectF:
    scene_rect = view.sceneRect()
    if scene_rect.isEmpty():
        return QRectF(origin, origin + QPointF(height, height))
    width = height * scene_rect.width() / scene_rect.height()
    return QRectF(origin.x(), origin.y(), width, height)


def _legend_lines(session) -> list[tuple[QColor | None, str]]:
    corr = session.correspondences
    lines: list[tuple[QColor | None, str]] = []
    for clique in corr.cliques:
        regions = f"sketch {', '.join(map(str, clique.sketch_regions)) or '–'}  ↔  metric {', '.join(map(str, clique.metric_regions)) or '–'}"
        status = session.clique_status(clique.id)
        mark = f"  [{status.upper()}]" if status else ""
        lines.append(
            (
                QColor(*session.color_of_clique(clique.id)),
                f"{clique.id}: {regions}  ({clique.source}, {clique.effective_status}){mark}",
            )
        )
    if not lines:
        lines.append((None, "no correspondences"))
    return lines


def _summary(session) -> str:
    parts = [counted(len(session.correspondences.cliques), "clique")]
    if session.anchors:
        parts.append(f"{counted(len(session.anchors), 'anchor')} (dashed)")
    score = session.evaluation
    if score is not None:
        parts.append(f"precision {score.precision:.3f}  recall {score.recall:.3f}  F1 {score.f1:.3f}")
    return "   ·   ".join(parts)


def render_figure(sketch_view, metric_view, session, *, map_height: int = 600, connectors: bool = False) -> QImage:
    """Render the figure to a QImage.

    Parameters
    ----------
    sketch_view, metric_view : MapView
        The two views (their scenes are drawn, whatever their zoom).
    session : AnnotationSession
        Source of the cliques, anchors and evaluation for the legend.
    map_height : int
        Height of each map in the figure, pixels.
    connectors : bool
        Draw a line between the interior points of each clique's first regions.
    """
    font = QFont()
    font.setPointSize(10)
    metrics = QFontMetricsF(font)
    top = QPointF(_MARGIN, _MARGIN + _TITLE_H)
    left = _map_rect(sketch_view, top, map_height)
    right = _map_rect(metric_view, QPointF(left.right() + _GAP, top.y()), map_height)
    lines = _legend_lines(session)
    columns = max(1, min(3, len(lines) // 12 + 1))
    per_column = -(-len(lines) // columns)
    column_width = max(metrics.horizontalAdvance(text) for _, text in lines) + _SWATCH + 14
    width = int(max(right.right() + _MARGIN, _MARGIN * 2 + columns * column_width))
    legend_top = right.bottom() + _MARGIN + _ROW_H
    height = int(legend_top + per_column * _ROW_H + _MARGIN)
    image = QImage(width, height, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(QColor("white"))
    painter = QPainter(image)
    painter.setFont(font)
    painter.setRenderHint(QPainter.RenderHint.Antialiasing, True)
    for view, rect, side in ((sketch_view, left, "sketch"), (metric_view, right, "metric")):
        title = session.map(side).name if session.map(side) is not None else "(none)"
        painter.setPen(QColor(30, 30, 30))
        painter.drawText(
            QRectF(rect.x(), _MARGIN, rect.width(), _TITLE_H),
            Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
            f"{side.capitalize()}: {title}",
        )
        if not view.sceneRect().isEmpty():
            scale = rect.height() / view.sceneRect().height()
            with view.layers.hidden("selection", "highlight"), view.layers.ids_shown(scale):
                view.scene().render(painter, rect, view.sceneRect(), Qt.AspectRatioMode.KeepAspectRatio)
        painter.setPen(QPen(QColor(120, 120, 120), 1))
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.drawRect(rect)
    if connectors:
        _draw_connectors(painter, session, (sketch_view, left), (metric_view, right))
    painter.setPen(QColor(30, 30, 30))
    painter.drawText(QPointF(_MARGIN, right.bottom() + _MARGIN + 4), _summary(session))
    for index, (colour, text) in enumerate(lines):
        column, row = divmod(index, per_column)
        x, y = _MARGIN + column * column_width, legend_top + row * _ROW_H
        if colour is not None:
            painter.setPen(QPen(QColor(60, 60, 60), 0.8))
            painter.setBrush(colour)
            painter.drawRect(QRectF(x, y - _SWATCH + 2, _SWATCH, _SWATCH))
        painter.setPen(QColor(30, 30, 30))
        painter.drawText(QPointF(x + _SWATCH + 6, y), text)
    painter.end()
    return image


def _draw_connectors(painter: QPainter, session, sketch, metric) -> None:
    for clique in session.correspondences.cliques:
        if not clique.sketch_regions or not clique.metric_regions:
            continue
        ends = []
        for (view, rect), region in ((sketch, clique.sketch_regions[0]), (metric, clique.metric_regions[0])):
            point = view.region_scene_point(region)
            scene = view.sceneRect()
            if point is None or scene.isEmpty():
                break
            scale = rect.height() / scene.height()
            ends.append(QPointF(rect.x() + point.x() * scale, rect.y() + point.y() * scale))
        if len(ends) == 2:
            pen = QPen(QColor(*session.color_of_clique(clique.id)), 1.6)
            painter.setPen(pen)
            painter.drawLine(ends[0], ends[1])


def export_figure(path: str | Path, sketch_view, metric_view, session, **options) -> None:
    """Render and write the figure as PNG, atomically (raises OSError on failure)."""
    image = render_figure(sketch_view, metric_view, session, **options)
    data = QByteArray()
    buffer = QBuffer(data)
    buffer.open(QIODevice.OpenModeFlag.WriteOnly)
    if not image.save(buffer, "PNG"):
        raise OSError(f"{path}: could not encode the figure as PNG")
    atomic_write_bytes(Path(path), bytes(data.data()))
