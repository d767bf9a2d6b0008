"""The evaluation panel: a reference's live precision / recall / F1, TP / FP / FN marks, clickable misses."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import answer_file_dialogs

from ursim_core.correspondences import Clique, Correspondences, save_correspondences, save_dat
from ursim_gui.views import file_dialogs


def reference_cliques():
    # Points inside rooms 1, 2, 3 of both maps (the metric map is the sketch scaled by 2).
    return Correspondences(
        cliques=tuple(
            Clique(id=i, sketch_points=[(30, col)], metric_points=[(60, 2 * col)])
            for i, col in ((1, 25), (2, 75), (3, 120))
        )
    )


@pytest.mark.parametrize("suffix", [".json", ".dat"])
def test_reference_scores_live_and_marks_cliques(window, tmp_path, monkeypatch, suffix):
    path = tmp_path / f"reference{suffix}"
    (save_correspondences if suffix == ".json" else save_dat)(reference_cliques(), path)
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(path)))
    session, panel = window.session, window.evaluation
    good = session.link([1], [1])
    bad = session.link([2], [3])
    panel.load_button.click()
    assert session.reference is not None
    assert panel.values["precision"].text() == "0.500"
    assert panel.values["recall"].text() == "0.333"
    assert panel.values["counts"].text() == "1 / 1 / 2"
    # Place accuracy: room 1's point is sent to room 1; room 2's to room 3 (wrong); room 3 unmatched.
    assert panel.values["place"].text() == "0.333 (1 / 3 points)"
    model = window.table.model
    assert model.data(model.index(model.row_of(good), 6)) == "TP"
    assert model.data(model.index(model.row_of(bad), 6)) == "FP"
    assert window.views["sketch"].badge_texts() == {1: "TP", 2: "FP", 3: "FN"}  # FN: a missed clique
    assert panel.missed.count() == 2 and panel.missed.item(0).text() == "2  ↔  2"

    session.delete_clique(bad)  # live: every edit re-scores
    assert panel.values["precision"].text() == "1.000"
    session.link([2], [2])
    session.link([3], [3])
    assert panel.values["f1"].text() == "1.000" and panel.missed.count() == 0
    assert panel.values["place"].text() == "1.000 (3 / 3 points)"

    panel.clear_button.click()
    assert session.reference is None and panel.values["f1"].text() == "–"
    assert model.data(model.index(0, 6)) == "" and window.views["sketch"].badge_texts() == {}


def test_scores_over_nothing_are_not_perfect_and_misses_are_clickable(window, qtbot, tmp_path, monkeypatch):
    panel = window.evaluation
    assert panel.values["f1"].text() == "–"  # no reference
    on_walls = Correspondences(cliques=(Clique(id=1, sketch_points=[(0, 0)], metric_points=[(0, 0)]),))
    walls = tmp_path / "walls.json"
    save_correspondences(on_walls, walls)
    answer_file_dialogs(monkeypatch, walls)
    panel.load_button.click()
    assert panel.values["counts"].text() == "0 / 0 / 0"
    assert not panel.values["precision"].text().startswith("1.0") and not panel.values["f1"].text().startswith("1.0")

    rooms = Correspondences(cliques=(Clique(id=1, sketch_points=[(30, 120)], metric_points=[(60, 240)]),))
    reference = tmp_path / "rooms.json"
    save_correspondences(rooms, reference)
    answer_file_dialogs(monkeypatch, reference)
    panel.load_button.click()
    assert panel.missed.count() == 1
    assert window.views["sketch"].badge_texts() == {3: "FN"} and window.views["metric"].badge_texts() == {3: "FN"}
    item = panel.missed.item(0)
    panel.missed.itemClicked.emit(item)
    assert window.session.selection == {"sketch": frozenset({3}), "metric": frozenset({3})}
