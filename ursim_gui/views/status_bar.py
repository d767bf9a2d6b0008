"""Status bar: cursor pixel and world position, region under the cursor, zoom, job progress."""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QProgressBar, QPushButton, QStatusBar

__all__ = ["format_cursor", "format_zoom", "CursorStatusBar"]


def format_cursor(side: str, row: int, col: int, world: tuple[float, float] | None, region: int) -> str:
    """Text for the cursor field, e.g. ``'metric  px (12, 40)  world (1.20, -3.05) m  region 7'``.

    Examples
    --------
    >>> format_cursor("sketch", 3, 4, None, 0)
    'sketch  px (3, 4)'
    """
    parts = [side, f"px ({row}, {col})"]
    if world is not None:
        parts.append(f"world ({world[0]:.2f}, {world[1]:.2f}) m")
    if region > 0:
        parts.append(f"region {region}")
    return "  ".join(parts)


def format_zoom(factor: float) -> str:
    """Zoom factor as a percentage, e.g. ``'zoom 250 %'``."""
    return f"zoom {factor * 100:.0f} %"


class CursorStatusBar(QStatusBar):
    """Permanent fields on the right, transient messages on the left.

    The job fields (progress bar and Cancel button) are hidden when no job runs.
    """

    def __init__(self, parent=None):
        super().__init__(parent)
        self.cursor_label = QLabel("")
        self.cursor_label.setObjectName("status_cursor")
        self.cursor_label.setMinimumWidth(360)
        self.zoom_label = QLabel("")
        self.zoom_label.setObjectName("status_zoom")
        self.zoom_label.setMinimumWidth(90)
        self.progress_bar = QProgressBar()
        self.progress_bar.setRange(0, 1000)
        self.progress_bar.setMaximumWidth(180)
        self.progress_bar.setTextVisible(False)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setObjectName("status_cancel")
        for widget in (self.progress_bar, self.cancel_button):
            widget.setVisible(False)
            self.addPermanentWidget(widget)
        self.addPermanentWidget(self.cursor_label)
        self.addPermanentWidget(self.zoom_label)

    def show_cursor(self, side: str, row: int, col: int, world: tuple[float, float] | None, region: int) -> None:
        """Show the cursor position; a negative row means the cursor left the map."""
        self.cursor_label.setText("" if row < 0 else format_cursor(side, row, col, world, region))

    def show_zoom(self, factor: float) -> None:
        self.zoom_label.setText(format_zoom(factor))

    def show_job(self, running: bool) -> None:
        """Show or hide the progress bar and Cancel button.

        The bar starts indeterminate (a busy animation): segmentation reports no progress of
        its own, so a bar frozen at a percentage would mislead; matching with the automatic
        m turns it into a percentage (:meth:`show_progress`).
        """
        self.progress_bar.setRange(0, 0)
        self.progress_bar.setVisible(running)
        self.cancel_button.setVisible(running)
        self.cancel_button.setEnabled(running)

    def show_progress(self, fraction: float, message: str) -> None:
        """A job step: the message is shown; a fraction past the first step makes the bar
        determinate (the automatic m reports one step per value of m)."""
        if fraction > 0.05:
            self.progress_bar.setRange(0, 1000)
            self.progress_bar.setValue(round(1000 * min(fraction, 1.0)))
        if message:
            self.showMessage(message)
