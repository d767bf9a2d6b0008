"""Error messages of the app: logged, and shown in a non-blocking window-modal box.

Non-blocking so a failing background job never stacks nested event loops. Every layer
above the model may show errors, so this lives at the bottom of the Qt layers.
"""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox, QWidget

__all__ = ["show_error"]

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
