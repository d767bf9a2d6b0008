"""AnnotationSession: every operation, undo/redo, dirty tracking, files, evaluation, jobs."""

from __future__ import annotations

import dataclasses
import os
import types

import cv2
import numpy as np
import pytest

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
)
from ursim_core.errors import FormatError, MapError, SegmentationError, UrsimError
from ursim_core.io.maps import map_from_array
from ursim_core.segmentation import Segmentation, load_label_image, save_label_image
from ursim_core.segmentation.graph import region_graph
from ursim_gui.model.jobs import JobCancelled, MatchJob, SegmentJob
from ursim_gui.model.session import AnnotationSession, color_of_clique

NOW = "2024-05-01T12:00:00Z"


# --------------------------------------------------------------------------- builders


def grid_labels(n_rows: int = 3, n_cols: int = 3, *, room: int = 20, wall: int = 2) -> np.ndarray:
    """Rooms 1..n_rows*n_cols in raster order, separated by walls (0)."""
    labels = np.zeros((n_rows * room + (n_rows + 1) * wall, n_cols * room + (n_cols + 1) * wall), np.int32)
    for index in range(n_rows * n_cols):
        row, col = divmod(index, n_cols)
        top, left = wall + row * (room + wall), wall + col * (room + wall)
        labels[top : top + room, left : left + room] = index + 1
    return labels


def seg_of(labels: np.ndarray, *, source=None) -> Segmentation:
    return Segmentation(labels=labels, graph=region_graph(labels), method="label-image", source=source)


def map_of(labels: np.ndarray, *, path=None):
    return map_from_array(np.where(labels > 0, 255, 0).astype(np.uint8), path=path)


def interior(labels: np.ndarray, region: int) -> tuple[int, int]:
    return region_graph(labels).nodes[region]["interior"]


class Recorder:
    """Counts the emissions of every session signal."""

    NAMES = (
        "map_changed",
        "segmentation_changed",
        "correspondences_changed",
        "selection_changed",
        "dirty_changed",
        "path_changed",
        "reference_changed",
        "history_changed",
        "error",
    )

    def __init__(self, session):
        self.calls = {name: [] for name in self.NAMES}
        for name in self.NAMES:
            getattr(session, name).connect(lambda *args, name=name: self.calls[name].append(args))

    def count(self, name):
        return len(self.calls[name])

    def reset(self):
        for calls in self.calls.values():
            calls.clear()


SKETCH_LABELS = grid_labels(room=20)
METRIC_LABELS = grid_labels(room=30)


@pytest.fixture
def session():
    session = AnnotationSession(annotator="tester", timestamp=lambda: NOW)
    session.set_map("sketch", map_of(SKETCH_LABELS))
    session.set_map("metric", map_of(METRIC_LABELS))
    session.set_segmentation("sketch", seg_of(SKETCH_LABELS))
    session.set_segmentation("metric", seg_of(METRIC_LABELS))
    return session


def write_document_files(folder, *, label_images: bool = True):
    """Map PNGs (and label images) of the grid pair in ``folder``; returns a ready session."""
    folder.mkdir(parents=True, exist_ok=True)
    session = AnnotationSession(timestamp=lambda: NOW)
    for side, labels in (("sketch", SKETCH_LABELS), ("metric", METRIC_LABELS)):
        cv2.imwrite(str(folder / f"{side}.png"), np.where(labels > 0, 255, 0).astype(np.uint8))
        session.load_map(side, folder / f"{side}.png")
        if label_images:
            save_label_image(seg_of(labels), folder / f"{side}-labels.png")
            session.set_segmentation(side, load_label_image(folder / f"{side}-labels.png", shape=labels.shape))
        else:
            session.set_segmentation(side, seg_of(labels))
    return session


def fake_match(pairs, *, anchors=()):
    """The parts of a MatchResult the session reads."""
    return types.SimpleNamespace(pairs=list(pairs), anchors=list(anchors), c_matrix=None)


# --------------------------------------------------------------------------- link


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


# --------------------------------------------------------------------------- unlink, delete


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


# --------------------------------------------------------------------------- status, note


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


# --------------------------------------------------------------------------- apply_match


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


# --------------------------------------------------------------------------- undo / redo


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


# --------------------------------------------------------------------------- dirty, save, title


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


