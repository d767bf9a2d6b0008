"""The main window's own wiring: its size, linked zoom, Ctrl+M, and matching settings that belong to the maps open."""

from __future__ import annotations

import dataclasses
import json

import cv2
import numpy as np
from PySide6.QtCore import Qt

from ursim_core.matching import MatchConfig


def test_the_window_fits_1366x768(window, qtbot):
    window.resize(1366, 768)
    qtbot.wait(50)
    assert window.width() <= 1366 and window.height() <= 768
    assert window.minimumSizeHint().width() <= 1366 and window.minimumSizeHint().height() <= 768


def test_linked_zoom(window, qtbot):
    sketch, metric = window.views["sketch"], window.views["metric"]
    window.actions["link_zoom"].setChecked(True)
    sketch.set_zoom(6)
    assert metric.zoom_factor() == sketch.zoom_factor() == 6
    window.actions["link_zoom"].setChecked(False)
    sketch.set_zoom(3)
    assert metric.zoom_factor() == 6


def test_ctrl_m_matches_again_after_a_link(window, qtbot):
    session = window.session
    assert window.actions["match"].isEnabled()
    session.link([1], [2])
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        qtbot.keyClick(window, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
        assert not window.actions["match"].isEnabled()  # one job at a time
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    assert (1, 2) in session.last_match.pairs
    assert window.actions["match"].isEnabled()


# ---- the orientation, input kind and scale belong to the maps open -------------------------------


def test_another_sketch_is_matched_with_its_orientation_unknown(window, map_files, tmp_path):
    """A known orientation belongs to its drawing: the next sketch (a campaign's next pair) must
    not be matched as if turned like the last one, while the same drawing keeps it."""
    import cv2
    import numpy as np

    panel, sketch = window.matching_panel, window.views["sketch"]
    panel.turn_left.click()
    window.documents.open_map("metric", map_files["metric"])  # the other side: kept
    assert panel.orientation.angle == 90.0 and sketch.orientation == (90.0, False)
    other = tmp_path / "another_sketch.png"
    cv2.imwrite(str(other), np.rot90(cv2.imread(str(map_files["sketch"]), cv2.IMREAD_GRAYSCALE)))
    window.documents.open_map("sketch", other)
    assert not panel.orientation.known and sketch.orientation == (0.0, False)
    if "orientation" in {field.name for field in dataclasses.fields(MatchConfig)}:
        assert panel.config().orientation == "any"
    panel.turn_right.click()
    window.session.load_map("sketch", other)  # the same drawing again
    assert panel.orientation.angle == 270.0 and sketch.orientation == (270.0, False)


def _another_map(path, tmp_path, name):
    other = tmp_path / name
    cv2.imwrite(str(other), np.fliplr(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)))
    return other


def _set_everything(panel):
    panel.turn_left.click()
    panel.set_input_kind("metric")
    panel.scale.setValue(0.5)
    config = panel.config()
    assert (config.orientation, config.input_kind, config.scale) == (90.0, "metric", 0.5)


def test_another_sketch_forgets_orientation_input_kind_and_scale(window, map_files, tmp_path):
    panel = window.matching_panel
    _set_everything(panel)
    window.documents.open_map("sketch", map_files["sketch"])  # the same drawing again: all kept
    assert (panel.config().orientation, panel.config().input_kind, panel.config().scale) == (90.0, "metric", 0.5)
    window.documents.open_map("sketch", _another_map(map_files["sketch"], tmp_path, "other_sketch.png"))
    config = panel.config()
    assert (config.orientation, config.input_kind, config.scale) == ("any", None, None)
    assert panel.scale.text() == "unknown (estimated)"


def test_another_metric_map_forgets_only_the_scale(window, map_files, tmp_path):
    panel = window.matching_panel
    _set_everything(panel)
    window.documents.open_map("metric", _another_map(map_files["metric"], tmp_path, "other_metric.png"))
    config = panel.config()
    # The scale relates the two maps; the orientation and input kind describe the sketch, still open.
    assert (config.orientation, config.input_kind, config.scale) == (90.0, "metric", None)


def test_a_file_opened_again_is_matched_with_the_settings_it_was_made_with(window, qtbot, map_files, tmp_path):
    panel, session = window.matching_panel, window.session
    panel.set_input_kind("metric")
    panel.scale.setValue(2.0)
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    assert session.last_match.config.resolved().matcher == "overlay"
    window.documents.save_as(tmp_path / "pair.json")
    record = json.loads((tmp_path / "pair.json").read_text())["matcher"]
    assert (record["config"]["input_kind"], record["config"]["scale"]) == ("metric", 2.0)

    # Another pair in between forgets them ...
    window.documents.close_document()
    window.documents.open_map("sketch", _another_map(map_files["sketch"], tmp_path, "other_sketch.png"))
    assert (panel.config().input_kind, panel.config().scale) == (None, None)
    # ... and the file brings them back, so that Match reproduces its cliques' matcher.
    assert window.documents.open_correspondences(tmp_path / "pair.json")
    assert (panel.config().input_kind, panel.config().scale) == ("metric", 2.0)
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    assert (session.last_match.config.resolved().matcher, session.last_match.config.scale) == ("overlay", 2.0)


def test_a_record_another_tool_wrote_sets_nothing_it_does_not_say_validly(window, qtbot, tmp_path):
    panel, session = window.matching_panel, window.session
    session.save(tmp_path / "pair.json")
    data = json.loads((tmp_path / "pair.json").read_text())
    data["matcher"] = {"config": {"input_kind": "lidar", "scale": "large"}, "note": "kept"}
    (tmp_path / "edited.json").write_text(json.dumps(data))
    panel.set_input_kind("sketch")
    panel.scale.setValue(3.0)
    assert window.documents.open_correspondences(tmp_path / "edited.json")
    assert (panel.config().input_kind, panel.config().scale) == (None, None)
    session.save(tmp_path / "again.json")  # the record is written back as it was
    assert json.loads((tmp_path / "again.json").read_text())["matcher"] == data["matcher"]
