"""Document operations of the session (ursim_gui.model.session_documents): save, open, .dat import and export."""

from __future__ import annotations

import json
import os

import cv2
import numpy as np
import pytest
from conftest import METRIC_LABELS, NOW, SKETCH_LABELS, Recorder, fake_match, map_of, seg_of, write_document_files

from ursim_core.correspondences import (
    Correspondences,
    MapRef,
    load_correspondences,
    load_dat,
    save_correspondences,
)
from ursim_core.errors import FormatError, MapError, UrsimError
from ursim_core.segmentation import save_label_image
from ursim_gui.model.jobs import SegmentJob
from ursim_gui.model.session import AnnotationSession

# ---- save ----------------------------------------------------------------------------------------


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


# ---- open ----------------------------------------------------------------------------------------


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


def test_a_reopened_turned_sketch_is_segmented_in_its_resamplings_again(tmp_path):
    from ursim_core.evaluation.augment import Orientation, transform_image
    from ursim_core.synth import make_pair

    plan, _ = make_pair(seed=2)
    turned = transform_image(plan.free, Orientation(25.0))
    cv2.imwrite(str(tmp_path / "sketch.png"), np.where(turned, 255, 0).astype(np.uint8))
    cv2.imwrite(str(tmp_path / "plan.png"), np.where(plan.free, 255, 0).astype(np.uint8))
    author = AnnotationSession()
    author.load_map("sketch", tmp_path / "sketch.png")
    author.load_map("metric", tmp_path / "plan.png")
    for side in ("sketch", "metric"):
        job = SegmentJob(author.map(side), "default", None, side=side)
        author.set_segmentation(side, job.run(lambda *a: None, lambda: False))
    made = author.segmentation("sketch")
    assert len(made.resampled) == 5  # the planar matcher votes over six
    author.link([1], [1])
    author.save(tmp_path / "pair.json")

    session = AnnotationSession()
    session.open(tmp_path / "pair.json")
    reopened = session.segmentation("sketch")
    assert np.array_equal(reopened.labels, made.labels)
    assert [o.params for o in reopened.resampled] == [o.params for o in made.resampled]
    assert all(np.array_equal(a.labels, b.labels) for a, b in zip(reopened.resampled, made.resampled, strict=True))
    assert session.segmentation("metric").resampled == () and not session.dirty

    # Parameters edited by hand into ones that cannot segment: the document still opens, on its
    # label image, and says why matching it will use the one segmentation.
    document = json.loads((tmp_path / "pair.json").read_text(encoding="utf-8"))
    save_label_image(made, tmp_path / "sketch-labels.png")
    document["maps"]["sketch"]["segmentation"]["labels"] = "sketch-labels.png"
    document["maps"]["sketch"]["segmentation"]["params"]["doors"] = "x"
    (tmp_path / "edited.json").write_text(json.dumps(document), encoding="utf-8")
    recorder = Recorder(session)
    session.open(tmp_path / "edited.json")
    assert np.array_equal(session.segmentation("sketch").labels, made.labels)
    assert session.segmentation("sketch").resampled == ()
    ((message,),) = recorder.calls["error"]
    assert "sketch.png" in message and "doors" in message and "one segmentation" in message
    session.save(tmp_path / "again.json")  # what loads saves again
    assert load_correspondences(tmp_path / "again.json").cliques == session.correspondences.cliques


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


# ---- .dat import/export --------------------------------------------------------------------------


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
