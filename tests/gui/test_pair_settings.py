"""The matching panel's orientation, input kind and scale belong to the maps open: another map is
matched with them unknown, the same maps keep them, and a file opened again brings back the input
kind and scale its automatic cliques were made with."""

from __future__ import annotations

import json

import cv2
import numpy as np
from PySide6.QtCore import Qt

from ursim_gui.model.pair_settings import MapIdentities, recorded_settings


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


def test_the_rules_without_qt():
    identities = MapIdentities({"sketch": None, "metric": "m"})
    assert identities.settings_to_forget("sketch", None) == ()  # the canvas's drawing, edited
    assert identities.settings_to_forget("sketch", "s") == ("orientation", "input_kind", "scale")
    assert identities.settings_to_forget("sketch", "s") == ()
    assert identities.settings_to_forget("metric", "m") == ()
    assert identities.settings_to_forget("metric", None) == ("scale",)
    assert recorded_settings({"config": {"input_kind": "sketch", "scale": 1e9}}) == {
        "input_kind": "sketch",
        "scale": None,
    }
    assert recorded_settings({"config": {"scale": True}}) == {"input_kind": None, "scale": None}
    assert recorded_settings({"config": "x"}) == {} == recorded_settings([1])
