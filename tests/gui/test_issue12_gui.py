"""Issue 12, GUI items: every autosave failure is caught and said once; a running session's
autosave is never offered as a crash copy (lock file with the owner's pid)."""

from __future__ import annotations

from conftest import error_boxes, simulate_crash

from ursim_gui.model import autosave
from ursim_gui.window import dialogs
from ursim_gui.window.main_window import MainWindow


def autosave_boxes(window):
    return [box for box in error_boxes(window) if box.windowTitle() == "Autosave failed"]


def test_any_autosave_failure_is_caught_and_said_once_per_streak(window, monkeypatch):
    documents = window.documents
    documents.autosave_timer.stop()
    documents.autosaver.delay_s = 0.0
    real_save = autosave.save_correspondences

    def refuse(*args, **kwargs):
        raise ValueError("Out of range float values are not JSON compliant")  # not an OSError

    monkeypatch.setattr(autosave, "save_correspondences", refuse)
    window.session.link([1], [1])
    documents.flush_autosave()
    documents.flush_autosave()  # still failing: no second box
    (box,) = autosave_boxes(window)
    assert "ValueError" in box.text() and "Save the document" in box.text()
    box.close()

    monkeypatch.setattr(autosave, "save_correspondences", real_save)
    window.session.link([2], [2])
    documents.flush_autosave()
    assert documents.autosaver.written_path is not None and not autosave_boxes(window)

    monkeypatch.setattr(autosave, "save_correspondences", refuse)
    window.session.link([3], [3])
    documents.flush_autosave()  # a new failing streak is said again
    assert len(autosave_boxes(window)) == 1


def test_a_running_sessions_autosave_is_not_offered_as_a_crash_copy(window, qtbot, tmp_path, monkeypatch):
    window.session.link([1], [1])
    window.documents.autosaver.flush()
    copy = window.documents.autosaver.written_path
    assert copy is not None and copy.is_file()

    offered = []
    monkeypatch.setattr(dialogs, "ask_recover", lambda parent, paths: offered.append(paths) or None)
    second = MainWindow(data_dir=tmp_path / "userdata")  # another window on the same data folder
    qtbot.addWidget(second)
    assert not second.documents.offer_recovery() and not offered

    simulate_crash(window.documents.autosaver)  # now its owner is gone
    third = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(third)
    third.documents.offer_recovery()
    assert offered == [[copy]]
    for extra in (second, third):
        extra.jobs.runner.shutdown()
        extra.documents.close_document()


def test_a_clean_close_removes_the_lock(window):
    autosaver = window.documents.autosaver
    lock = autosaver.folder / f"{autosaver._instance_id}{autosave.LOCK_SUFFIX}"
    assert lock.read_text().split()[0].isdigit()
    window.documents.close_document()
    assert not lock.exists()
