"""Issue 13, sketch orientation: rotate (90-degree steps, free angle) and mirror the sketch view,
passed to the matcher; the points stay in the original image's pixel frame."""

from __future__ import annotations

import dataclasses

from conftest import region_point
from PySide6.QtCore import Qt

from ursim_core.matching import MatchConfig


def test_turning_the_sketch_keeps_points_in_the_image_frame(window, qtbot):
    session, panel, sketch = window.session, window.matching_panel, window.views["sketch"]
    interior = tuple(int(v) for v in session.segmentation("sketch").graph.nodes[1]["interior"])
    panel.turn_left.click()
    panel.mirror.click()
    assert sketch.orientation == (90.0, True)
    assert panel.orientation.angle == 90.0 and panel.orientation.mirrored
    # The view is turned: the map's width now runs vertically on screen.
    top_left, top_right = sketch.mapFromScene(0, 0), sketch.mapFromScene(100, 0)
    assert abs(top_left.x() - top_right.x()) < abs(top_left.y() - top_right.y())
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch, 1))
    assert session.selection["sketch"] == frozenset({1})
    qtbot.mouseClick(
        window.views["metric"].viewport(), Qt.MouseButton.LeftButton, pos=region_point(window.views["metric"], 1)
    )
    qtbot.keyClick(sketch, Qt.Key.Key_L)
    assert session.correspondences.cliques[0].sketch_points == (interior,)  # original pixel frame


def test_the_orientation_goes_to_the_match_config(window):
    panel = window.matching_panel
    fields = {field.name for field in dataclasses.fields(MatchConfig)}
    assert panel.config().matcher == "auto"
    panel.turn_right.click()
    panel.angle.setValue(30.0)
    panel.angle.editingFinished.emit()
    config = panel.config()
    if "orientation" in fields:  # the core's MatchConfig has the fields (added this round)
        assert config.orientation == 30.0 and config.mirrored is False
    panel.unknown.click()
    assert not panel.orientation.known and window.views["sketch"].orientation == (0.0, False)
    if "orientation" in fields:
        assert panel.config().orientation == "any"


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


def test_the_orientation_the_matcher_read_can_be_kept(window, qtbot):
    panel, sketch = window.matching_panel, window.views["sketch"]
    assert not panel.keep_found.isVisible()  # nothing matched yet
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        panel.match_button.click()
    result = window.session.last_match
    found = (float(round(result.orientation[0] % 360.0, 1) % 360.0), result.orientation[1])
    assert "read the sketch" in panel.summary.text()
    assert panel.keep_found.isVisible() and panel.found_orientation.describe() in panel.keep_found.text()
    panel.keep_found.click()
    assert (panel.orientation.angle, panel.orientation.mirrored) == found == sketch.orientation
    assert not panel.keep_found.isVisible()  # it is the orientation set now
    config = panel.config()
    assert (config.orientation, config.mirrored) == found
    panel.unknown.click()
    assert panel.keep_found.isVisible()  # offered again while the last answer stands


def test_a_file_opened_again_offers_the_orientation_its_match_read(window, qtbot, tmp_path):
    panel = window.matching_panel
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        panel.match_button.click()
    offered = panel.keep_found.text()
    window.documents.save_as(tmp_path / "pair.json")
    window.documents.open_correspondences(tmp_path / "pair.json")
    assert window.session.last_match is None  # no result in memory: the file's record speaks
    assert "automatic cliques from the file" in panel.summary.text() and "read the sketch" in panel.summary.text()
    assert panel.keep_found.isVisible() and panel.keep_found.text() == offered
    panel.keep_found.click()
    assert window.views["sketch"].orientation == (panel.orientation.angle, panel.orientation.mirrored)
