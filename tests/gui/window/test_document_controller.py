"""File commands of the window: open maps and documents, save, .dat, the unsaved-changes question, autosave."""

from __future__ import annotations

import json
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import answer_file_dialogs, click, error_boxes, key, link_by_clicks, simulate_crash
from PySide6.QtCore import QMimeData, QPointF, Qt, QUrl
from PySide6.QtGui import QDropEvent

from ursim_core.correspondences import Clique, Correspondences, load_correspondences, load_dat, save_correspondences
from ursim_gui.model import autosave
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs
from ursim_gui.window.main_window import MainWindow

# ---- open ----------------------------------------------------------------------------------------


def choose_file(monkeypatch, path):
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(path)))


def test_file_menu_opens_each_map(empty_window, map_files, monkeypatch):
    win = empty_window
    choose_file(monkeypatch, map_files["sketch"])
    win.actions["open_sketch"].trigger()
    choose_file(monkeypatch, map_files["metric"])
    win.actions["open_metric"].trigger()
    assert win.session.map("sketch").shape == (60, 150)
    assert win.session.map("metric").shape == (120, 300)
    assert win.views["metric"].sceneRect().width() == 300
    assert "300 × 120 px" in win.view_titles["metric"].text()  # width x height
    assert win.segmentation_panel.boxes["metric"].segment_button.isEnabled()


def test_drop_on_a_view_opens_that_side(empty_window, map_files):
    view = empty_window.views["metric"]
    data = QMimeData()
    data.setUrls([QUrl.fromLocalFile(str(map_files["metric"]))])
    view.dropEvent(
        QDropEvent(
            QPointF(5, 5), Qt.DropAction.CopyAction, data, Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
        )
    )
    assert empty_window.session.map("metric").path == map_files["metric"]
    assert view.has_image()


def test_ros_yaml_map_opens(empty_window, map_files, tmp_path, monkeypatch):
    yaml_path = tmp_path / "ros.yaml"
    yaml_path.write_text(
        f"image: {map_files['metric'].name}\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    choose_file(monkeypatch, yaml_path)
    empty_window.actions["open_metric"].trigger()
    assert empty_window.session.map("metric").resolution == pytest.approx(0.05)


def test_unreadable_map_shows_an_error_and_changes_nothing(empty_window, tmp_path, monkeypatch, caplog):
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image at all")
    choose_file(monkeypatch, bad)
    empty_window.actions["open_sketch"].trigger()
    boxes = error_boxes(empty_window)
    assert boxes and "broken.png" in boxes[0].text()
    assert empty_window.session.map("sketch") is None
    assert any("broken.png" in record.getMessage() and record.levelname == "ERROR" for record in caplog.records)


@pytest.mark.parametrize("side", ["sketch", "metric"])
@pytest.mark.parametrize("content", [b"", b"not an image at all", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00"])
def test_a_map_that_cannot_be_read_leaves_the_pair_as_it_was(window, qtbot, tmp_path, monkeypatch, side, content):
    # The file is read before the document is replaced: no question, nothing lost, undo kept.
    link_by_clicks(qtbot, window, 1, 1)
    session = window.session
    before = session.correspondences
    maps = {name: session.map(name) for name in ("sketch", "metric")}
    segmentations = {name: session.segmentation(name) for name in ("sketch", "metric")}
    asked = []
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: asked.append(what) or "discard")
    bad = tmp_path / "bad.png"
    bad.write_bytes(content)
    choose_file(monkeypatch, bad)
    assert not window.documents.open_map(side)
    assert error_boxes(window) and "bad.png" in error_boxes(window)[0].text()
    assert not asked
    assert session.correspondences == before and session.can_undo
    assert {name: session.map(name) for name in maps} == maps
    assert {name: session.segmentation(name) for name in segmentations} == segmentations


def test_open_correspondences_loads_the_maps_it_names(window, tmp_path, monkeypatch):
    window.session.link([1], [1])
    saved = tmp_path / "corr.json"
    window.session.save(saved)
    fresh = MainWindow(data_dir=tmp_path / "other")
    window.close()
    choose_file(monkeypatch, saved)
    fresh.actions["open_correspondences"].trigger()
    assert fresh.session.path == saved
    assert fresh.session.map("sketch") is not None and fresh.session.map("metric") is not None
    assert len(fresh.session.correspondences.cliques) == 1
    assert fresh.table.model.rowCount() == 1
    fresh.discard_and_close()


def test_bad_json_shows_an_error(empty_window, tmp_path, monkeypatch):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "something else"}))
    choose_file(monkeypatch, bad)
    empty_window.actions["open_correspondences"].trigger()
    assert error_boxes(empty_window)
    assert empty_window.session.path is None


