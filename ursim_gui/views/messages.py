"""Error messages of the app: logged, and shown in a non-blocking window-modal box; and the
question a drawing window asks before its drawing is lost.

Errors are non-blocking so a failing background job never stacks nested event loops. Every
layer above the model may show errors, so this lives at the bottom of the Qt layers.
"""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox, QWidget

__all__ = ["show_error", "ask_save_discard_cancel", "ask_keep_drawing"]

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


def ask_save_discard_cancel(parent: QWidget | None, title: str, text: str, name: str) -> str:
    """A modal Save / Discard / Cancel question (Save the default): 'save', 'discard' or 'cancel'."""
    box = QMessageBox(parent)
    box.setObjectName(name)
    box.setIcon(QMessageBox.Icon.Warning)
    box.setWindowTitle(title)
    box.setText(text)
    box.setStandardButtons(
        QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel
    )
    box.setDefaultButton(QMessageBox.StandardButton.Save)
    answer = box.exec()
    return {QMessageBox.StandardButton.Save: "save", QMessageBox.StandardButton.Discard: "discard"}.get(
        QMessageBox.StandardButton(answer), "cancel"
    )


def ask_keep_drawing(parent: QWidget | None) -> str:
    """Ask what to do with a drawing neither saved nor used: 'save', 'discard' or 'cancel'."""
    return ask_save_discard_cancel(
        parent,
        "Unsaved drawing",
        "The drawing has not been saved or used as the sketch. Save it before closing?",
        "unkept_drawing_box",
    )
