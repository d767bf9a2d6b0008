"""AnnotationSession (ursim_gui.model.session): undo/redo, dirty, maps and re-segmentation, queries."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import METRIC_LABELS, SKETCH_LABELS, Recorder, fake_match, interior, map_of, seg_of

from ursim_core.errors import SegmentationError
from ursim_gui.model.session import AnnotationSession, color_of_clique

# ---- undo / redo ---------------------------------------------------------------------------------


def test_undo_and_redo_restore_exact_values(session):
    values = [session.correspondences]
    session.link([1], [1])
    values.append(session.correspondences)
    session.link([2, 3], [2], into=None)
    values.append(session.correspondences)
    session.set_status(2, "accepted")
    values.append(session.correspondences)
    session.unlink("sketch", 3)
    values.append(session.correspondences)
    session.apply_match(fake_match([(5, 5), (6, 6)]))
    values.append(session.correspondences)
    session.delete_clique(1)
    values.append(session.correspondences)

    recorder = Recorder(session)
    for expected in reversed(values[:-1]):
        assert session.undo() is True
        assert session.correspondences == expected
    assert session.undo() is False and not session.can_undo
    for expected in values[1:]:
        assert session.redo() is True
        assert session.correspondences == expected
    assert session.redo() is False
    steps = 2 * (len(values) - 1)
    assert recorder.count("correspondences_changed") == steps
    assert recorder.count("history_changed") == steps


def test_a_new_edit_after_undo_drops_the_redo_tail(session):
    session.link([1], [1])
    session.link([2], [2])
    session.undo()
    assert session.redo_text == "Link sketch 2 to metric 2"
    session.link([3], [3])
    assert not session.can_redo
    assert [c.sketch_regions for c in session.correspondences.cliques] == [(1,), (3,)]


# ---- dirty, title --------------------------------------------------------------------------------


def test_dirty_follows_the_saved_value_including_undo_back_to_it(session, tmp_path):
    recorder = Recorder(session)
    assert not session.dirty and session.window_title() == "URSIM Studio — untitled"
    session.link([1], [1])
    assert session.dirty and session.window_title() == "URSIM Studio — untitled*"
    session.save(tmp_path / "pair.json")
    assert not session.dirty and session.window_title() == "URSIM Studio — pair.json"
    assert recorder.calls["path_changed"] == [(tmp_path / "pair.json",)]
    session.link([2], [2])
    assert session.dirty
    session.undo()
    assert not session.dirty  # back to exactly what is on disk
    session.undo()
    assert session.dirty  # before the saved state is a change too
    session.redo()
    assert not session.dirty
    assert recorder.calls["dirty_changed"] == [(True,), (False,), (True,), (False,), (True,), (False,)]


# ---- maps and re-segmentation --------------------------------------------------------------------


def test_set_map_updates_the_reference_and_drops_the_segmentation(session):
    session.link([1], [1])
    recorder = Recorder(session)
    session.set_map("sketch", map_of(SKETCH_LABELS))
    assert session.segmentation("sketch") is None
    assert session.correspondences.sketch.size == SKETCH_LABELS.shape
    assert session.correspondences.sketch.segmentation_method is None
    assert session.correspondences.cliques[0].sketch_points == (interior(SKETCH_LABELS, 1),)
    assert recorder.calls["map_changed"] == [("sketch",)]
    assert recorder.calls["segmentation_changed"] == [("sketch",)]
    session.undo()  # the history was rebased: undo does not bring back the old segmentation reference
    assert session.correspondences.sketch.segmentation_method is None


def test_resegmentation_reassigns_region_ids_from_points_in_every_history_value(session):
    session.link([1], [1])
    session.link([2, 3], [9])
    # Renumber the sketch rooms (10 - id) and merge old rooms 2 and 3 into one region.
    renumbered = np.where(SKETCH_LABELS > 0, 10 - SKETCH_LABELS, 0).astype(np.int32)
    merged = renumbered.copy()
    merged[merged == 7] = 8
    recorder = Recorder(session)
    session.set_segmentation("sketch", seg_of(merged))
    cliques = session.correspondences.cliques
    assert [c.sketch_regions for c in cliques] == [(9,), (8,)]
    assert [c.metric_regions for c in cliques] == [(1,), (9,)]
    assert cliques[1].sketch_points == (interior(SKETCH_LABELS, 2), interior(SKETCH_LABELS, 3))
    assert session.correspondences.sketch.segmentation_method == "label-image"
    assert recorder.count("segmentation_changed") == 1 and recorder.count("correspondences_changed") == 1
    session.undo()
    assert [c.sketch_regions for c in session.correspondences.cliques] == [(9,)]


def test_set_segmentation_refuses_labels_of_another_size(session):
    with pytest.raises(SegmentationError, match="label image"):
        session.set_segmentation("sketch", seg_of(METRIC_LABELS))


def test_resegmentation_clears_that_sides_selection(session):
    session.select("sketch", [1, 2])
    session.select("metric", [3], add=True)
    session.set_segmentation("sketch", seg_of(SKETCH_LABELS))
    assert session.selection == {"sketch": frozenset(), "metric": frozenset({3})}


def test_the_no_region_reason_is_worked_out_once_per_segmentation(session, monkeypatch):
    from ursim_core import segmentation as segmentation_module

    assert session.no_region_reason("sketch") is None  # it has regions
    asked = []
    monkeypatch.setattr(segmentation_module, "why_no_region", lambda free, method: asked.append(1) or "why")
    empty = seg_of(np.zeros_like(SKETCH_LABELS))
    session.set_segmentation("sketch", empty)
    assert session.no_region_reason("sketch") == session.no_region_reason("sketch") == "why"
    assert len(asked) == 1
    session.set_segmentation("sketch", seg_of(np.zeros_like(SKETCH_LABELS)))  # a new one: asked again
    assert session.no_region_reason("sketch") == "why" and len(asked) == 2
    assert AnnotationSession().no_region_reason("metric") is None


def test_a_new_map_drops_the_kept_no_region_reason_and_its_segmentation(session, monkeypatch):
    from ursim_core import segmentation as segmentation_module

    monkeypatch.setattr(segmentation_module, "why_no_region", lambda free, method: "why")
    session.set_segmentation("sketch", seg_of(np.zeros_like(SKETCH_LABELS)))
    assert session.no_region_reason("sketch") == "why"
    session.set_map("sketch", map_of(SKETCH_LABELS))
    assert session.no_region_reason("sketch") is None and "sketch" not in session._no_region_reasons


# ---- queries, selection, match configuration -----------------------------------------------------


def test_partners_clique_of_and_colours(session):
    first = session.link([1, 2], [5])
    second = session.link([2], [6, 7])
    assert session.partners("sketch", 2) == frozenset({5, 6, 7})
    assert session.partners("metric", 5) == frozenset({1, 2})
    assert session.partners("sketch", 9) == frozenset()
    assert session.clique_of("sketch", 2) == [first, second]
    assert session.clique_of("metric", 7) == [second]
    colours = {session.color_of_clique(i) for i in range(1, 40)}
    assert len(colours) == 39
    assert all(0 <= channel <= 255 for colour in colours for channel in colour)
    overlay = pytest.importorskip("ursim_gui.model.region_style")
    assert all(color_of_clique(i) == overlay.clique_colour(i) for i in range(1, 100))


def test_match_config_defaults_to_the_core_defaults(session):
    matching = pytest.importorskip("ursim_core.matching", reason="ursim_core.matching is not available yet")
    assert session.match_config == matching.MatchConfig()
    custom = dataclasses.replace(matching.MatchConfig(), m=0.1)
    session.match_config = custom
    assert session.match_config is custom
