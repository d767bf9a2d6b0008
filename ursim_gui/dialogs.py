"""Message dialogs of the app: errors (logged too), the unsaved-changes question, recovery.

Errors use non-blocking window-modal boxes so a failing background job never stacks
nested event loops; questions that need an answer before going on are modal.
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox, QWidget

__all__ = ["show_error", "ask_unsaved_changes", "ask_recover"]

_log = logging.getLogger("ursim_gui")
#: Parentless error boxes are kept here while shown; Python would otherwise delete them.
_open_boxes: set[QMessageBox] = set()


def show_error(parent: QWidget | None, title: str, message: str) -> QMessageBox:
    """Log ``message`` and show it in a window-modal box (returns at once)."""
    _log.error("%s: %s", title, message)
    box = QMessageBox(QMessageBox.Icon.Critical, title, message, QMessageBox.StandardButton.Ok, parent)
    box.setObjectName("error_box")
    box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose, True)
    if parent is None:
        _open_boxes.add(box)
        box.finished.connect(lambda _result: _open_boxes.discard(box))
    box.open()
    return box


def ask_unsaved_changes(parent: QWidget | None, what: str) -> str:
    """Ask what to do with unsaved changes before ``what``: 'save', 'discard' or 'cancel'."""
    box = QMessageBox(parent)
    box.setObjectName("unsaved_box")
    box.setIcon(QMessageBox.Icon.Warning)
    box.setWindowTitle("Unsaved changes")
    box.setText(f"The correspondences have unsaved changes. Save them before {what}?")
    box.setStandardButtons(
        QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel
    )
    box.setDefaultButton(QMessageBox.StandardButton.Save)
    answer = box.exec()
    return {QMessageBox.StandardButton.Save: "save", QMessageBox.StandardButton.Discard: "discard"}.get(
        QMessageBox.StandardButton(answer), "cancel"
    )


def ask_recover(parent: QWidget | None, paths: list[Path]) -> Path | None:
    """Offer to recover the newest autosave file; returns the path to recover or None."""
    newest = max(paths, key=lambda p: p.stat().st_mtime)
    box = QMessageBox(parent)
    box.setObjectName("recover_box")
    box.setIcon(QMessageBox.Icon.Question)
    box.setWindowTitle("Recover unsaved work")
    box.setText(f"Unsaved correspondences from an earlier session were found:\n{newest.name}\n\nRecover them?")
    recover = box.addButton("Recover", QMessageBox.ButtonRole.AcceptRole)
    box.addButton("Not now", QMessageBox.ButtonRole.RejectRole)
    box.exec()
    return newest if box.clickedButton() is recover else None
