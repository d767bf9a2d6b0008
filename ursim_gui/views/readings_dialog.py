"""The readings dialog: the sketch turned as each reading the matcher ranked, beside the metric map.

A close call between two readings (a half-turned row of rooms, a mirror image) is quicker to settle
by eye than by turning the sketch view through them: each reading is a tile, ranked, with how much
worse the matcher found it; choosing one tells the matcher that reading and matches again. Of the
27 generated partial sketches misread on seeds 0-127, the right reading is the runner-up in 16,
third in 7 and fourth in 2 (docs/studies.md, round 54).

A thin view: it is given the images and the ranked readings and says which one was chosen
(:attr:`ReadingsDialog.reading_chosen`); the matching panel tells the matcher.
"""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QIcon, QImage, QKeySequence, QPixmap
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QToolButton,
    QVBoxLayout,
)

from ursim_core.matching.orientation import describe_gap
from ursim_gui.views.map_view import drawn_area, oriented_transform

__all__ = ["ReadingsDialog", "reading_caption", "turned_picture", "drawn_part", "TILE_SIDE"]

#: The longer side of a reading's tile, pixels.
TILE_SIDE = 220


def reading_caption(rank: int, reading, gap: float, *, read: bool, shown: bool) -> str:
    """A tile's text: its rank, the reading in words, and how it ranked.

    ``read``: the reading the matcher chose; ``shown``: the reading of the answer shown now.

    Examples
    --------
    >>> from ursim_gui.model.orientation import SketchOrientation
    >>> print(reading_caption(1, SketchOrientation(0.0), 0.0, read=True, shown=True))
    1. upright
    read by the matcher · shown now
    >>> print(reading_caption(2, SketchOrientation(180.0, True), 0.005, read=False, shown=False))
    2. turned 180° counter-clockwise, mirrored
    ranked 0.5% worse
    """
    how = "read by the matcher" if read else describe_gap(gap, hint=False)
    return f"{rank}. {reading.describe()}\n{how}" + (" · shown now" if shown else "")


class ReadingsDialog(QDialog):
    """The metric map, and a tile per reading with the sketch turned to it, best ranked first.

    Parameters
    ----------
    sketch, metric : QImage
        The two maps, not turned (the app gives each map's drawn part, :func:`drawn_part`).
    readings : list of (SketchOrientation, float)
        The readings and their gaps, the matcher's own first
        (``SketchOrientation.readings_in``).
    shown : SketchOrientation or None
        The reading of the answer shown now: its tile cannot be chosen again.

    Signals
    -------
    reading_chosen(object) : the :class:`~ursim_gui.model.orientation.SketchOrientation` chosen
    """

    reading_chosen = Signal(object)

    def __init__(self, sketch: QImage, metric: QImage, readings, shown=None, parent=None):
        super().__init__(parent)
        self.setWindowTitle("Compare the readings")
        self.setObjectName("readings_dialog")
        explanation = QLabel(
            "The matcher read the sketch in each of these ways and ranked them, best first. Choose "
            "the one that turns the sketch like the metric map: the matcher is told it and matches "
            "again (Undo gives the answer back). Keys 1-9 choose a tile."
        )
        explanation.setWordWrap(True)
        metric_label = QLabel()
        metric_label.setObjectName("readings_metric")
        metric_label.setAlignment(Qt.AlignmentFlag.AlignCenter)
        metric_label.setPixmap(QPixmap.fromImage(_fitted(metric, int(TILE_SIDE * 1.6))))
        metric_label.setToolTip("The metric map, not turned")
        metric_box = QVBoxLayout()
        metric_box.addWidget(QLabel("<b>Metric map</b>"))
        metric_box.addWidget(metric_label, 1)
        grid = QGridLayout()
        self.tiles: list[QToolButton] = []
        columns = 2 if len(readings) <= 4 else 3
        for index, (reading, gap) in enumerate(readings):
            tile = QToolButton()
            tile.setObjectName(f"reading_{index + 1}")
            tile.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextUnderIcon)
            picture = turned_picture(sketch, reading)
            icon = QIcon(picture)
            # The answer shown now keeps its picture when its tile is disabled: greyed, it would
            # not compare.
            icon.addPixmap(picture, QIcon.Mode.Disabled)
            tile.setIcon(icon)
            tile.setIconSize(QSize(TILE_SIDE, TILE_SIDE))
            is_shown = shown is not None and reading == shown
            tile.setText(reading_caption(index + 1, reading, gap, read=index == 0, shown=is_shown))
            tile.setEnabled(not is_shown)
            tile.setToolTip("The answer shown now" if is_shown else "Match in this reading")
            if index < 9:
                tile.setShortcut(QKeySequence(str(index + 1)))
            tile.clicked.connect(lambda _checked=False, reading=reading: self._choose(reading))
            grid.addWidget(tile, index // columns, index % columns)
            self.tiles.append(tile)
        body = QHBoxLayout()
        body.addLayout(metric_box)
        body.addLayout(grid)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(explanation)
        layout.addLayout(body, 1)
        layout.addWidget(buttons)

    def _choose(self, reading) -> None:
        self.reading_chosen.emit(reading)
        self.accept()


def turned_picture(image: QImage, reading, side: int = TILE_SIDE) -> QPixmap:
    """``image`` mirrored and turned as ``reading`` (a ``SketchOrientation``) says, as the sketch
    view would show it, fitted to a ``side`` x ``side`` square; the corners a free angle uncovers
    are transparent. Shrunk before it is turned: a building-sized map would take long at full
    size, for a tile."""
    if image.isNull():
        return QPixmap()
    shrunk = _fitted(image, 2 * side).convertToFormat(QImage.Format.Format_ARGB32_Premultiplied)
    turned = shrunk.transformed(
        oriented_transform(reading.angle or 0.0, reading.mirrored), Qt.TransformationMode.SmoothTransformation
    )
    return QPixmap.fromImage(_fitted(turned, side))


def drawn_part(image: QImage, box) -> QImage:
    """The part of ``image`` inside ``box`` (``(first row, end row, first col, end col)``, the free
    space's box, as ``ursim_core.matching.template.free_box`` gives it) with a margin of 2 % of its
    longer side, within the image: a sketch drawn small on a large sheet fills its tile. The whole
    image when ``box`` is None.

    Examples
    --------
    >>> image = QImage(100, 50, QImage.Format.Format_Grayscale8)
    >>> part = drawn_part(image, (10, 20, 30, 70))
    >>> part.width(), part.height()
    (42, 12)
    """
    if box is None or image.isNull():
        return image
    return image.copy(drawn_area(box, 0.02).toRect().intersected(image.rect()))


def _fitted(image: QImage, side: int) -> QImage:
    """``image`` scaled to fit a ``side`` x ``side`` square (an empty one stays empty); an image,
    not a pixmap, until then: a building-sized map is not copied whole to the screen's format."""
    if image.isNull():
        return image
    return image.scaled(side, side, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation)
