"""The shortcut sheet (F1) lists every shortcut of the app."""

from __future__ import annotations

from conftest import key
from PySide6.QtCore import Qt
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import QApplication

from ursim_gui.window.shortcuts import SHORTCUTS, ShortcutSheet


def test_f1_opens_the_shortcut_sheet(window, qtbot):
    key(qtbot, window, Qt.Key.Key_F1)
    sheets = [w for w in QApplication.topLevelWidgets() if isinstance(w, ShortcutSheet) and w.isVisible()]
    if not sheets:
        sheets = [w for w in window.findChildren(ShortcutSheet) if w.isVisible()]
    assert sheets
    keys = sheets[0].key_texts()
    native = QKeySequence.SequenceFormat.NativeText
    for spec in SHORTCUTS:
        for sequence in spec.keys:
            assert any(QKeySequence(sequence).toString(native) in text for text in keys), spec.id
    assert "Ctrl+Click" in keys
    sheets[0].close()
