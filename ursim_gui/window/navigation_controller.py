"""Wiring of the goal and route tools into the window: tool actions, Esc, exports with file dialogs."""

from __future__ import annotations

from pathlib import Path

from ursim_core.errors import UrsimError
from ursim_gui.model.navigation import NavigationModel
from ursim_gui.tools.navigation_tools import NavigationTools
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs

__all__ = ["NavigationController"]

_TOOL_ACTIONS = {"goal_tool": "goal", "route_tool": "route"}


class NavigationController:
    """Goal / route tools of ``window`` (a MainWindow) and their File-like exports."""

    def __init__(self, window, segmentation_editor):
        self.window = window
        self.model = NavigationModel(window.session)
        self.tools = NavigationTools(self.model, window.views, window)
        self.editor = segmentation_editor
        a = window.actions
        for action_id, mode in _TOOL_ACTIONS.items():
            a[action_id].toggled.connect(lambda on, mode=mode: self._toggled(mode, on))
        self.tools.mode_changed.connect(lambda mode: [a[i].setChecked(_TOOL_ACTIONS[i] == mode) for i in _TOOL_ACTIONS])
        # The segmentation editor's stroke modes and these tools share the left drag: one at a time.
        segmentation_editor.mode_changed.connect(lambda mode: mode and self.tools.set_mode(""))
        a["clear_selection"].triggered.connect(lambda: self.tools.set_mode(""))
        a["goal_nearest"].triggered.connect(self.model.accept_offer)
        a["clear_navigation"].triggered.connect(self.model.clear)
        a["export_navigation"].triggered.connect(lambda: self.export_json())
        a["export_nav2"].triggered.connect(lambda: self.export_nav2())
        self.tools.message.connect(lambda text: window.statusBar().showMessage(text, 8000))

    def _toggled(self, mode: str, on: bool) -> None:
        if on:
            if self.editor.mode:
                self.editor.set_mode("")
            self.tools.set_mode(mode)
        elif self.tools.mode == mode:
            self.tools.set_mode("")

    def export_json(self, path: Path | None = None) -> bool:
        """Write the goals and route as JSON (asks for the file when ``path`` is None)."""
        return self._export(
            path, "Export goals and route", "goals.json", "Navigation JSON (*.json)", self.model.save_json
        )

    def export_nav2(self, path: Path | None = None) -> bool:
        """Write nav2's waypoint file (asks for the file when ``path`` is None)."""
        return self._export(
            path, "Export nav2 waypoints", "waypoints.yaml", "nav2 waypoints (*.yaml)", self.model.save_nav2_waypoints
        )

    def _export(self, path, title: str, name: str, filters: str, save) -> bool:
        if not self.model.has_content():
            self.window.statusBar().showMessage("Nothing to export: place a goal or draw a route first", 6000)
            return False
        if path is None:
            path = file_dialogs.ask_save_path(self.window, title, name, filters)
            if path is None:
                return False
        try:
            save(path)
        except (UrsimError, OSError) as error:
            dialogs.show_error(self.window, "Export failed", str(error))
            return False
        self.window.statusBar().showMessage(f"Written to {path}", 4000)
        return True
