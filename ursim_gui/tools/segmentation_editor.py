"""Segmentation editing on either map: merge the selected regions, split one by a line, paint or erase a wall.

A tool over the two map views and the session: merge works on the selection (Ctrl+click
two regions of one map, then Merge); split, paint wall and erase wall are modes in which
a left drag on a map draws the line or stroke (the middle button still pans, Esc leaves
the mode). Every edit is one session call, so one undo step.
"""

from __future__ import annotations

from collections import Counter

from PySide6.QtCore import QObject, Signal

__all__ = ["SegmentationEditor", "MODES"]

#: Stroke modes: what a left drag on a map does.
MODES = ("split", "paint_wall", "erase_wall")


class SegmentationEditor(QObject):
    """Turns strokes on ``views`` into segmentation edits of ``session``.

    Signals
    -------
    mode_changed(str) : the stroke mode ('' when none)
    message(str) : what an edit did or why it did nothing, for the status bar
    """

    mode_changed = Signal(str)
    message = Signal(str)

    def __init__(self, session, views: dict, parent=None):
        super().__init__(parent)
        self.session = session
        self.views = views
        self.mode = ""
        self.wall_width = 3
        for side, view in views.items():
            view.stroke_drawn.connect(lambda points, side=side: self.stroke(side, points))

    def set_mode(self, mode: str) -> None:
        """Enter a stroke mode of :data:`MODES`, or leave it with ''."""
        if mode and mode not in MODES:
            raise ValueError(f"mode must be one of {MODES} or '', got {mode!r}")
        self.mode = mode
        for view in self.views.values():
            view.set_stroke_mode(bool(mode))
        self.mode_changed.emit(mode)

    def merge_selected(self) -> bool:
        """Merge the regions selected on one map into the lowest id (one undo step)."""
        for side in ("sketch", "metric"):
            regions = sorted(self.session.selection.get(side, ()))
            if len(regions) >= 2:
                keep = regions[0]
                self.session.merge_regions(side, keep, regions[1:])
                self.message.emit(f"Merged {side} regions {', '.join(map(str, regions))} into {keep}")
                return True
        self.message.emit("Select two regions of one map (Ctrl+click) to merge them")
        return False

    def stroke(self, side: str, points: list) -> bool:
        """A stroke drawn on ``side`` in the current mode."""
        if not self.mode or len(points) < 2 or self.session.segmentation(side) is None:
            return False
        if self.mode == "split":
            labels = self.session.segmentation(side).labels
            rows, cols = labels.shape
            crossed = Counter(
                int(labels[r, c]) for r, c in points if 0 <= r < rows and 0 <= c < cols and labels[r, c] != 0
            )
            if not crossed:
                self.message.emit("Draw the split line across a region")
                return False
            region = crossed.most_common(1)[0][0]
            changed = self.session.split_region(side, region, points[0], points[-1])
        elif self.mode == "paint_wall":
            changed = self.session.paint_wall(side, points, width=self.wall_width)
        else:
            changed = self.session.erase_wall(side, points, width=self.wall_width)
        self.message.emit(f"{self.mode.replace('_', ' ').capitalize()}: {'done' if changed else 'nothing changed'}")
        return changed
