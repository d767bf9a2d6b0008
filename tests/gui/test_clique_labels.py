"""Semantic clique labels in the GUI: edited in the table (one undo step), saved, shown on the map, exported (issue 15)."""

from __future__ import annotations

import json

from PySide6.QtCore import Qt

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
