"""The dark theme: it reaches the map views and is remembered."""

from __future__ import annotations


def test_dark_theme_follows_into_the_map_views_and_is_remembered(window, tmp_path, qtbot):
    from PySide6.QtWidgets import QApplication

    from ursim_gui.window.main_window import MainWindow

    light = window.views["sketch"].backgroundBrush().color().lightness()
    window.actions["dark_theme"].setChecked(True)
    QApplication.processEvents()
    try:
        assert QApplication.instance().palette().window().color().lightness() < 100
        assert window.views["sketch"].backgroundBrush().color().lightness() < light
        window.close()
        again = MainWindow(data_dir=tmp_path / "userdata")
        qtbot.addWidget(again)
        assert again.actions["dark_theme"].isChecked()
        again.actions["dark_theme"].setChecked(False)
        again.jobs.runner.shutdown()
    finally:
        window.actions["dark_theme"].setChecked(False)
        QApplication.processEvents()
