"""Shared fixtures of the GUI tests: offscreen Qt, small synthetic maps and segmentations."""

from __future__ import annotations

import os

# Must happen before QApplication exists (pytest-qt creates it lazily in the qapp fixture).
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np
import pytest


def two_room_free(rows: int = 60, cols: int = 130) -> np.ndarray:
    """Two rooms joined by a door: the smallest map with two regions and one edge."""
    free = np.zeros((rows, cols), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    return free


def three_room_labels() -> np.ndarray:
    """Label image of three rooms in a row (1 | 2 | 3), walls 0, 60x150."""
    labels = np.zeros((60, 150), np.int32)
    labels[5:55, 5:48] = 1
    labels[5:55, 52:98] = 2
    labels[5:55, 102:145] = 3
    labels[28:32, 48:52] = 1
    labels[28:32, 98:102] = 2
    return labels


@pytest.fixture
def labels3() -> np.ndarray:
    return three_room_labels()


@pytest.fixture
def segmentation3(labels3):
    from ursim_core.segmentation import Segmentation
    from ursim_core.segmentation.graph import region_graph

    return Segmentation(labels=labels3, graph=region_graph(labels3), method="label-image")


@pytest.fixture
def grey3(labels3) -> np.ndarray:
    return np.where(labels3 > 0, 255, 0).astype(np.uint8)


@pytest.fixture(autouse=True)
def _user_data_dir(tmp_path, monkeypatch):
    """Keep logs and autosaves of every test in its own temporary folder."""
    monkeypatch.setenv("URSIM_GUI_DATA_DIR", str(tmp_path / "userdata"))


def scaled(labels: np.ndarray, factor: int) -> np.ndarray:
    return np.kron(labels, np.ones((factor, factor), labels.dtype))


@pytest.fixture
def map_files(tmp_path, labels3):
    """Sketch (60x150) and metric (120x300) PNG maps of three rooms, and their label images.

    Regions are numbered alike on both sides, so the right match is 1-1, 2-2, 3-3.
    """
    import cv2

    files = {}
    for side, labels in (("sketch", labels3), ("metric", scaled(labels3, 2))):
        image = np.where(labels > 0, 255, 0).astype(np.uint8)
        files[side] = tmp_path / f"{side}.png"
        cv2.imwrite(str(files[side]), image)
        files[f"{side}_labels"] = tmp_path / f"{side}_labels.png"
        cv2.imwrite(str(files[f"{side}_labels"]), labels.astype(np.uint16))
    return files


@pytest.fixture(autouse=True)
def _never_block_on_questions(monkeypatch):
    """Modal questions would hang a test; tests that check them patch their own answer."""
    from ursim_gui.window import dialogs

    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: "discard")
    monkeypatch.setattr(dialogs, "ask_recover", lambda parent, paths: None)
    from PySide6.QtWidgets import QInputDialog

    monkeypatch.setattr(QInputDialog, "getText", staticmethod(lambda *args, **kwargs: ("tester", True)))


@pytest.fixture
def window(qtbot, tmp_path, map_files):
    """Main window with both maps open and segmented from their label images (no MAORIS)."""
    from ursim_core.segmentation import load_label_image
    from ursim_gui.window.main_window import MainWindow

    win = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(win)
    win.resize(1400, 900)
    win.show()
    qtbot.waitExposed(win)
    for side in ("sketch", "metric"):
        win.session.load_map(side, map_files[side])
        labels = load_label_image(map_files[f"{side}_labels"], shape=win.session.map(side).shape)
        win.session.set_segmentation(side, labels)
    yield win
    win.jobs.runner.shutdown()


@pytest.fixture
def example_window(qtbot, tmp_path):
    """Main window shown on the bundled example pair, segmented and matched."""
    from ursim_gui.model.example import example_inputs
    from ursim_gui.window.main_window import MainWindow

    if example_inputs() is None:
        pytest.skip("resources/example is not generated in this checkout")
    win = MainWindow(data_dir=tmp_path / "data")
    qtbot.addWidget(win)
    win.resize(1200, 700)
    win.show()
    assert win.open_inputs(example=True, wait=True)
    return win


def region_point(view, region: int):
    """Viewport position of a region's interior point (to click or hover it)."""
    return view.mapFromScene(view.region_scene_point(region))


def hover(qtbot, widget, pos) -> None:
    """Deliver a mouse move onto ``pos`` of ``widget``, as the window system would.

    The event is sent straight to the widget instead of moving the shared cursor. Through the
    cursor, Qt drops a move to the position it already has (tests in one worker share it), and
    the offscreen platform may deliver a late enter/leave of an earlier window after the move;
    either left the status bar empty in CI twice. Pending events are flushed first so that such
    a late leave cannot land after this move.
    """
    from PySide6.QtCore import QEvent, QPointF, Qt
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication

    QApplication.processEvents()
    local = QPointF(pos)
    event = QMouseEvent(
        QEvent.Type.MouseMove,
        local,
        QPointF(widget.mapToGlobal(local)),
        Qt.MouseButton.NoButton,
        Qt.MouseButton.NoButton,
        Qt.KeyboardModifier.NoModifier,
    )
    QApplication.sendEvent(widget, event)


def error_boxes(parent):
    """Visible error dialogs of a window."""
    from PySide6.QtWidgets import QMessageBox

    return [box for box in parent.findChildren(QMessageBox, "error_box") if box.isVisible()]


def dead_pid() -> int:
    """The id of a process that has just exited (as a crashed run's)."""
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def simulate_crash(autosaver) -> None:
    """Leave ``autosaver``'s copy as a crashed run would: its lock names a dead process."""
    lock = autosaver.folder / f"{autosaver._instance_id}.lock"
    lock.write_text(f"{dead_pid()}\n", encoding="ascii")
