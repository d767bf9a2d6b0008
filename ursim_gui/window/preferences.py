"""User preferences (QSettings, an INI file in the user data folder): annotator, recent files, layout.

The annotator's name is asked once and then remembered; recent campaigns and
correspondence files, the window geometry, dock layout and display toggles are restored
at the next start. The file is ``<data folder>/settings.ini`` so tests and portable
installs keep it beside their other data.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSettings
from PySide6.QtWidgets import QInputDialog, QWidget

__all__ = ["Preferences", "MAX_RECENT", "LAYOUT_VERSION"]

MAX_RECENT = 10
#: Raised when the docks' arrangement changes (2: the right column split evenly between the
#: segmentation and matching docks), so a layout saved by an older app is not restored.
LAYOUT_VERSION = 2


class Preferences:
    """Typed access to the app's settings file."""

    def __init__(self, data_dir: Path, parent: QWidget | None = None):
        self.path = Path(data_dir) / "settings.ini"
        self.settings = QSettings(str(self.path), QSettings.Format.IniFormat)
        self.parent = parent

    # ---- annotator -------------------------------------------------------------------
    def annotator(self, *, ask: bool = False) -> str:
        """The annotator's name; with ``ask``, asked once when unknown (empty if declined)."""
        name = str(self.settings.value("annotator", "") or "")
        if not name and ask:
            name, ok = QInputDialog.getText(
                self.parent, "Annotator", "Your name (written into every correspondence file you save):"
            )
            name = name.strip() if ok else ""
            if name:
                self.set_annotator(name)
        return name

    def set_annotator(self, name: str) -> None:
        self.settings.setValue("annotator", str(name))
        self.settings.sync()

    # ---- recent files ----------------------------------------------------------------------
    def recent(self, kind: str) -> list[str]:
        value = self.settings.value(f"recent/{kind}", [])
        if isinstance(value, str):
            value = [value]
        return [str(item) for item in (value or [])]

    def add_recent(self, kind: str, path: str) -> None:
        items = [path] + [item for item in self.recent(kind) if item != path]
        self.settings.setValue(f"recent/{kind}", items[:MAX_RECENT])
        self.settings.sync()

    # ---- window layout ----------------------------------------------------------------------
    def save_window(self, window, toggles: dict[str, bool]) -> None:
        self.settings.setValue("window/geometry", window.saveGeometry())
        self.settings.setValue("window/state", window.saveState(LAYOUT_VERSION))
        for name, checked in toggles.items():
            self.settings.setValue(f"display/{name}", bool(checked))
        self.settings.sync()

    def restore_window(self, window) -> bool:
        """Geometry and dock layout of the last session; False when there is none."""
        geometry = self.settings.value("window/geometry")
        state = self.settings.value("window/state")
        restored = bool(geometry) and window.restoreGeometry(geometry)
        if state:
            # A layout saved by an app whose docks were arranged otherwise is not restored
            # (Qt refuses a state of another version): the user gets the new arrangement.
            window.restoreState(state, LAYOUT_VERSION)
        return restored

    def toggle(self, name: str, default: bool) -> bool:
        value = self.settings.value(f"display/{name}", default)
        return value in (True, "true", "1", 1)
