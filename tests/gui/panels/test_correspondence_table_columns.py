"""The correspondence table's columns: the values whole, only the free text (Label, Note) elided, and the
terse headers explained."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QHeaderView

from ursim_gui.panels.correspondence_table import COLUMNS, FREE_TEXT_COLUMNS


def test_only_the_free_text_shares_the_width_left(window, qtbot):
    table = window.table
    window.session.link([1], [1])
    header = table.view.horizontalHeader()
    assert {COLUMNS[column] for column in FREE_TEXT_COLUMNS} == {"Label", "Note"}
    for column in range(len(COLUMNS)):
        stretched = header.sectionResizeMode(column) == QHeaderView.ResizeMode.Stretch
        assert stretched == (column in FREE_TEXT_COLUMNS), COLUMNS[column]
    table.view.resize(420, 200)  # narrower than every column wants
    qtbot.wait(10)
    status = COLUMNS.index("Status")
    assert table.view.columnWidth(status) > table.view.fontMetrics().horizontalAdvance("accepted")


def test_a_long_label_is_whole_in_its_tooltip(window):
    session, model = window.session, window.table.model
    clique = session.link([1], [1])
    label = "the long corridor between the kitchen and the meeting rooms " * 3
    session.set_label(clique, label)
    index = model.index(model.row_of(clique), COLUMNS.index("Label"))
    assert label.strip() in model.data(index, Qt.ItemDataRole.ToolTipRole)


def test_every_header_but_the_obvious_ones_says_what_it_holds(window):
    model = window.table.model
    for name in ("Sketch", "Metric", "Source", "Status", "Eval", "Label", "Note"):
        tip = model.headerData(COLUMNS.index(name), Qt.Orientation.Horizontal, Qt.ItemDataRole.ToolTipRole)
        assert tip, name


def test_filling_the_table_does_not_narrow_it(window, qtbot):
    # A scroll bar that appears with the rows would narrow the view and lay the columns out again.
    table = window.table
    table.view.setFixedHeight(70)  # room for about two rows: the third needs scrolling
    qtbot.wait(10)
    width = table.view.viewport().width()
    for region in (1, 2, 3):
        window.session.link([region], [region])
    qtbot.wait(10)
    assert table.view.viewport().width() == width
