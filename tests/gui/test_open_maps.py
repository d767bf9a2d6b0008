"""Feature 1: opening maps from the menu, by drag and drop, from the command line, and
through a correspondence JSON; unreadable files give an error dialog, never a crash."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import error_boxes
from PySide6.QtCore import QMimeData, QPointF, Qt, QUrl
from PySide6.QtGui import QDropEvent

from ursim_gui.app import parse_args
from ursim_gui.views import file_dialogs
from ursim_gui.window.main_window import MainWindow


@pytest.fixture
def empty_window(qtbot, tmp_path):
    win = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(win)
    win.show()
    return win


def choose_file(monkeypatch, path):
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(path)))


def test_file_menu_opens_each_map(empty_window, map_files, monkeypatch):
    win = empty_window
    choose_file(monkeypatch, map_files["sketch"])
    win.actions["open_sketch"].trigger()
    choose_file(monkeypatch, map_files["metric"])
    win.actions["open_metric"].trigger()
    assert win.session.map("sketch").shape == (60, 150)
    assert win.session.map("metric").shape == (120, 300)
    assert win.views["metric"].sceneRect().width() == 300
    assert "300 × 120 px" in win.view_titles["metric"].text()  # width x height
    assert win.segmentation_panel.boxes["metric"].segment_button.isEnabled()


def test_drop_on_a_view_opens_that_side(empty_window, map_files):
    view = empty_window.views["metric"]
    data = QMimeData()
    data.setUrls([QUrl.fromLocalFile(str(map_files["metric"]))])
    view.dropEvent(
        QDropEvent(
            QPointF(5, 5), Qt.DropAction.CopyAction, data, Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
        )
    )
    assert empty_window.session.map("metric").path == map_files["metric"]
    assert view.has_image()


def test_ros_yaml_map_opens(empty_window, map_files, tmp_path, monkeypatch):
    yaml_path = tmp_path / "ros.yaml"
    yaml_path.write_text(
        f"image: {map_files['metric'].name}\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    choose_file(monkeypatch, yaml_path)
    empty_window.actions["open_metric"].trigger()
    assert empty_window.session.map("metric").resolution == pytest.approx(0.05)


def test_unreadable_map_shows_an_error_and_changes_nothing(empty_window, tmp_path, monkeypatch, caplog):
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image at all")
    choose_file(monkeypatch, bad)
    empty_window.actions["open_sketch"].trigger()
    boxes = error_boxes(empty_window)
    assert boxes and "broken.png" in boxes[0].text()
    assert empty_window.session.map("sketch") is None
    assert any("broken.png" in record.getMessage() and record.levelname == "ERROR" for record in caplog.records)


def test_command_line_maps_are_opened_segmented_and_matched(empty_window, map_files):
    args = parse_args([str(map_files["sketch"]), str(map_files["metric"])])
    assert empty_window.open_inputs(*args.maps, wait=True)
    session = empty_window.session
    assert session.segmentation("sketch") is not None and session.segmentation("metric") is not None
    assert session.last_match is not None
    with pytest.raises(SystemExit):
        parse_args(["only_one_map.png"])


def test_open_correspondences_loads_the_maps_it_names(window, tmp_path, monkeypatch):
    window.session.link([1], [1])
    saved = tmp_path / "corr.json"
    window.session.save(saved)
    fresh = MainWindow(data_dir=tmp_path / "other")
    window.close()
    choose_file(monkeypatch, saved)
    fresh.actions["open_correspondences"].trigger()
    assert fresh.session.path == saved
    assert fresh.session.map("sketch") is not None and fresh.session.map("metric") is not None
    assert len(fresh.session.correspondences.cliques) == 1
    assert fresh.table.model.rowCount() == 1
    fresh.discard_and_close()


def test_bad_json_shows_an_error(empty_window, tmp_path, monkeypatch):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "something else"}))
    choose_file(monkeypatch, bad)
    empty_window.actions["open_correspondences"].trigger()
    assert error_boxes(empty_window)
    assert empty_window.session.path is None


def test_command_line_correspondences_option(window, tmp_path, qtbot):
    window.session.link([2], [2])
    saved = tmp_path / "cli.json"
    window.session.save(saved)
    fresh = MainWindow(data_dir=tmp_path / "cli-data")
    qtbot.addWidget(fresh)
    args = parse_args(["--correspondences", str(saved)])
    assert fresh.open_inputs(correspondences=args.correspondences)
    assert fresh.session.path == saved and fresh.session.correspondences.cliques[0].sketch_regions == (2,)
