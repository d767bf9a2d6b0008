"""The correspondence table: label and note cells edited in place, selection synced with the map views."""

from __future__ import annotations

import json

from conftest import region_point
from PySide6.QtCore import QPointF, Qt

from ursim_core.correspondences.exporters import clique_label, correspondences_to_geojson
from ursim_gui.panels.correspondence_table import COLUMNS


def test_label_edited_in_the_table_is_one_undo_step_and_round_trips(example_window, tmp_path):
    window = example_window
    session, model = window.session, window.table.model
    column = COLUMNS.index("Label")
    index = model.index(0, column)
    clique_id = model.clique_id(0)
    assert model.flags(index) & Qt.ItemFlag.ItemIsEditable
    assert model.setData(index, "  kitchen ", Qt.ItemDataRole.EditRole)
    assert clique_label(session.clique(clique_id)) == "kitchen"
    assert model.data(index) == "kitchen" and session.dirty
    region = session.clique(clique_id).sketch_regions[0]
    assert "“kitchen”" in window.tools.region_tooltip("sketch", region)

    window.actions["undo"].trigger()
    assert clique_label(session.clique(clique_id)) is None and model.data(index) == ""
    window.actions["redo"].trigger()
    assert clique_label(session.clique(clique_id)) == "kitchen"

    path = tmp_path / "labelled.json"
    session.save(path)
    stored = next(c for c in json.loads(path.read_text())["cliques"] if c["id"] == clique_id)
    assert stored["label"] == "kitchen"
    session.open(path)
    assert clique_label(session.clique(clique_id)) == "kitchen" and not session.dirty
    features = correspondences_to_geojson(session.correspondences, side="metric")["features"]
    assert any(f["properties"].get("label") == "kitchen" for f in features)

    # A blank label removes it (one more undo step); the same label again is no step at all.
    assert not window.actions["undo"].isEnabled() or "Label" not in window.actions["undo"].text()
    model.setData(index, "kitchen", Qt.ItemDataRole.EditRole)
    assert not session.dirty
    model.setData(index, "", Qt.ItemDataRole.EditRole)
    assert clique_label(session.clique(clique_id)) is None and session.dirty
    assert f"Label clique {clique_id}" in window.actions["undo"].text()


def test_table_and_views_select_each_other(window, qtbot):
    session = window.session
    a = session.link([1], [1])
    b = session.link([3], [3])
    table = window.table
    table.view.selectRow(table.model.row_of(b))
    assert session.selected_clique == b
    assert window.views["sketch"].marked_regions("selection") == {3}
    assert window.views["metric"].marked_regions("selection") == {3}
    sketch = window.views["sketch"]
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch, 1))
    assert session.selected_clique == a
    assert table.view.selectionModel().selectedRows()[0].row() == table.model.row_of(a)
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=sketch.mapFromScene(QPointF(0.5, 0.5)))
    assert session.selected_clique is None and not table.view.selectionModel().selectedRows()


def test_note_cell_edits_the_clique_note(window, qtbot):
    clique = window.session.link([1], [1])
    model = window.table.model
    note = model.index(model.row_of(clique), model.columnCount() - 1)
    assert model.flags(note) & Qt.ItemFlag.ItemIsEditable
    assert not model.flags(model.index(0, 1)) & Qt.ItemFlag.ItemIsEditable
    window.table.view.edit(note)
    from PySide6.QtWidgets import QLineEdit

    editor = window.table.view.findChild(QLineEdit)
    editor.setText("kitchen")
    qtbot.keyClick(editor, Qt.Key.Key_Return)  # the delegate commits on the next loop
    qtbot.waitUntil(lambda: window.session.clique(clique).note == "kitchen")
    assert model.data(note) == "kitchen"
    window.session.undo()
    assert window.session.clique(clique).note == ""
