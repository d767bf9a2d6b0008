"""Undoable edits of the session (ursim_gui.model.session_edits): link, unlink, delete, status, note, apply_match."""

from __future__ import annotations

import types

import numpy as np
import pytest
from conftest import METRIC_LABELS, NOW, SKETCH_LABELS, Recorder, fake_match, interior, write_document_files

from ursim_gui.model.session import AnnotationSession

# ---- link ----------------------------------------------------------------------------------------


def test_link_creates_a_manual_clique_at_interior_points_in_one_history_entry(session):
    recorder = Recorder(session)
    clique_id = session.link([1, 2], [5])
    clique = session.correspondences.clique(clique_id)
    assert clique_id == 1
    assert clique.sketch_regions == (1, 2) and clique.metric_regions == (5,)
    assert clique.sketch_points == (interior(SKETCH_LABELS, 1), interior(SKETCH_LABELS, 2))
    assert clique.metric_points == (interior(METRIC_LABELS, 5),)
    assert clique.source == "manual" and clique.effective_status == "accepted"
    assert len(session.history) == 1 and session.undo_text == "Link sketch 1, 2 to metric 5"
    assert recorder.count("correspondences_changed") == 1
    assert recorder.count("history_changed") == 1
    assert recorder.calls["dirty_changed"] == [(True,)]


def test_link_into_an_existing_clique_adds_only_new_regions_and_makes_it_manual(session):
    session.apply_match(fake_match([(1, 1)]))
    auto_id = session.correspondences.cliques[0].id
    recorder = Recorder(session)
    assert session.link([1, 4], [2], into=auto_id) == auto_id
    clique = session.correspondences.clique(auto_id)
    assert clique.sketch_regions == (1, 4) and clique.metric_regions == (1, 2)
    assert clique.sketch_points == (interior(SKETCH_LABELS, 1), interior(SKETCH_LABELS, 4))
    assert clique.source == "manual"
    assert recorder.count("history_changed") == 1 and len(session.history) == 2

    # Nothing new to add: no history entry, no signal.
    recorder.reset()
    session.link([4], [1, 2], into=auto_id)
    assert len(session.history) == 2 and recorder.count("correspondences_changed") == 0


def test_link_rejects_bad_input_without_touching_the_document(session):
    before = session.correspondences
    with pytest.raises(ValueError, match="at least one region"):
        session.link([], [])
    with pytest.raises(ValueError, match="sketch region"):
        session.link([99], [1])
    with pytest.raises(KeyError):
        session.link([1], [1], into=42)
    bare = AnnotationSession()
    with pytest.raises(ValueError, match="not segmented"):
        bare.link([1], [])
    assert session.correspondences == before and len(session.history) == 0


def test_new_clique_ids_continue_after_the_largest(session):
    assert [session.link([r], [r]) for r in (1, 2, 3)] == [1, 2, 3]
    session.delete_clique(2)
    assert session.link([4], [4]) == 4


# ---- unlink, delete ------------------------------------------------------------------------------


def test_unlink_removes_the_region_and_its_point_and_keeps_the_rest(session):
    clique_id = session.link([1, 2], [5, 6])
    session.unlink("sketch", 2)
    clique = session.correspondences.clique(clique_id)
    assert clique.sketch_regions == (1,) and clique.sketch_points == (interior(SKETCH_LABELS, 1),)
    assert clique.metric_regions == (5, 6)
    assert session.undo_text == "Unlink sketch region 2"


def test_unlink_keeps_half_cliques_and_deletes_cliques_empty_on_both_sides(session):
    clique_id = session.link([1], [5])
    session.unlink("sketch", 1)
    assert session.correspondences.clique(clique_id).sketch_regions == ()
    session.unlink("metric", 5)
    assert session.correspondences.cliques == ()
    assert len(session.history) == 3


def test_unlink_touches_every_clique_with_the_region(session):
    session.link([1], [5])
    session.link([1, 2], [6])
    session.unlink("sketch", 1)
    assert [c.sketch_regions for c in session.correspondences.cliques] == [(), (2,)]
    assert len(session.history) == 3


def test_unlink_of_a_region_in_no_clique_is_a_no_op(session):
    session.link([1], [5])
    recorder = Recorder(session)
    session.unlink("metric", 9)
    assert len(session.history) == 1 and recorder.count("correspondences_changed") == 0


def test_delete_clique_and_the_selected_clique_follows(session):
    first = session.link([1], [1])
    second = session.link([2], [2])
    session.select_clique(second)
    recorder = Recorder(session)
    session.delete_clique(second)
    assert [c.id for c in session.correspondences.cliques] == [first]
    assert session.selected_clique is None
    assert recorder.count("selection_changed") == 1 and recorder.count("history_changed") == 1
    with pytest.raises(KeyError):
        session.delete_clique(second)
    assert len(session.history) == 3