def test_save_load_round_trip_is_exact(session, tmp_path):
    session.link([1, 2], [1])
    session.apply_match(fake_match([(5, 5)]))
    session.set_note(1, "naïve note ✓")
    session.set_status(2, "rejected")
    session.save(tmp_path / "out.json")
    loaded = load_correspondences(tmp_path / "out.json")
    assert loaded == session.correspondences
    assert loaded.created == loaded.modified == NOW and loaded.annotator == "tester"


def test_save_without_a_path_needs_one():
    with pytest.raises(ValueError, match="give a path"):
        AnnotationSession().save()


def test_failed_save_into_a_missing_folder_stays_dirty(session, tmp_path):
    session.link([1], [1])
    recorder = Recorder(session)
    with pytest.raises(OSError):
        session.save(tmp_path / "no-such-folder" / "pair.json")
    assert session.dirty and session.path is None
    assert recorder.count("dirty_changed") == 0 and recorder.count("path_changed") == 0


def test_failed_save_keeps_the_old_file_intact(session, tmp_path, monkeypatch):
    target = tmp_path / "pair.json"
    session.link([1], [1])
    session.save(target)
    old_bytes = target.read_bytes()
    session.link([2], [2])
    edited = session.correspondences

    def refuse(*_args, **_kwargs):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OSError, match="Read-only"):
        session.save()
    monkeypatch.undo()
    assert target.read_bytes() == old_bytes
    assert session.dirty and session.correspondences == edited and session.path == target
    assert [p.name for p in tmp_path.iterdir()] == ["pair.json"]  # no temporary left behind


def test_saving_again_keeps_created_and_updates_modified(session, tmp_path):
    times = iter(["2024-05-01T12:00:00Z", "2024-06-01T08:00:00Z"])
    session = AnnotationSession(timestamp=lambda: next(times))
    session.set_map("sketch", map_of(SKETCH_LABELS))
    session.set_segmentation("sketch", seg_of(SKETCH_LABELS))
    session.link([1], [])
    session.save(tmp_path / "a.json")
    session.link([2], [])
    session.save()
    loaded = load_correspondences(tmp_path / "a.json")
    assert (loaded.created, loaded.modified) == ("2024-05-01T12:00:00Z", "2024-06-01T08:00:00Z")
    session.undo()
    session.redo()
    assert not session.dirty


# --------------------------------------------------------------------------- open


def test_open_loads_maps_label_images_and_clears_history(tmp_path):
    author = write_document_files(tmp_path / "doc")
    author.link([1], [1])
    author.link([5, 6], [5])
    author.save(tmp_path / "doc" / "pair.json")

    session = AnnotationSession(timestamp=lambda: NOW)
    session.open(tmp_path / "doc" / "pair.json")
    assert session.correspondences == author.correspondences
    assert not session.dirty and not session.can_undo
    assert session.path == tmp_path / "doc" / "pair.json"
    for side, labels in (("sketch", SKETCH_LABELS), ("metric", METRIC_LABELS)):
        assert session.map(side).shape == labels.shape
        assert np.array_equal(session.segmentation(side).labels, labels)
        assert session.segmentation(side).method == "label-image"


def test_open_resolves_paths_relative_to_the_json_after_moving_the_folder(tmp_path):
    author = write_document_files(tmp_path / "doc")
    author.link([2], [3])
    author.save(tmp_path / "doc" / "pair.json")
    (tmp_path / "doc").rename(tmp_path / "moved")
    session = AnnotationSession()
    session.open(tmp_path / "moved" / "pair.json")
    assert session.map("sketch").path == tmp_path / "moved" / "sketch.png"
    assert session.correspondences.cliques[0].metric_regions == (3,)


def test_open_segments_when_the_label_image_is_missing(tmp_path):
    free = np.zeros((60, 130), np.uint8)
    free[5:55, 5:60] = 255
    free[5:55, 70:125] = 255
    free[27:33, 60:70] = 255
    cv2.imwrite(str(tmp_path / "two.png"), free)
    author = AnnotationSession()
    author.load_map("sketch", tmp_path / "two.png")
    author.load_map("metric", tmp_path / "two.png")
    for side in ("sketch", "metric"):
        author.set_segmentation(side, SegmentJob(author.map(side), "default", None).run(lambda *a: None, lambda: False))
    author.link([1], [2])
    author.save(tmp_path / "pair.json")
    assert load_correspondences(tmp_path / "pair.json").sketch.labels_path is None

    session = AnnotationSession()
    session.open(tmp_path / "pair.json")
    assert session.segmentation("sketch").method == "maoris"
    assert session.segmentation("sketch").n_regions == 2
    assert session.correspondences == author.correspondences and not session.dirty


