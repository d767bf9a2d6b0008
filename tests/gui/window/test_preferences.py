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
