"""Edited segmentations (ursim_gui.model.session_label_edits): saved beside the document and in the autosave copy."""

from __future__ import annotations

import json

import numpy as np

from ursim_core.correspondences import load_correspondences
from ursim_gui.model.session import AnnotationSession


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


def test_a_segmentation_edit_of_an_untitled_matched_pair_is_unsaved_work(session):
    # Untouched matcher output alone is not worth a question on closing (matching again gives
    # it back), but a merge is the person's work: it makes the document dirty, so it is asked
    # about and autosaved.
    from conftest import fake_match

    session.apply_match(fake_match([(1, 1), (2, 2)]))
    assert session.path is None and not session.dirty
    dirty = []
    session.dirty_changed.connect(dirty.append)
    assert session.merge_regions("sketch", 1, 2)
    assert session.dirty and dirty == [True]
    session.undo()
    assert not session.dirty


def test_a_drawn_sketch_is_saved_beside_the_document_and_reopens_with_it(session, tmp_path):
    from ursim_core.io.maps import load_map, map_from_array

    drawn = np.full((60, 80), 255, np.uint8)
    drawn[:, 40] = 0  # a wall: two rooms
    drawn[0, :] = drawn[-1, :] = drawn[:, 0] = drawn[:, -1] = 0
    session.new_document(keep=["metric"])
    session.set_map("sketch", map_from_array(drawn))
    # A drawing has no file: until the document is saved it exists only in the session.
    assert session.dirty

    document = tmp_path / "drawn.json"
    session.save(document)
    beside = tmp_path / "drawn.sketch.png"
    assert beside.is_file() and not session.dirty
    assert session.map("sketch").path == beside and session.correspondences.sketch.path == beside
    assert np.array_equal(load_map(beside).free, session.map("sketch").free)

    reopened = AnnotationSession()
    reopened.open(document)
    assert reopened.map("sketch").path == beside and not reopened.dirty
    assert np.array_equal(reopened.map("sketch").free, session.map("sketch").free)
    assert reopened.map("sketch").sha256 == session.map("sketch").sha256


def test_a_drawn_sketch_survives_a_crash_through_the_autosave_copy(session, tmp_path):
    from ursim_core.io.maps import map_from_array
    from ursim_gui.model.autosave import Autosaver, discard, recover

    drawn = np.full((50, 70), 255, np.uint8)
    drawn[0, :] = drawn[-1, :] = drawn[:, 0] = drawn[:, -1] = 0
    session.new_document(keep=["metric"])
    session.set_map("sketch", map_from_array(drawn))
    saver = Autosaver(session, tmp_path / "autosave")
    saver.flush()
    copy = saver.path
    drawing = copy.with_name(f"{copy.stem}.sketch.png")
    assert copy.is_file() and drawing.is_file()
    assert session.map("sketch").path is None  # the session is untouched: the copy only references it

    recovered = AnnotationSession()
    released = recovered.restore(recover(copy), autosave=copy)
    assert np.array_equal(recovered.map("sketch").free, session.map("sketch").free)
    # A drawing again: saved beside the document, never named in the autosave folder (the
    # recovered sketch's file was the copy's PNG, referenced by every later save).
    assert released == [drawing] and recovered.map("sketch").path is None and recovered.dirty
    discard(copy)
    assert not copy.exists() and not drawing.exists()
    document = tmp_path / "recovered.json"
    recovered.save(document)
    beside = tmp_path / "recovered.sketch.png"
    assert load_correspondences(document).sketch.path == beside and beside.is_file()
    reopened = AnnotationSession()
    reopened.open(document)
    assert np.array_equal(reopened.map("sketch").free, session.map("sketch").free)
    saver.close()
