"""Preferences kept between runs: the recent files."""

from __future__ import annotations


def test_recent_files_are_remembered_and_offered(window, tmp_path, qtbot):
    from ursim_gui.window.main_window import MainWindow

    window.session.link([1], [1])
    window.documents.save_as(tmp_path / "doc.json")
    window.close()
    again = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(again)
    again._fill_recent_menu()
    assert str(tmp_path / "doc.json") in [action.text() for action in again.recent_menu.actions()]
    again.jobs.runner.shutdown()


def test_a_dock_layout_saved_by_an_older_app_is_not_restored(qtbot, tmp_path):
    # The docks were rearranged (LAYOUT_VERSION): an old layout would hide the Match button again.
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QDockWidget, QMainWindow

    from ursim_gui.window.preferences import LAYOUT_VERSION, Preferences

    def window_with_dock(area):
        window = QMainWindow()
        qtbot.addWidget(window)
        dock = QDockWidget("panel")
        dock.setObjectName("panel")
        window.addDockWidget(area, dock)
        return window, dock

    preferences = Preferences(tmp_path)
    old, _ = window_with_dock(Qt.DockWidgetArea.LeftDockWidgetArea)
    preferences.settings.setValue("window/state", old.saveState(LAYOUT_VERSION - 1))
    new, dock = window_with_dock(Qt.DockWidgetArea.RightDockWidgetArea)
    preferences.restore_window(new)
    assert new.dockWidgetArea(dock) == Qt.DockWidgetArea.RightDockWidgetArea
    preferences.save_window(old, {})
    preferences.restore_window(new)
    assert new.dockWidgetArea(dock) == Qt.DockWidgetArea.LeftDockWidgetArea