def test_open_errors_leave_the_session_unchanged(session, tmp_path):
    session.link([1], [1])
    before = (session.correspondences, session.map("sketch"), session.segmentation("metric"), len(session.history))
    recorder = Recorder(session)

    (tmp_path / "bad.json").write_text("{not json", encoding="utf-8")
    with pytest.raises(FormatError, match="bad.json"):
        session.open(tmp_path / "bad.json")

    document = Correspondences(sketch=MapRef(path=tmp_path / "gone.png"), metric=MapRef(path=tmp_path / "gone.png"))
    save_correspondences(document, tmp_path / "dangling.json")
    with pytest.raises(MapError) as error:
        session.open(tmp_path / "dangling.json")
    assert "gone.png" in str(error.value) and "dangling.json" in str(error.value)

    after = (session.correspondences, session.map("sketch"), session.segmentation("metric"), len(session.history))
    assert after == before
    assert sum(recorder.count(name) for name in Recorder.NAMES) == 0


def test_open_refuses_a_map_of_another_size(tmp_path):
    author = write_document_files(tmp_path)
    author.link([1], [1])
    author.save(tmp_path / "pair.json")
    cv2.imwrite(str(tmp_path / "sketch.png"), np.full((10, 10), 255, np.uint8))
    with pytest.raises(MapError, match="10x10"):
        AnnotationSession().open(tmp_path / "pair.json")


def test_open_warns_when_a_map_changed_since_saving(tmp_path):
    author = write_document_files(tmp_path)
    author.link([1], [1])
    author.save(tmp_path / "pair.json")
    changed = np.where(SKETCH_LABELS > 0, 255, 0).astype(np.uint8)
    changed[0, 0] = 255
    cv2.imwrite(str(tmp_path / "sketch.png"), changed)
    session = AnnotationSession()
    messages = []
    session.error.connect(messages.append)
    session.open(tmp_path / "pair.json")
    assert len(messages) == 1 and "changed" in messages[0]


# --------------------------------------------------------------------------- maps and re-segmentation


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


# --------------------------------------------------------------------------- evaluation


def write_reference(tmp_path):
    """Reference: sketch room r matches metric room r, for rooms 1..4."""
    cliques = tuple(
        Clique(id=r, sketch_points=[interior(SKETCH_LABELS, r)], metric_points=[interior(METRIC_LABELS, r)])
        for r in (1, 2, 3, 4)
    )
    save_correspondences(Correspondences(cliques=cliques), tmp_path / "reference.json")
    return tmp_path / "reference.json"


def test_evaluation_follows_edits_and_the_reference(session, tmp_path):
    right = session.link([1], [1])
    wrong = session.link([2], [3])
    assert session.evaluation is None and session.clique_status(right) is None
    recorder = Recorder(session)
    session.load_reference(write_reference(tmp_path))
    assert recorder.count("reference_changed") == 1
    assert session.reference[0] == (frozenset({1}), frozenset({1}))
    score = session.evaluation
    assert (score.tp, score.fp, score.fn) == (1, 1, 3)
    assert session.clique_status(right) == "tp" and session.clique_status(wrong) == "fp"
    assert session.missed_reference() == [1, 2, 3]

    session.link([2], [2])
    assert (session.evaluation.tp, session.evaluation.fp, session.evaluation.fn) == (2, 1, 2)
    session.set_status(wrong, "rejected")
    assert session.evaluation.fp == 0 and session.clique_status(wrong) is None
    session.undo()
    assert session.evaluation.fp == 1

    session.clear_reference()
    assert session.evaluation is None and session.reference is None and session.missed_reference() == []


def test_a_clique_with_one_wrong_pair_is_marked_fp(session, tmp_path):
    session.load_reference(write_reference(tmp_path))
    mixed = session.link([1, 2], [1])
    assert session.clique_status(mixed) == "fp"


def test_dat_reference_regions_follow_the_current_segmentation(session, tmp_path):
    reference = load_correspondences(write_reference(tmp_path))
    save_dat(reference, tmp_path / "reference.dat")
    session.load_reference(tmp_path / "reference.dat")
    session.link([1], [1])
    assert session.evaluation.tp == 1
    renumbered = np.where(SKETCH_LABELS > 0, 10 - SKETCH_LABELS, 0).astype(np.int32)
    session.set_segmentation("sketch", seg_of(renumbered))
    assert session.reference[0] == (frozenset({9}), frozenset({1}))
    assert session.evaluation.tp == 1  # the clique's ids moved with the points too


