"""The segmentation editor on the map views: merge, split by a line, paint and erase a wall, one undo step each."""

from __future__ import annotations

import numpy as np
from conftest import click
from PySide6.QtCore import QPointF, Qt
from PySide6.QtTest import QTest


def drag(qtbot, view, start, end):
    """A left drag from pixel ``start`` to pixel ``end`` ((row, col))."""
    to_view = lambda rc: view.mapFromScene(QPointF(rc[1] + 0.5, rc[0] + 0.5))
    qtbot.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=to_view(start))
    QTest.mouseMove(view.viewport(), to_view(((start[0] + end[0]) // 2, (start[1] + end[1]) // 2)))
    QTest.mouseMove(view.viewport(), to_view(end))
    qtbot.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=to_view(end))


def regions(window, side):
    return sorted(int(r) for r in np.unique(window.session.segmentation(side).labels) if r)


def test_merge_selected_regions_is_one_undo_step_and_cliques_follow_their_points(window, qtbot):
    session, sketch = window.session, window.views["sketch"]
    session.link([2], [2])
    click(qtbot, sketch, 1, Qt.KeyboardModifier.ControlModifier)
    click(qtbot, sketch, 2, Qt.KeyboardModifier.ControlModifier)
    steps = len(session.history)
    qtbot.keyClick(sketch, Qt.Key.Key_M)
    assert regions(window, "sketch") == [1, 3] and session.correspondences.cliques[0].sketch_regions == (1,)
    assert session.segmentation("sketch").method == "edited" and len(session.history) == steps + 1
    qtbot.keyClick(sketch, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert regions(window, "sketch") == [1, 2, 3] and session.correspondences.cliques[0].sketch_regions == (2,)
    qtbot.keyClick(sketch, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert regions(window, "sketch") == [1, 3]


def test_split_a_region_by_drawing_a_line(window, qtbot):
    session, metric = window.session, window.views["metric"]
    qtbot.keyClick(metric, Qt.Key.Key_K)
    assert window.actions["split_mode"].isChecked() and metric.stroke_mode
    drag(qtbot, metric, (4, 150), (115, 150))  # across room 2 of the metric map (cols 104..196)
    assert regions(window, "metric") == [1, 2, 3, 4]
    qtbot.keyClick(metric, Qt.Key.Key_Escape)
    assert not metric.stroke_mode and not window.actions["split_mode"].isChecked()
    session.undo()
    assert regions(window, "metric") == [1, 2, 3]


def test_paint_and_erase_a_wall(window, qtbot):
    session, sketch = window.session, window.views["sketch"]
    qtbot.keyClick(sketch, Qt.Key.Key_W)
    drag(qtbot, sketch, (2, 25), (58, 25))  # a wall across room 1
    assert regions(window, "sketch") == [1, 2, 3, 4]
    painted = session.segmentation("sketch").labels.copy()
    assert (painted[5:55, 24:27] == 0).all()
    qtbot.keyClick(sketch, Qt.Key.Key_W, Qt.KeyboardModifier.ShiftModifier)
    assert window.actions["erase_wall_mode"].isChecked() and not window.actions["paint_wall_mode"].isChecked()
    drag(qtbot, sketch, (10, 50), (20, 50))  # the wall between rooms 1 and 2, above the door
    erased = session.segmentation("sketch").labels
    assert (erased[10:21, 49:52] != 0).all()
    assert len(session.history) == 2  # one step each
