"""The F1 sheet reads whole (no "…"), its keys column no wider than the keys; the map openers have keys."""

from __future__ import annotations

from collections import Counter

import pytest
from conftest import answer_file_dialogs
from PySide6.QtCore import QRect, Qt
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import QStyle

from ursim_gui.window.shortcuts import ACTION_COLUMN, SHORTCUTS, ShortcutSheet

#: The sheet as it opens, and made narrow by hand.
SHEET_SIZES = [None, (600, 500)]


@pytest.mark.parametrize("size", SHEET_SIZES, ids=lambda size: "as opened" if size is None else f"{size[0]}x{size[1]}")
def test_no_cell_of_the_sheet_is_elided(qtbot, size):
    """The Action column was elided ("…") while the Keys column was far wider than its keys."""
    sheet = ShortcutSheet()
    qtbot.addWidget(sheet)
    if size is not None:
        sheet.resize(*size)
    sheet.show()
    qtbot.waitExposed(sheet)
    table = sheet.table
    metrics = table.fontMetrics()
    # The item's text rectangle is its cell less a margin a side (QCommonStyle's item view text).
    margin = table.style().pixelMetric(QStyle.PixelMetric.PM_FocusFrameHMargin, None, table) + 1
    for row in range(table.rowCount()):
        for column in range(table.columnCount()):
            text = table.item(row, column).text()
            cell = table.visualRect(table.model().index(row, column))
            room = QRect(0, 0, cell.width() - 2 * margin, 10_000)
            needed = metrics.boundingRect(room, Qt.TextFlag.TextWordWrap, text)
            assert needed.width() <= room.width() and needed.height() <= cell.height(), (row, column, text)
    keys = 1
    assert table.columnWidth(keys) <= table.sizeHintForColumn(keys) + 2  # as wide as the keys, no more
    assert table.columnWidth(ACTION_COLUMN) > table.columnWidth(keys)


def test_the_sheet_fits_its_screen(qtbot):
    sheet = ShortcutSheet()
    qtbot.addWidget(sheet)
    available = sheet.screen().availableGeometry()
    assert sheet.width() <= available.width() and sheet.height() <= available.height()


def test_the_map_openers_have_keys_of_their_own_and_the_sheet_lists_them(qtbot):
    by_id = {spec.id: spec for spec in SHORTCUTS}
    assert by_id["open_sketch"].keys and by_id["open_metric"].keys
    every_key = Counter(QKeySequence(key).toString() for spec in SHORTCUTS for key in spec.keys)
    assert [key for key, uses in every_key.items() if uses > 1] == []  # no two commands share a key
    sheet = ShortcutSheet()
    qtbot.addWidget(sheet)
    native = QKeySequence.SequenceFormat.NativeText
    for action_id in ("open_sketch", "open_metric"):
        shown = QKeySequence(by_id[action_id].keys[0]).toString(native)
        assert any(shown == text for text in sheet.key_texts()), action_id


def test_the_sketch_key_opens_a_sketch(empty_window, qtbot, monkeypatch, map_files):
    window = empty_window
    qtbot.waitExposed(window)
    answer_file_dialogs(monkeypatch, map_files["sketch"])
    sequence = QKeySequence(next(spec.keys[0] for spec in SHORTCUTS if spec.id == "open_sketch"))
    combination = sequence[0]
    qtbot.keyClick(window.views["sketch"], combination.key(), combination.keyboardModifiers())
    assert window.session.map("sketch") is not None
    assert window.session.map("sketch").path.name == map_files["sketch"].name
