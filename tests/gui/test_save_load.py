"""Feature 9: save / save as / open, .dat import and export, the dirty title, the close
question, failed saves, autosave and recovery."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from conftest import error_boxes, simulate_crash
from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QApplication, QMessageBox

from ursim_core.correspondences import load_correspondences, load_dat
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs
from ursim_gui.window.main_window import MainWindow


def save_to(monkeypatch, path):
    monkeypatch.setattr(file_dialogs, "ask_save_path", lambda *a, **k: Path(str(path)))


def test_ctrl_s_saves_and_the_title_tracks_dirty(window, qtbot, tmp_path, monkeypatch):
    window.session.link([1], [1])
    assert window.windowTitle().endswith("untitled*")
    target = tmp_path / "out.json"
    save_to(monkeypatch, target)
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)
    assert load_correspondences(target).cliques[0].sketch_regions == (1,)
    assert window.windowTitle().endswith("out.json")
    window.session.link([2], [2])
    assert window.windowTitle().endswith("out.json*")
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)  # no dialog now
    assert len(load_correspondences(target).cliques) == 2 and not window.session.dirty
    other = tmp_path / "copy.json"
    save_to(monkeypatch, other)
    qtbot.keyClick(
        window.views["sketch"], Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier
    )
    assert other.is_file() and window.session.path == other


def test_failed_save_shows_an_error_and_stays_dirty(window, tmp_path, monkeypatch):
    window.session.link([1], [1])
    save_to(monkeypatch, tmp_path / "missing-folder" / "out.json")
    window.actions["save"].trigger()
    boxes = error_boxes(window)
    assert boxes and "missing-folder" in boxes[0].text()
    assert window.session.dirty and window.windowTitle().endswith("*")
    from ursim_gui.model import session_documents as session_module

    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(session_module, "save_correspondences", disk_full)
    save_to(monkeypatch, tmp_path / "out.json")
    window.actions["save_as"].trigger()
    assert "No space left" in error_boxes(window)[-1].text()
    assert window.session.dirty and window.session.path is None


def test_dat_export_and_import(window, tmp_path, monkeypatch):
    window.session.link([1], [3])
    dat = tmp_path / "out.dat"
    save_to(monkeypatch, dat)
    window.actions["export_dat"].trigger()
    assert len(load_dat(dat).cliques) == 1
    window.session.delete_clique(window.session.correspondences.cliques[0].id)
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(dat)))
    window.actions["import_dat"].trigger()
    (clique,) = window.session.correspondences.cliques
    assert (clique.sketch_regions, clique.metric_regions) == ((1,), (3,))


@pytest.mark.parametrize("answer, closed", [("cancel", False), ("discard", True)])
def test_closing_with_unsaved_changes_asks(window, monkeypatch, answer, closed):
    asked = []
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: asked.append(what) or answer)
    window.session.link([1], [1])
    window.close()
    assert asked == ["closing"]
    assert window.isVisible() is not closed


def test_close_question_save_choice_saves(window, tmp_path, monkeypatch):
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: "save")
    save_to(monkeypatch, tmp_path / "saved.json")
    window.session.link([1], [1])
    window.close()
    assert (tmp_path / "saved.json").is_file() and not window.isVisible()


def test_the_real_close_question_has_three_answers(qtbot):
    def answer():
        box = QApplication.activeModalWidget()
        assert {b.text().replace("&", "") for b in box.buttons()} >= {"Save", "Discard", "Cancel"}
        box.button(QMessageBox.StandardButton.Cancel).click()

    QTimer.singleShot(0, answer)
    from importlib import reload

    real = reload(dialogs)  # the autouse fixture patched the module attribute
    assert real.ask_unsaved_changes(None, "closing") == "cancel"


def test_autosave_and_recovery(window, qtbot, tmp_path, monkeypatch):
    session = window.session
    session.link([1], [2])
    window.documents.autosaver.flush_if_due(time.monotonic() + 60)  # the timer's call, made due
    folder = window.documents.autosave_dir
    (copy,) = folder.glob("*.autosave.json")
    assert load_correspondences(copy).cliques[0].metric_regions == (2,)
    # A crash: the window goes away without a clean close; the copy stays, its lock
    # names a process that is gone.
    window.documents.autosave_timer.stop()
    simulate_crash(window.documents.autosaver)

    offered = []
    monkeypatch.setattr(dialogs, "ask_recover", lambda parent, paths: offered.append(paths) or paths[0])
    fresh = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(fresh)
    assert fresh.documents.offer_recovery()
    assert offered and offered[0] == [copy]
    (clique,) = fresh.session.correspondences.cliques
    assert clique.metric_regions == (2,) and fresh.session.dirty
    assert fresh.session.map("sketch") is not None  # maps reopened from the copy
    assert fresh.windowTitle().endswith("*")
    assert fresh.table.model.rowCount() == 1


def test_real_recovery_dialog_offers_recover(qtbot, tmp_path):
    copy = tmp_path / "x.autosave.json"
    copy.write_text("{}")

    def answer():
        box = QApplication.activeModalWidget()
        assert "x.autosave.json" in box.text()
        next(b for b in box.buttons() if b.text() == "Recover").click()

    QTimer.singleShot(0, answer)
    from importlib import reload

    assert reload(dialogs).ask_recover(None, [copy]) == copy


def test_saving_over_a_file_changed_on_disk_asks_first(window, tmp_path, monkeypatch):
    """Issue 12 item 3 through the window: the changed-on-disk question, Cancel keeps the other file."""
    import dataclasses

    from ursim_core.correspondences import load_correspondences, save_correspondences
    from ursim_gui.window import dialogs

    path = tmp_path / "shared.json"
    window.session.save(path)
    # Another session (or program) writes the file: here, a new annotator name.
    save_correspondences(dataclasses.replace(load_correspondences(path), annotator="someone else"), path)
    written = path.read_bytes()
    asked = []
    monkeypatch.setattr(dialogs, "ask_overwrite_changed", lambda parent, p: asked.append(p) or False)
    assert window.documents.save() is False
    assert asked == [path] and path.read_bytes() == written
    monkeypatch.setattr(dialogs, "ask_overwrite_changed", lambda parent, p: True)
    assert window.documents.save() is True and path.read_bytes() != written