# ---- status, note --------------------------------------------------------------------------------


def test_set_status_and_note_are_single_undoable_steps(session):
    clique_id = session.link([1], [1])
    session.set_status(clique_id, "rejected")
    assert session.correspondences.clique(clique_id).status == "rejected"
    assert session.undo_text == f"Reject clique {clique_id}"
    session.set_status(clique_id, "rejected")  # unchanged: no entry
    session.set_note(clique_id, "door looks wrong")
    assert session.correspondences.clique(clique_id).note == "door looks wrong"
    assert len(session.history) == 3
    session.undo()
    assert session.correspondences.clique(clique_id).note == ""
    with pytest.raises(ValueError, match="status"):
        session.set_status(clique_id, "maybe")
    with pytest.raises(KeyError):
        session.set_note(77, "x")


# ---- apply_match ---------------------------------------------------------------------------------


def test_apply_match_replaces_auto_cliques_and_keeps_manual_ones(session):
    manual = session.link([1], [1])
    session.set_note(manual, "mine")
    session.apply_match(fake_match([(1, 1), (2, 2), (3, 3)], anchors=[(2, 2)]))
    cliques = session.correspondences.cliques
    # (1, 1) is already the manual clique's pair: not proposed again.
    assert [(c.sketch_regions, c.metric_regions, c.source) for c in cliques] == [
        ((1,), (1,), "manual"),
        ((2,), (2,), "auto"),
        ((3,), (3,), "auto"),
    ]
    assert cliques[1].sketch_points == (interior(SKETCH_LABELS, 2),)
    assert all(c.effective_status == "pending" for c in cliques[1:])
    assert session.anchors == [(2, 2)] and session.last_match.pairs == [(1, 1), (2, 2), (3, 3)]
    assert session.undo_text == "Apply match (2 pairs)"

    after_first = session.correspondences
    session.apply_match(fake_match([(4, 4)]))
    cliques = session.correspondences.cliques
    assert [(c.sketch_regions, c.source, c.note) for c in cliques] == [((1,), "manual", "mine"), ((4,), "auto", "")]
    assert len(session.history) == 4
    session.undo()
    assert session.correspondences == after_first


def test_apply_match_records_what_produced_the_cliques_and_the_file_keeps_it(tmp_path):
    """As ``ursim match`` does, the file says which matcher made its automatic cliques and how it
    read the sketch, so that the app can offer that orientation when the file is opened again."""
    from ursim_core.matching import match
    from ursim_core.matching.results import match_record
    from ursim_gui.model.orientation import SketchOrientation

    author = write_document_files(tmp_path / "doc")
    result = match(author.segmentation("sketch"), author.segmentation("metric"))
    author.apply_match(result)
    record = author.correspondences.extra["matcher"]
    assert record == match_record(result.config, result)
    assert SketchOrientation.found_in_record(record) == SketchOrientation.found_in(result) is not None
    # Every reading ranked, as the result has them (the file's gaps to six decimals).
    from_file, from_result = SketchOrientation.readings_in(record=record), SketchOrientation.readings_in(result)
    assert len(from_result) > 1 and [r for r, _ in from_file] == [r for r, _ in from_result]
    assert [gap for _, gap in from_file] == pytest.approx([gap for _, gap in from_result], abs=1e-6)
    author.undo()
    assert "matcher" not in author.correspondences.extra  # the record is part of the edit
    author.redo()
    author.save(tmp_path / "doc" / "pair.json")
    session = AnnotationSession(timestamp=lambda: NOW)
    session.open(tmp_path / "doc" / "pair.json")
    assert session.correspondences.extra["matcher"] == record and session.last_match is None


def test_apply_match_records_the_matcher_score_of_each_pair(session):
    scores = np.arange(81, dtype=float).reshape(9, 9)
    session.apply_match(types.SimpleNamespace(pairs=[(2, 3)], anchors=[], c_matrix=scores))
    assert session.correspondences.cliques[0].score == scores[1, 2]


def test_apply_match_refuses_a_stale_result(session):
    with pytest.raises(ValueError, match="re-segmented"):
        session.apply_match(fake_match([(1, 42)]))
    assert session.correspondences.cliques == () and session.last_match is None


def test_apply_match_without_new_cliques_still_refreshes_views(session):
    session.link([1], [1])
    recorder = Recorder(session)
    session.apply_match(fake_match([(1, 1)], anchors=[(1, 1)]))
    assert len(session.history) == 1
    assert recorder.count("correspondences_changed") == 1 and session.anchors == [(1, 1)]
