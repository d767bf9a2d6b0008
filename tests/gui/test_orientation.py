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
