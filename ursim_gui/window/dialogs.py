"""Questions of the main window: unsaved changes, crash recovery (modal: the answer is needed to go on).

``show_error`` (from :mod:`ursim_gui.views.messages`) is re-exported for the window's modules.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QMessageBox, QWidget

from ursim_gui.views.messages import ask_save_discard_cancel, show_error

__all__ = ["show_error", "ask_unsaved_changes", "ask_recover", "ask_overwrite_changed"]


def ask_unsaved_changes(parent: QWidget | None, what: str) -> str:
    """Ask what to do with unsaved changes before ``what``: 'save', 'discard' or 'cancel'."""
    return ask_save_discard_cancel(
        parent, "Unsaved changes", f"The correspondences have unsaved changes. Save them before {what}?", "unsaved_box"
    )


def ask_overwrite_changed(parent: QWidget | None, path: Path) -> bool:
    """The file changed on disk since it was opened (another session?): True to overwrite it."""
    box = QMessageBox(parent)
    box.setObjectName("changed_on_disk_box")
    box.setIcon(QMessageBox.Icon.Warning)
    box.setWindowTitle("File changed on disk")
    box.setText(
        f"{path} was changed by someone else since it was opened or last saved here "
        "(another window or another program). Overwrite it with this document, losing those changes?"
    )
    box.setStandardButtons(QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Cancel)
    box.button(QMessageBox.StandardButton.Save).setText("Overwrite")
    box.setDefaultButton(QMessageBox.StandardButton.Cancel)
    return QMessageBox.StandardButton(box.exec()) == QMessageBox.StandardButton.Save


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
