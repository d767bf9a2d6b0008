"""Open and save dialogs that cannot freeze the app on special files (``/proc``, ``/dev``, pipes).

Qt's own file dialog asks its icon provider for every entry it lists, and the default
provider guesses the type from the file's *content*: listing ``/proc`` then blocks the
GUI thread forever reading ``/proc/kmsg`` (seen typing ``/proc/`` into the save dialog;
only kill -9 ended it). These dialogs use an icon provider that looks at the file type
only, and list only folders and regular files (a pipe or a device is never a map or a
correspondence file). Always the Qt dialog, so the behaviour is the same everywhere.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSortFilterProxyModel
from PySide6.QtGui import QAbstractFileIconProvider
from PySide6.QtWidgets import QFileDialog, QWidget

__all__ = ["ask_open_path", "ask_save_path", "ask_folder", "make_file_dialog", "TypeOnlyIconProvider"]


class TypeOnlyIconProvider(QAbstractFileIconProvider):
    """Folder or file icon from the file's type, never from reading it."""

    def icon(self, what):
        if isinstance(what, QAbstractFileIconProvider.IconType):
            return super().icon(what)
        kind = QAbstractFileIconProvider.IconType.Folder if what.isDir() else QAbstractFileIconProvider.IconType.File
        return super().icon(kind)

    def type(self, info) -> str:
        return "Folder" if info.isDir() else "File"


class _FoldersAndRegularFiles(QSortFilterProxyModel):
    def filterAcceptsRow(self, row: int, parent) -> bool:
        model = self.sourceModel()
        info = model.fileInfo(model.index(row, 0, parent))
        return info.isDir() or info.isFile()


#: One provider for every dialog; the dialogs do not take ownership of it.
_ICONS: TypeOnlyIconProvider | None = None


def make_file_dialog(parent: QWidget | None, title: str, filters: str, *, save: bool, name: str = "") -> QFileDialog:
    """The guarded dialog (not shown): Qt's widget dialog, type-only icons, special files hidden."""
    global _ICONS
    if _ICONS is None:
        _ICONS = TypeOnlyIconProvider()
    dialog = QFileDialog(parent, title, "", filters)
    dialog.setObjectName("file_dialog")
    dialog.setOption(QFileDialog.Option.DontUseNativeDialog, True)
    dialog.setIconProvider(_ICONS)
    dialog.setProxyModel(_FoldersAndRegularFiles(dialog))
    if save:
        dialog.setAcceptMode(QFileDialog.AcceptMode.AcceptSave)
        dialog.setFileMode(QFileDialog.FileMode.AnyFile)
        if name:
            dialog.selectFile(name)
    else:
        dialog.setAcceptMode(QFileDialog.AcceptMode.AcceptOpen)
        dialog.setFileMode(QFileDialog.FileMode.ExistingFile)
    return dialog


def _run(dialog: QFileDialog) -> Path | None:
    try:
        if dialog.exec() != QFileDialog.DialogCode.Accepted or not dialog.selectedFiles():
            return None
        return Path(dialog.selectedFiles()[0])
    finally:
        dialog.deleteLater()


def ask_open_path(parent: QWidget | None, title: str, filters: str) -> Path | None:
    """Ask for an existing file; None when cancelled."""
    return _run(make_file_dialog(parent, title, filters, save=False))


def ask_save_path(parent: QWidget | None, title: str, name: str, filters: str) -> Path | None:
    """Ask where to save (``name`` is the suggested file name); None when cancelled."""
    return _run(make_file_dialog(parent, title, filters, save=True, name=name))


def ask_folder(parent: QWidget | None, title: str) -> Path | None:
    """Ask for a folder (a campaign); None when cancelled."""
    global _ICONS
    if _ICONS is None:
        _ICONS = TypeOnlyIconProvider()
    dialog = QFileDialog(parent, title)
    dialog.setObjectName("file_dialog")
    dialog.setOption(QFileDialog.Option.DontUseNativeDialog, True)
    dialog.setIconProvider(_ICONS)
    dialog.setFileMode(QFileDialog.FileMode.Directory)
    dialog.setOption(QFileDialog.Option.ShowDirsOnly, True)
    return _run(dialog)
