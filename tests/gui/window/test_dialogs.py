"""The window's modal questions (ursim_gui.window.dialogs), answered for real: unsaved changes, crash recovery."""

from __future__ import annotations

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication, QMessageBox

from ursim_gui.window import dialogs


def test_the_real_close_question_has_three_answers(qtbot):
    def answer():
        box = QApplication.activeModalWidget()
        assert {b.text().replace("&", "") for b in box.buttons()} >= {"Save", "Discard", "Cancel"}
        box.button(QMessageBox.StandardButton.Cancel).click()

    QTimer.singleShot(0, answer)
    from importlib import reload

    real = reload(dialogs)  # the autouse fixture patched the module attribute
    assert real.ask_unsaved_changes(None, "closing") == "cancel"


def test_real_recovery_dialog_offers_recover(qtbot, tmp_path):
    copy = tmp_path / "x.autosave.json"
    copy.write_text("{}")

    def answer():
        box = QApplication.activeModalWidget()
        assert "x.autosave.json" in box.text()
        next(b for b in box.buttons() if b.text() == "Recover").click()

    QTimer.singleShot(0, answer)
    from importlib import reload

    assert reload(dialogs).ask_recover(None, [copy]) == copy
