"""The window on a laptop screen: Match and the sketch's orientation without scrolling, the toolbar and the
correspondence table without overflow, the maps wider than the panels."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from conftest import segmented_window
from PySide6.QtCore import QRect
from PySide6.QtWidgets import QMenu, QToolBar, QWidget

from ursim_gui.panels.correspondence_table import FREE_TEXT_COLUMNS
from ursim_gui.window.main_window import MainWindow

LAPTOP_SIZES = [(1280, 800), (1366, 768)]


def first_start(qtbot, tmp_path, map_files, size) -> MainWindow:
    """A window started for the first time (no layout remembered) at ``size``, both maps segmented."""
    window = segmented_window(qtbot, tmp_path / f"first_start_{size[0]}", map_files, size)
    qtbot.wait(20)
    return window


@pytest.fixture(params=LAPTOP_SIZES, ids=lambda size: f"{size[0]}x{size[1]}")
def laptop_window(request, qtbot, tmp_path, map_files):
    window = first_start(qtbot, tmp_path, map_files, request.param)
    yield window
    window.jobs.runner.shutdown()


def shown_whole(area, widget: QWidget) -> bool:
    """Whether ``widget`` lies wholly inside the visible part of the scroll area ``area``."""
    viewport = area.viewport()
    placed = QRect(widget.mapTo(viewport, widget.rect().topLeft()), widget.size())
    return widget.isVisible() and viewport.rect().contains(placed)


def matched(window) -> None:
    """A match's answer in the session and the panel (its summary, the reading it offers next)."""
    window.session.apply_match(
        SimpleNamespace(pairs=[(1, 1), (2, 2), (3, 3)], anchors=[(1, 1)], m=0.1, cost=1.0, reason="")
    )


def test_match_and_the_orientation_row_show_without_scrolling(laptop_window, qtbot):
    """The Matching dock showed 170 of its 499 pixels, the Match button and the orientation row at the
    bottom: they were never visible without scrolling, even at 1920x1080."""
    window = laptop_window
    matched(window)
    qtbot.wait(20)
    panel, area = window.matching_panel, window.docks["matching"].widget()
    assert area.verticalScrollBar().value() == 0
    for widget in (panel.match_button, panel.turn_left, panel.turn_right, panel.mirror, panel.unknown):
        assert shown_whole(area, widget), widget.objectName()


def test_the_maps_get_more_width_than_the_panel_column(laptop_window):
    """The longest choice of the matching settings made the right column 576 px wide at 1280x800."""
    window = laptop_window
    column = window.docks["matching"].width()
    assert column <= 0.35 * window.width()
    assert all(view.width() > 0.8 * column for view in window.views.values())


def test_every_toolbar_button_fits_and_is_in_a_menu(laptop_window):
    """'Route tool' hid in the toolbar's overflow at 1280x800."""
    window = laptop_window
    toolbar = window.findChild(QToolBar, "main_toolbar")
    actions = [action for action in toolbar.actions() if not action.isSeparator()]
    hidden = [action.iconText() for action in actions if not toolbar.widgetForAction(action).isVisible()]
    assert hidden == []
    in_menus = {action for menu in window.menuBar().findChildren(QMenu) for action in menu.actions()}
    assert all(action in in_menus for action in actions)
    assert all(action.toolTip() and action.toolTip() != action.iconText() for action in actions)


def test_the_correspondence_table_fits_without_a_horizontal_scroll_bar(laptop_window, qtbot):
    """At 1280x800 the Status column showed 'pendi' and Eval, Label and Note needed scrolling."""
    window = laptop_window
    matched(window)
    window.session.link([1], [2])  # a manual clique: another source, and a row reset
    qtbot.wait(20)
    view = window.table.view
    assert view.horizontalScrollBar().maximum() == 0
    header = view.horizontalHeader()
    for column in range(view.model().columnCount()):
        if column in FREE_TEXT_COLUMNS:
            continue
        needed = max(view.sizeHintForColumn(column), header.sectionSizeHint(column))
        assert view.columnWidth(column) >= needed, view.model().headerData(column, header.orientation())
    status = view.model().headerData(5, header.orientation())
    assert status == "Status"
    widest = max(view.fontMetrics().horizontalAdvance(text) for text in ("pending", "accepted", "rejected"))
    assert view.columnWidth(5) > widest