# --------------------------------------------------------------------------- queries and selection


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


def test_selection_rules_and_signals(session):
    clique_id = session.link([1, 2], [5])
    recorder = Recorder(session)
    session.select_clique(clique_id)
    assert session.selection == {"sketch": frozenset({1, 2}), "metric": frozenset({5})}
    session.select("sketch", [4], add=True)  # extend the clique's selection, keep the clique
    assert session.selected_clique == clique_id and session.selection["sketch"] == frozenset({1, 2, 4})
    session.select("metric", [6])  # a plain click starts a new selection
    assert session.selected_clique is None and session.selection["metric"] == frozenset({6})
    session.select("metric", [6])  # unchanged: no signal
    session.clear_selection()
    session.clear_selection()
    assert session.selection == {"sketch": frozenset(), "metric": frozenset()}
    assert recorder.count("selection_changed") == 4
    with pytest.raises(KeyError):
        session.select_clique(99)


# --------------------------------------------------------------------------- .dat import/export


def test_dat_export_then_import_round_trips_the_cliques(session, tmp_path):
    session.link([1], [1])
    session.link([2, 3], [4])
    expected = [
        (c.sketch_points, c.metric_points, c.sketch_regions, c.metric_regions) for c in session.correspondences.cliques
    ]
    session.export_dat(tmp_path / "pair.dat")
    assert len(load_dat(tmp_path / "pair.dat").cliques) == 2

    session.delete_clique(1)
    session.delete_clique(2)
    session.import_dat(tmp_path / "pair.dat")
    got = [
        (c.sketch_points, c.metric_points, c.sketch_regions, c.metric_regions) for c in session.correspondences.cliques
    ]
    assert got == expected
    assert session.undo_text == "Import pair.dat"
    session.undo()
    assert session.correspondences.cliques == ()


def test_import_of_a_broken_dat_raises_and_changes_nothing(session, tmp_path):
    (tmp_path / "broken.dat").write_text("not a dat file\n", encoding="utf-8")
    with pytest.raises(UrsimError, match="broken.dat"):
        session.import_dat(tmp_path / "broken.dat")
    assert len(session.history) == 0


# --------------------------------------------------------------------------- jobs feed the session


def test_segment_job_reports_progress_and_its_result_feeds_the_session():
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    reports = []
    job = SegmentJob(map_from_array(free), "default", {"doors": 40}, side="metric")
    segmentation = job.run(lambda fraction, message: reports.append(fraction), lambda: False)
    assert segmentation.n_regions == 2 and segmentation.params["doors"] == 40
    assert reports[0] == 0.0 and reports[-1] == 1.0 and reports == sorted(reports)
    assert job.description == "Segmenting metric (preset default)"
    session = AnnotationSession()
    session.set_map("metric", map_from_array(free))
    session.set_segmentation(job.side, segmentation)
    assert session.correspondences.metric.segmentation_params["doors"] == 40


def test_segment_job_checks_parameters_before_the_long_step():
    with pytest.raises(UrsimError, match="preset"):
        SegmentJob(np.ones((10, 10), bool), "no-such-preset", None).run(lambda *a: None, lambda: False)


def test_jobs_raise_job_cancelled_between_steps():
    free = np.ones((20, 20), bool)
    with pytest.raises(JobCancelled):
        SegmentJob(free, "default", None).run(lambda *a: None, lambda: True)
    # Cancelled during the long step: the finished result is not returned.
    polls = []

    def cancel_after_first_polls():
        polls.append(1)
        return len(polls) > 2

    with pytest.raises(JobCancelled):
        SegmentJob(free, "default", None).run(lambda *a: None, cancel_after_first_polls)
    assert len(polls) == 3


