"""Light and dark themes: Qt's Fusion style with a palette; the map views follow the palette."""

from __future__ import annotations

from PySide6.QtGui import QColor, QPalette
from PySide6.QtWidgets import QApplication

__all__ = ["apply_theme", "dark_palette", "THEMES"]

THEMES = ("system", "dark")


def dark_palette() -> QPalette:
    """A dark palette with enough contrast for the tables and the map marks."""
    palette = QPalette()
    colours = {
        QPalette.ColorRole.Window: QColor(45, 47, 51),
        QPalette.ColorRole.WindowText: QColor(225, 226, 230),
        QPalette.ColorRole.Base: QColor(30, 31, 34),
        QPalette.ColorRole.AlternateBase: QColor(40, 42, 46),
        QPalette.ColorRole.ToolTipBase: QColor(60, 62, 66),
        QPalette.ColorRole.ToolTipText: QColor(235, 235, 235),
        QPalette.ColorRole.Text: QColor(225, 226, 230),
        QPalette.ColorRole.Button: QColor(55, 57, 62),
        QPalette.ColorRole.ButtonText: QColor(225, 226, 230),
        QPalette.ColorRole.BrightText: QColor(255, 90, 90),
        QPalette.ColorRole.Highlight: QColor(52, 120, 200),
        QPalette.ColorRole.HighlightedText: QColor(255, 255, 255),
        QPalette.ColorRole.PlaceholderText: QColor(140, 142, 150),
        QPalette.ColorRole.Link: QColor(110, 170, 240),
    }
    for role, colour in colours.items():
        palette.setColor(role, colour)
    for role in (QPalette.ColorRole.Text, QPalette.ColorRole.ButtonText, QPalette.ColorRole.WindowText):
        palette.setColor(QPalette.ColorGroup.Disabled, role, QColor(120, 122, 128))
    return palette


def apply_theme(name: str) -> None:
    """'dark': Fusion with :func:`dark_palette`; 'system': the style's own palette."""
    app = QApplication.instance()
    if app is None:
        return
    if name == "dark":
        app.setStyle("Fusion")
        app.setPalette(dark_palette())
    else:
        app.setPalette(app.style().standardPalette())
