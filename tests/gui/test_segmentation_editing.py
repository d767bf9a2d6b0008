"""Issue 13, segmentation editing: merge, split by a line, paint / erase a wall; one undo step each;
saved as a label image referenced in the JSON (method "edited") and reopened exactly."""

from __future__ import annotations

import json

import numpy as np
from conftest import region_point
from PySide6.QtCore import QPointF, Qt
from PySide6.QtTest import QTest

from ursim_gui.model.session import AnnotationSession


def click(qtbot, view, region, modifier=Qt.KeyboardModifier.NoModifier):
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, modifier, region_point(view, region))


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


def test_an_edited_segmentation_is_saved_beside_the_file_and_reopened_exactly(window, qtbot, tmp_path):
    session = window.session
    session.link([1], [1])
    session.merge_regions("sketch", 2, 3)
    edited = session.segmentation("sketch").labels.copy()
    document = tmp_path / "doc.json"
    session.save(document)
    labels_file = tmp_path / "doc.sketch.labels.png"
    raw = json.loads(document.read_text())
    sketch_ref = raw["maps"]["sketch"] if "maps" in raw else raw["sketch"]
    text = json.dumps(sketch_ref)
    assert labels_file.is_file() and "doc.sketch.labels.png" in text and '"edited"' in text
    assert "label-image" in text  # the method it started from
    assert not session.dirty

    reopened = AnnotationSession()
    reopened.open(document)
    assert np.array_equal(reopened.segmentation("sketch").labels, edited)
    assert reopened.correspondences.cliques == session.correspondences.cliques and not reopened.dirty


def test_an_edited_segmentation_survives_a_crash_through_the_autosave_copy(window, tmp_path):
    """The autosave copy carries the edited label image, so recovering it restores the edit."""
    from ursim_gui.model.autosave import Autosaver, discard, recover

    session = window.session
    session.link([1], [1])
    session.merge_regions("sketch", 2, 3)
    edited = session.segmentation("sketch").labels.copy()
    saver = Autosaver(session, tmp_path / "autosave")
    saver.flush()
    copy = saver.path
    labels_copy = copy.with_name(f"{copy.stem}.sketch.labels.png")
    assert copy.is_file() and labels_copy.is_file()
    assert session.path is None or session.path.parent != copy.parent  # the document is untouched

    recovered = AnnotationSession()
    recovered.restore(recover(copy))
    assert np.array_equal(recovered.segmentation("sketch").labels, edited)
    discard(copy)
    assert not copy.exists() and not labels_copy.exists()
    saver.close()