def test_match_job_result_applies_to_the_session(session):
    pytest.importorskip("ursim_core.matching", reason="ursim_core.matching is not available yet")
    from ursim_core.matching import MatchConfig

    reports = []
    job = MatchJob(session.segmentation("sketch"), session.segmentation("metric"), MatchConfig())
    result = job.run(lambda fraction, message: reports.append((fraction, message)), lambda: False)
    assert reports[0][0] == 0.0 and reports[-1][0] == 1.0
    session.apply_match(result)
    auto = [c for c in session.correspondences.cliques if c.source == "auto"]
    assert auto, "two identical 3x3 grids must give some match"
    assert [(c.sketch_regions[0], c.metric_regions[0]) for c in auto] == list(dict.fromkeys(result.pairs))
    with pytest.raises(JobCancelled):
        MatchJob(session.segmentation("sketch"), session.segmentation("metric")).run(lambda *a: None, lambda: True)


def test_match_config_defaults_to_the_core_defaults(session):
    matching = pytest.importorskip("ursim_core.matching", reason="ursim_core.matching is not available yet")
    assert session.match_config == matching.MatchConfig()
    custom = dataclasses.replace(matching.MatchConfig(), m=0.1)
    session.match_config = custom
    assert session.match_config is custom


def _cancelled_during_the_sweep(session, config) -> int:
    """Run a match job that is cancelled at its sixth poll; the number of polls."""
    polls = []

    def cancel_during_the_sweep():
        polls.append(1)
        return len(polls) > 5

    with pytest.raises(JobCancelled):
        MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
            lambda *a: None, cancel_during_the_sweep
        )
    return len(polls)


def test_match_job_with_automatic_m_reports_each_m_and_cancels_between_them(session):
    from ursim_core.matching import MatchConfig

    fields = {field.name for field in dataclasses.fields(MatchConfig)}
    # One orientation: the sweep of m is then one matcher run per m of the grid.
    config = MatchConfig(m="auto", **({"orientation": "upright", "mirrored": False} if "orientation" in fields else {}))
    reports = []
    MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
        lambda fraction, message: reports.append((fraction, message)), lambda: False
    )
    fractions = [fraction for fraction, _ in reports]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    steps = [message for _, message in reports if message.startswith("matching at m = ")]
    assert len(steps) == len(config.m_grid)

    assert _cancelled_during_the_sweep(session, config) == 6


def test_a_large_pair_shares_its_sweeps_with_the_helper_process_and_a_cancel_stops_it(session, monkeypatch):
    from ursim_core.matching import MatchConfig, sweep_helper

    config = MatchConfig(m="auto")
    alone = MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
        lambda *a: None, lambda: False
    )
    # Every pair counts as building-sized: the job must start the helper and hand it values of m.
    monkeypatch.setattr(sweep_helper, "MIN_REGIONS", 0)
    shared_calls, closed = [], []
    share, close = sweep_helper.Helper.share, sweep_helper.Helper.close
    monkeypatch.setattr(
        sweep_helper.Helper, "share", lambda self, *a, **k: shared_calls.append(1) or share(self, *a, **k)
    )
    monkeypatch.setattr(sweep_helper.Helper, "close", lambda self: closed.append(1) or close(self))
    shared = MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
        lambda *a: None, lambda: False
    )
    assert shared_calls, "the sweeps ran without the helper"
    assert (shared.pairs, shared.m, shared.cost, shared.orientation) == (
        alone.pairs,
        alone.m,
        alone.cost,
        alone.orientation,
    )
    assert closed == [1] and sweep_helper._ACTIVE is None

    _cancelled_during_the_sweep(session, config)
    assert closed == [1, 1] and sweep_helper._ACTIVE is None  # the helper went with the cancel


def test_a_second_session_on_the_same_file_does_not_silently_drop_the_first_ones_work(tmp_path):
    """Issue 12 item 3: the second session's save raises FileChangedError instead of overwriting."""
    import dataclasses

    from ursim_core.correspondences import load_correspondences, save_correspondences
    from ursim_core.errors import FileChangedError
    from ursim_gui.model.session import AnnotationSession

    path = tmp_path / "shared.json"
    AnnotationSession().save(path)
    second = AnnotationSession()
    second.open(path)
    # Another session (or program) writes the file: here, a new annotator name.
    changed = dataclasses.replace(load_correspondences(path), annotator="someone else")
    save_correspondences(changed, path)
    written = path.read_bytes()
    with pytest.raises(FileChangedError):
        second.save()
    assert path.read_bytes() == written and second.path == path
    second.save(overwrite_changed=True)  # the user chose to overwrite
    assert load_correspondences(path).modified is not None
    second.save()  # its digest is the one it wrote: no question now
    reopened = AnnotationSession()
    reopened.open(path)
    reopened.save()


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