def test_opening_another_sketch_starts_a_new_document_and_never_overwrites_the_old(
    window, qtbot, tmp_path, monkeypatch, labels3
):
    link_by_clicks(qtbot, window, 1, 1)
    document = tmp_path / "k01.json"
    answer_file_dialogs(monkeypatch, document)
    window.actions["save"].trigger()
    reference = tmp_path / "reference.json"
    save_correspondences(
        Correspondences(cliques=(Clique(id=1, sketch_points=[(30, 25)], metric_points=[(60, 50)]),)), reference
    )
    window.documents.load_reference(reference)
    saved_bytes = document.read_bytes()
    other = tmp_path / "03.png"
    cv2.imwrite(str(other), np.where(labels3[:, ::-1] > 0, 255, 0).astype(np.uint8))

    asked = []
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: asked.append(what) or "discard")
    answer_file_dialogs(monkeypatch, other)
    window.actions["open_sketch"].trigger()

    session = window.session
    assert session.map("sketch").path == other
    assert session.map("metric") is not None  # the metric map stays for the next sketch
    assert session.correspondences.cliques == () and session.path is None
    assert session.reference is None and window.evaluation.values["f1"].text() == "–"
    assert "k01.json" not in window.windowTitle() and "untitled" in window.windowTitle()
    assert not asked  # the old document was saved: nothing to ask

    new_file = tmp_path / "03.json"
    answer_file_dialogs(monkeypatch, new_file)
    window.actions["save"].trigger()  # asks for a new name: it never writes k01.json
    assert document.read_bytes() == saved_bytes and new_file.is_file()


def test_opening_another_map_with_unsaved_changes_asks_and_cancel_keeps_all(window, qtbot, tmp_path, monkeypatch):
    link_by_clicks(qtbot, window, 1, 1)
    session = window.session
    session.save(tmp_path / "doc.json")
    link_by_clicks(qtbot, window, 2, 2)
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: "cancel")
    answer_file_dialogs(monkeypatch, tmp_path / "sketch_labels.png")
    window.actions["open_sketch"].trigger()
    assert len(session.correspondences.cliques) == 2 and session.path == tmp_path / "doc.json"


# ---- save ----------------------------------------------------------------------------------------


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
    written = target.read_bytes(), target.stat().st_mtime_ns
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_S, Qt.KeyboardModifier.ControlModifier)  # nothing changed
    assert (target.read_bytes(), target.stat().st_mtime_ns) == written
    assert "No changes to save" in window.statusBar().currentMessage()
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


# ---- .dat export and import ----------------------------------------------------------------------


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


def test_dat_export_leaves_out_rejected_cliques(window, qtbot, tmp_path, monkeypatch):
    link_by_clicks(qtbot, window, 1, 1)
    link_by_clicks(qtbot, window, 2, 2)
    click(qtbot, window.views["sketch"], 2)  # selects the clique 2 <-> 2
    key(qtbot, window, Qt.Key.Key_R)
    target = tmp_path / "out.dat"
    answer_file_dialogs(monkeypatch, target)
    window.actions["export_dat"].trigger()
    exported = load_dat(target)
    assert len(exported.cliques) == 1
    assert exported.cliques[0].sketch_points == window.session.correspondences.cliques[0].sketch_points


# ---- unsaved changes -----------------------------------------------------------------------------


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


def test_quitting_an_untouched_matched_pair_does_not_ask(window, qtbot, monkeypatch):
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    assert window.session.correspondences.cliques
    asked = []
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: asked.append(what) or "cancel")
    assert not window.windowTitle().endswith("*")
    window.close()
    assert not asked and not window.isVisible()


def test_a_reviewed_automatic_clique_is_an_unsaved_change(window, qtbot, monkeypatch):
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    window.table.view.selectRow(0)
    key(qtbot, window, Qt.Key.Key_R)
    assert window.windowTitle().endswith("*")


# ---- autosave and recovery -----------------------------------------------------------------------


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


def test_a_drawn_sketch_recovered_is_a_drawing_again(window, qtbot, tmp_path, monkeypatch):
    # It was recovered from the copy's PNG and kept that file's path: every later save named a
    # file in the autosave folder, which nothing ever removed nor copied beside the document.
    from ursim_core.io import map_from_array

    drawn = np.full((50, 70), 255, np.uint8)
    drawn[0, :] = drawn[-1, :] = drawn[:, 0] = drawn[:, -1] = 0
    window.session.new_document(keep=["metric"])
    window.session.set_map("sketch", map_from_array(drawn))
    window.documents.autosaver.flush_if_due(time.monotonic() + 60)
    folder = window.documents.autosave_dir
    (copy,) = folder.glob("*.autosave.json")
    (drawing,) = folder.glob("*.sketch.png")
    window.documents.autosave_timer.stop()
    simulate_crash(window.documents.autosaver)

    monkeypatch.setattr(dialogs, "ask_recover", lambda parent, paths: paths[0])
    fresh = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(fresh)
    assert fresh.documents.offer_recovery()
    assert fresh.session.map("sketch").path is None and fresh.session.dirty
    assert "drawn, not saved yet" in fresh.view_titles["sketch"].text()
    assert not copy.exists() and not drawing.exists()
    fresh.session.save(tmp_path / "pair.json")
    assert load_correspondences(tmp_path / "pair.json").sketch.path == tmp_path / "pair.sketch.png"


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


def test_a_file_that_records_no_segmentation_gets_its_maps_segmented(empty_window, qtbot):
    # The bundled example's ground truth names its maps and points only: it opens with regions.
    example = Path(__file__).resolve().parents[3] / "resources" / "example" / "ground_truth.json"
    session = empty_window.session
    assert empty_window.documents.open_correspondences(example)
    qtbot.waitUntil(lambda: not empty_window.jobs.busy, timeout=120_000)
    assert session.segmentation("sketch") is not None and session.segmentation("metric") is not None
    assert all(clique.sketch_regions and clique.metric_regions for clique in session.correspondences.cliques)
    assert not session.dirty and session.path == example
