"""Tab bars of tabified docks that Qt leaves on screen where they no longer belong.

Qt 6 (seen with PySide6 6.11) makes a tab bar for each group of tabified docks. When a group is
tabified while the window is still hidden (:meth:`QMainWindow.tabifyDockWidget` in the window's
constructor, or :meth:`QMainWindow.restoreState` of the last session's layout) after a group in
another dock area, it makes two and keeps using one; the other is never hidden, so the first
``show()`` shows it at the place it was first laid out. In this window that is the middle of the
map views: a fragment of "Segmentation | Campaign" between the sketch and the metric map, on every
start. Qt places the tab bar it uses against the dock it switches, so a visible tab bar that
shares an edge with no docked widget is one of those leftovers.
"""

from __future__ import annotations

from PySide6.QtCore import QRect, Qt
from PySide6.QtWidgets import QDockWidget, QMainWindow, QTabBar

__all__ = ["stray_tab_bars", "hide_stray_tab_bars"]


def stray_tab_bars(window: QMainWindow) -> list[QTabBar]:
    """The window's visible dock tab bars that share an edge with none of its docked widgets."""
    window.layout().activate()  # the docks' geometry as it will be shown
    docks = [dock.geometry() for dock in window.findChildren(QDockWidget) if dock.isVisible() and not dock.isFloating()]
    bars = window.findChildren(QTabBar, options=Qt.FindChildOption.FindDirectChildrenOnly)
    return [bar for bar in bars if bar.isVisible() and not any(_abuts(bar.geometry(), dock) for dock in docks)]


def _abuts(bar: QRect, dock: QRect) -> bool:
    """The bar shares an edge with the dock, as Qt lays out the bar it uses; a leftover lies
    elsewhere, often across a dock (in a narrower window it fell under the Segmentation dock)."""
    return not bar.intersects(dock) and bar.adjusted(-1, -1, 1, 1).intersects(dock)


def hide_stray_tab_bars(window: QMainWindow) -> int:
    """Hide the leftovers of :func:`stray_tab_bars`; the number hidden.

    Only bars Qt no longer lays out are hidden; a group tabified later gets a bar of its own.
    """
    stray = stray_tab_bars(window)
    for bar in stray:
        bar.hide()
    return len(stray)
