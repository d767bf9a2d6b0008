"""Autosave: debouncing with an injected clock, file content, recovery, removal."""

from __future__ import annotations

import os
import time

import cv2
import numpy as np
import pytest
from conftest import simulate_crash

from ursim_core.correspondences import load_correspondences
from ursim_core.segmentation import Segmentation, load_label_image, save_label_image
from ursim_core.segmentation.graph import region_graph
from ursim_gui.model.autosave import (
    AUTOSAVE_SUFFIX,
    Autosaver,
    default_autosave_folder,
    discard,
    find_recoverable,
    recover,
    recover_with_origin,
)
from ursim_gui.model.session import AnnotationSession


def rooms_labels() -> np.ndarray:
    """Four rooms in a 2x2 grid."""
    labels = np.zeros((50, 50), np.int32)
    labels[2:24, 2:24] = 1
    labels[2:24, 26:48] = 2
    labels[26:48, 2:24] = 3
    labels[26:48, 26:48] = 4
    return labels


class Clock:
    """Time the test sets by hand."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


@pytest.fixture
def files(tmp_path):
    """A map and a label image on disk, for documents that can be reopened."""
    labels = rooms_labels()
    cv2.imwrite(str(tmp_path / "rooms.png"), np.where(labels > 0, 255, 0).astype(np.uint8))
    save_label_image(Segmentation(labels=labels, graph=region_graph(labels)), tmp_path / "rooms-labels.png")
    return tmp_path


def make_session(files) -> AnnotationSession:
    session = AnnotationSession(timestamp=lambda: "2024-05-01T12:00:00Z")
    for side in ("sketch", "metric"):
        session.load_map(side, files / "rooms.png")
        session.set_segmentation(side, load_label_image(files / "rooms-labels.png", shape=(50, 50)))
    return session


@pytest.fixture
def clock():
    return Clock()


@pytest.fixture
def autosave_dir(tmp_path):
    return tmp_path / "autosave"


def test_the_copy_is_written_only_after_a_quiet_delay(files, clock, autosave_dir):
    session = make_session(files)
    saver = Autosaver(session, autosave_dir, delay_s=2.0, clock=clock)
    session.link([1], [2])
    assert saver.pending
    clock.now += 1.9
    assert saver.flush_if_due(clock.now) is False and not saver.path.exists()
    session.link([2], [1])  # a new edit restarts the delay
    clock.now += 1.9
    assert saver.flush_if_due(clock.now) is False
    clock.now += 0.1
    assert saver.flush_if_due(clock.now) is True
    assert saver.path.is_file() and not saver.pending
    assert saver.flush_if_due(clock.now + 10) is False  # nothing new


def test_a_stream_of_edits_is_saved_after_max_delay(files, clock, autosave_dir):
    session = make_session(files)
    saver = Autosaver(session, autosave_dir, delay_s=2.0, max_delay_s=5.0, clock=clock)
    for step in range(6):
        session.link([1 + step % 4], [1 + (step + 1) % 4])
        assert saver.flush_if_due(clock.now) is (step == 5)
        clock.now += 1.0


def test_mark_dirty_takes_the_time_explicitly(files, autosave_dir):
    session = make_session(files)
    saver = Autosaver(session, autosave_dir, delay_s=2.0, clock=lambda: pytest.fail("clock must not be read"))
    saver.mark_dirty(10.0)
    assert not saver.due(11.9) and saver.due(12.0)


def test_the_copy_holds_the_correspondences_and_the_document_path(files, clock, autosave_dir):
    session = make_session(files)
    session.link([1], [2])
    session.save(files / "doc.json")
    session.link([3], [4])
    saver = Autosaver(session, autosave_dir, clock=clock)
    saver.mark_dirty(clock.now)
    saver.flush_if_due(clock.now + 2)

    assert saver.path.name.startswith("doc-") and saver.path.name.endswith(AUTOSAVE_SUFFIX)
    raw = recover(saver.path)
    assert raw.extra == {"autosave_of": str(files / "doc.json")}
    corr, origin = recover_with_origin(saver.path)
    assert corr == session.correspondences and origin == files / "doc.json"
    assert find_recoverable(autosave_dir) == []  # its session still runs: not a crash copy
    simulate_crash(saver)
    assert find_recoverable(autosave_dir) == [saver.path]


def test_recovery_reopens_the_maps_and_is_dirty(files, clock, autosave_dir):
    session = make_session(files)
    session.link([1], [2])
    session.save(files / "doc.json")
    session.link([3], [4])
    saver = Autosaver(session, autosave_dir, clock=clock)
    saver.flush()
    expected = session.correspondences
    simulate_crash(saver)
    del session, saver  # the "crash"

    (path,) = find_recoverable(autosave_dir)
    recovered = AnnotationSession()
    recovered.restore(recover(path))
    assert recovered.correspondences == expected
    assert "autosave_of" not in recovered.correspondences.extra
    assert recovered.path == files / "doc.json" and recovered.dirty
    assert recovered.map("sketch").shape == (50, 50)
    assert recovered.segmentation("metric").n_regions == 4
    recovered.undo()  # recovery starts a fresh history
    assert recovered.correspondences == expected


def test_recovering_an_untitled_document(files, clock, autosave_dir):
    session = make_session(files)
    session.link([4], [4])
    saver = Autosaver(session, autosave_dir, clock=clock)
    saver.flush()
    assert saver.path.name.startswith("untitled-")
    corr, origin = recover_with_origin(saver.path)
    assert origin is None
    recovered = AnnotationSession()
    recovered.restore(corr)
    assert recovered.path is None and recovered.dirty
    assert recovered.correspondences == session.correspondences


def test_the_copy_is_removed_on_save_on_undo_to_saved_and_on_close(files, clock, autosave_dir):
    session = make_session(files)
    saver = Autosaver(session, autosave_dir, clock=clock)
    session.link([1], [1])
    saver.flush()
    untitled_copy = saver.path
    session.save(files / "doc.json")
    assert not untitled_copy.exists() and find_recoverable(autosave_dir) == []

    session.link([2], [2])
    saver.flush()
    assert saver.path.exists()
    session.undo()  # back to the saved state: nothing to recover
    assert find_recoverable(autosave_dir) == []

    session.redo()
    saver.flush()
    assert saver.path.exists() and find_recoverable(autosave_dir) == []  # running, not crashed
    saver.close()
    assert find_recoverable(autosave_dir) == []
    session.link([3], [3])  # no longer watched
    assert not saver.pending
    saver.close()  # idempotent


def test_save_as_moves_the_copy_to_the_new_name(files, clock, autosave_dir):
    session = make_session(files)
    session.link([1], [1])
    session.save(files / "first.json")
    saver = Autosaver(session, autosave_dir, clock=clock)
    session.link([2], [2])
    saver.flush()
    old_copy = saver.path
    # A failed save to a new name keeps the old copy: it still protects the edit.
    with pytest.raises(OSError):
        session.save(files / "missing-folder" / "x.json")
    assert old_copy.exists()
    session.save(files / "second.json")
    assert not old_copy.exists() and find_recoverable(autosave_dir) == []


def test_a_clean_document_writes_no_copy(files, clock, autosave_dir):
    session = make_session(files)
    saver = Autosaver(session, autosave_dir, clock=clock)
    saver.mark_dirty(clock.now)
    assert saver.flush_if_due(clock.now + 5) is True
    assert not autosave_dir.exists() or find_recoverable(autosave_dir) == []


def test_a_failed_write_raises_and_backs_off(files, clock, tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the folder should be", encoding="utf-8")
    session = make_session(files)
    saver = Autosaver(session, blocker, delay_s=2.0, clock=clock)
    session.link([1], [1])
    clock.now += 2
    with pytest.raises(OSError):
        saver.flush_if_due(clock.now)
    assert saver.pending
    assert saver.flush_if_due(clock.now + 1) is False  # waits another delay before retrying
    with pytest.raises(OSError):
        saver.flush_if_due(clock.now + 2)


def test_find_recoverable_sorts_newest_first_and_tolerates_a_missing_folder(tmp_path):
    assert find_recoverable(tmp_path / "nowhere") == []
    older, newer = tmp_path / f"a{AUTOSAVE_SUFFIX}", tmp_path / f"b{AUTOSAVE_SUFFIX}"
    for path in (older, newer):
        path.write_text("{}", encoding="utf-8")
    (tmp_path / "notes.json").write_text("{}", encoding="utf-8")
    os.utime(older, (time.time() - 100, time.time() - 100))
    assert find_recoverable(tmp_path) == [newer, older]
    discard(newer)
    discard(newer)  # already gone: fine
    assert find_recoverable(tmp_path) == [older]


def test_recover_of_a_broken_file_raises_a_format_error(tmp_path):
    from ursim_core.errors import FormatError

    broken = tmp_path / f"x{AUTOSAVE_SUFFIX}"
    broken.write_text("{", encoding="utf-8")
    with pytest.raises(FormatError, match="x.autosave.json"):
        recover(broken)


def test_default_folder_precedence(monkeypatch, tmp_path):
    monkeypatch.setenv("URSIM_AUTOSAVE_DIR", str(tmp_path / "explicit"))
    monkeypatch.setenv("URSIM_GUI_DATA_DIR", str(tmp_path / "data"))
    assert default_autosave_folder() == tmp_path / "explicit"
    monkeypatch.delenv("URSIM_AUTOSAVE_DIR")
    assert default_autosave_folder() == tmp_path / "data" / "autosave"
    monkeypatch.delenv("URSIM_GUI_DATA_DIR")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    expected = {
        "linux": tmp_path / "xdg" / "ursim-studio" / "autosave",
        "darwin": tmp_path / "home" / "Library" / "Application Support" / "ursim-studio" / "autosave",
    }
    import sys

    if sys.platform in expected:
        assert default_autosave_folder() == expected[sys.platform]
    monkeypatch.setenv("URSIM_AUTOSAVE_DIR", str(tmp_path / "explicit"))
    session = AnnotationSession()
    assert Autosaver(session).folder == tmp_path / "explicit"


def test_the_copy_is_a_valid_correspondence_file(files, clock, autosave_dir):
    session = make_session(files)
    session.link([1, 2], [3])
    saver = Autosaver(session, autosave_dir, clock=clock)
    saver.flush()
    loaded = load_correspondences(saver.path)
    assert loaded.sketch.path == files / "rooms.png"
    assert loaded.cliques == session.correspondences.cliques


def test_a_crash_copy_of_the_same_document_is_not_removed_by_a_new_session(files, clock, autosave_dir):
    crashed = make_session(files)
    crashed.link([1], [1])
    crashed.save(files / "doc.json")
    crashed.link([2], [2])
    crashed_saver = Autosaver(crashed, autosave_dir, clock=clock)
    crashed_saver.flush()
    simulate_crash(crashed_saver)
    (crash_copy,) = find_recoverable(autosave_dir)

    # The user declined recovery for now and opens the document again.
    session = AnnotationSession()
    saver = Autosaver(session, autosave_dir, clock=clock)
    session.open(files / "doc.json")
    saver.flush_if_due(clock.now + 60)
    session.link([3], [3])
    saver.flush_if_due(clock.now + 120)
    assert saver.path != crash_copy and saver.path.exists()
    assert find_recoverable(autosave_dir) == [crash_copy]  # the running session's copy is not offered
    saver.close()
    assert find_recoverable(autosave_dir) == [crash_copy]
    assert recover_with_origin(crash_copy)[0] == crashed.correspondences
