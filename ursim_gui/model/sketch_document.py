"""Qt-free drawing document behind the sketch canvas: a grey image, tools and undo.

Walls are black (0) on white (255) paper, the convention ``ursim_core.io.maps`` reads as
obstacle / free. Each finished stroke or shape is one undo step; the image before it is
kept as a snapshot (a sketch is small, and snapshots make undo exact).
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from ursim_core.io.atomic import atomic_write_bytes
from ursim_gui.model.signals import Signal

__all__ = ["SketchDocument", "TOOLS", "INK", "PAPER"]

INK, PAPER = 0, 255
#: Tool names: freehand pen, freehand eraser, straight wall, rectangle (outline).
TOOLS = ("pen", "eraser", "wall", "rectangle")
_MAX_UNDO = 200


class SketchDocument:
    """A sketch being drawn.

    Parameters
    ----------
    rows, cols : int
        Canvas size in pixels.

    Attributes
    ----------
    changed : Signal
        Emitted with no argument after every change of the image.
    history_changed : Signal
        Emitted when undo/redo availability changes.
    """

    def __init__(self, rows: int, cols: int):
        if rows < 8 or cols < 8:
            raise ValueError(f"a sketch needs at least 8x8 pixels, got {rows}x{cols}")
        self.image = np.full((int(rows), int(cols)), PAPER, np.uint8)
        self.tool = "pen"
        self.width = 3
        self.changed = Signal("changed")
        self.history_changed = Signal("history_changed")
        self._undo: list[np.ndarray] = []
        self._redo: list[np.ndarray] = []
        self._stroke_start: np.ndarray | None = None
        self._last_point: tuple[int, int] | None = None
        self._anchor: tuple[int, int] | None = None
        # The drawing as last saved to ``saved_path`` and as last used as the session's sketch:
        # what a closing window would lose is a drawing that is neither.
        self.saved_path: Path | None = None
        self._saved_image: np.ndarray | None = None
        self._used_image: np.ndarray | None = None

    # ---- strokes: begin, extend, end form one undo step --------------------------------
    def begin(self, row: int, col: int) -> None:
        """Start a stroke or shape at pixel (row, col) with the current tool."""
        self._stroke_start = self.image.copy()
        self._anchor = self._last_point = (int(row), int(col))
        if self.tool in ("pen", "eraser"):
            self._line(self.image, self._anchor, self._anchor, self._colour())
            self.changed.emit()

    def extend(self, row: int, col: int) -> None:
        """Continue the stroke to (row, col); shapes are redrawn from the stroke start."""
        if self._stroke_start is None:
            return
        point = (int(row), int(col))
        if self.tool in ("pen", "eraser"):
            self._line(self.image, self._last_point, point, self._colour())
        else:
            self.image[...] = self._stroke_start
            self._shape(self.image, self._anchor, point)
        self._last_point = point
        self.changed.emit()

    def end(self, row: int, col: int) -> None:
        """Finish the stroke at (row, col) and record one undo step if it changed anything."""
        if self._stroke_start is None:
            return
        self.extend(row, col)
        before, self._stroke_start = self._stroke_start, None
        if not np.array_equal(before, self.image):
            self._undo.append(before)
            del self._undo[:-_MAX_UNDO]
            self._redo.clear()
            self.history_changed.emit()

    # ---- whole-document operations ---------------------------------------------------------------
    def clear(self) -> None:
        """Blank the paper (undoable)."""
        if (self.image == PAPER).all():
            return
        self._undo.append(self.image.copy())
        self._redo.clear()
        self.image[...] = PAPER
        self.changed.emit()
        self.history_changed.emit()

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)

    def undo(self) -> None:
        if self._undo:
            self._redo.append(self.image.copy())
            self.image[...] = self._undo.pop()
            self.changed.emit()
            self.history_changed.emit()

    def redo(self) -> None:
        if self._redo:
            self._undo.append(self.image.copy())
            self.image[...] = self._redo.pop()
            self.changed.emit()
            self.history_changed.emit()

    def map_image(self) -> np.ndarray:
        """The sketch as a map: paper outside the outermost walls becomes outside (black).

        People draw a building's outline on white paper; the paper around it is not free space
        (the KTH sketches are filled black there). Paper connected to the canvas border is
        therefore outside, unless nothing would be left (no closed outline yet).

        Examples
        --------
        >>> doc = SketchDocument(20, 30)
        >>> doc.image[2, 2:28] = doc.image[17, 2:28] = INK
        >>> doc.image[2:18, 2] = doc.image[2:18, 27] = INK
        >>> map_ = doc.map_image()
        >>> int(map_[0, 0]), int(map_[10, 15])
        (0, 255)
        """
        paper = (self.image > INK).astype(np.uint8)
        count, labels = cv2.connectedComponents(paper, connectivity=4)
        border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
        outside = np.isin(labels, border[border > 0])
        if not (paper.astype(bool) & ~outside).any():
            return self.image.copy()
        return np.where(outside, INK, self.image).astype(np.uint8)

    def save_png(self, path: str | Path) -> None:
        """Write the sketch as an 8-bit grey PNG of :meth:`map_image`, atomically.

        Raises OSError on failure. Saving the map image means a saved sketch loads back as
        exactly the map that "Use as sketch" gives.
        """
        ok, encoded = cv2.imencode(".png", self.map_image())
        if not ok:
            raise OSError(f"{path}: could not encode the sketch as PNG")
        atomic_write_bytes(Path(path), encoded.tobytes())
        self.saved_path = Path(path).absolute()
        self._saved_image = self.image.copy()

    @property
    def file_of_drawing(self) -> Path | None:
        """The PNG last saved, while the drawing is still what was saved there; else None."""
        return (
            self.saved_path if self._saved_image is not None and np.array_equal(self.image, self._saved_image) else None
        )

    def mark_used(self) -> None:
        """The drawing as it is now was handed to the session as its sketch."""
        self._used_image = self.image.copy()

    @property
    def unkept(self) -> bool:
        """True when closing would lose drawing: not blank, and neither saved nor used as it is.

        >>> document = SketchDocument(10, 10)
        >>> document.unkept
        False
        >>> document.begin(2, 2); document.end(2, 8)
        >>> document.unkept
        True
        >>> document.mark_used()
        >>> document.unkept
        False
        """
        if not (self.image != PAPER).any():
            return False
        return not any(
            kept is not None and np.array_equal(self.image, kept) for kept in (self._saved_image, self._used_image)
        )

    # ---- drawing -------------------------------------------------------------------------------
    def _colour(self) -> int:
        return PAPER if self.tool == "eraser" else INK

    def _line(self, image: np.ndarray, start, end, colour: int) -> None:
        # cv2 points are (x, y) = (col, row).
        cv2.line(image, (start[1], start[0]), (end[1], end[0]), colour, max(1, int(self.width)), cv2.LINE_8)

    def _shape(self, image: np.ndarray, start, end) -> None:
        if self.tool == "wall":
            self._line(image, start, end, INK)
        else:
            cv2.rectangle(image, (start[1], start[0]), (end[1], end[0]), INK, max(1, int(self.width)), cv2.LINE_8)
