"""Shared fixtures and helpers of the GUI tests: offscreen Qt, synthetic maps, model sessions, window clicks, keys."""

from __future__ import annotations

import logging
import os
import types
from pathlib import Path

# Must happen before QApplication exists (pytest-qt creates it lazily in the qapp fixture).
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import cv2
import numpy as np
import pytest
from PySide6.QtCore import Qt

from ursim_core.io.maps import map_from_array
from ursim_core.segmentation import Segmentation, load_label_image, save_label_image
from ursim_core.segmentation.graph import region_graph
from ursim_gui.model.session import AnnotationSession


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


def segmented_window(qtbot, data_dir, map_files, size=(1400, 900)):
    """A main window of ``size`` with both maps open and segmented from their label images (no MAORIS)."""
    from ursim_core.segmentation import load_label_image
    from ursim_gui.window.main_window import MainWindow

    win = MainWindow(data_dir=data_dir)
    qtbot.addWidget(win)
    win.resize(*size)
    win.show()
    qtbot.waitExposed(win)
    for side in ("sketch", "metric"):
        win.session.load_map(side, map_files[side])
        labels = load_label_image(map_files[f"{side}_labels"], shape=win.session.map(side).shape)
        win.session.set_segmentation(side, labels)
    return win


@pytest.fixture
def window(qtbot, tmp_path, map_files):
    """Main window with both maps open and segmented from their label images (no MAORIS)."""
    win = segmented_window(qtbot, tmp_path / "userdata", map_files)
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


# ---- sessions of the model tests -----------------------------------------------------------------


NOW = "2024-05-01T12:00:00Z"


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
def session(tmp_path_factory):
    # Maps from files, as the app opens them: a map with no file is a drawing, the user's work.
    folder = tmp_path_factory.mktemp("maps")
    session = AnnotationSession(annotator="tester", timestamp=lambda: NOW)
    for side, labels in (("sketch", SKETCH_LABELS), ("metric", METRIC_LABELS)):
        cv2.imwrite(str(folder / f"{side}.png"), np.where(labels > 0, 255, 0).astype(np.uint8))
        session.load_map(side, folder / f"{side}.png")
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


# ---- driving the main window ---------------------------------------------------------------------


def click(qtbot, view, region, modifier=Qt.KeyboardModifier.NoModifier):
    """Click a region of a map view (with ``modifier``)."""
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, modifier, region_point(view, region))


def key(qtbot, window, name, modifier=Qt.KeyboardModifier.NoModifier):
    """Press a key on the window's sketch view."""
    qtbot.keyClick(window.views["sketch"], name, modifier)


def link_by_clicks(qtbot, window, sketch: int, metric: int) -> None:
    window.session.clear_selection()
    click(qtbot, window.views["sketch"], sketch)
    # Ctrl: a plain click on a matched region would select its clique instead.
    click(qtbot, window.views["metric"], metric, Qt.KeyboardModifier.ControlModifier)
    key(qtbot, window, Qt.Key.Key_L)


def answer_file_dialogs(monkeypatch, path: Path) -> None:
    """Every open or save dialog answers ``path``."""
    from ursim_gui.views import file_dialogs

    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(path))
    monkeypatch.setattr(file_dialogs, "ask_save_path", lambda *a, **k: Path(path))


@pytest.fixture
def empty_window(qtbot, tmp_path):
    from ursim_gui.window.main_window import MainWindow

    win = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(win)
    win.show()
    return win


def new_window(qtbot, data_dir):
    from ursim_gui.window.main_window import MainWindow

    window = MainWindow(data_dir=data_dir)
    qtbot.addWidget(window)
    window.show()
    qtbot.waitExposed(window)
    return window


@pytest.fixture
def plain_campaign(tmp_path, labels3):
    """A plain folder: metric.png and three sketches (the three-room map and two copies)."""
    folder = tmp_path / "plain"
    folder.mkdir()
    cv2.imwrite(str(folder / "metric.png"), np.where(scaled(labels3, 2) > 0, 255, 0).astype(np.uint8))
    for name in ("s1", "s2", "s3"):
        cv2.imwrite(str(folder / f"{name}.png"), np.where(labels3 > 0, 255, 0).astype(np.uint8))
    return folder


@pytest.fixture
def restore_logging():
    """main() installs log handlers on the root logger; take them off afterwards."""
    yield
    root = logging.getLogger()
    for handler in [h for h in root.handlers if getattr(h, "_ursim_gui", False)]:
        root.removeHandler(handler)
        handler.close()
