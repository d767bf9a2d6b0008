"""The sketch canvas (File > New sketch): size, drawing tools, width, undo/redo, save as PNG, "Use as sketch"."""

from __future__ import annotations

import cv2
import numpy as np
from PySide6.QtCore import QPoint, Qt, QTimer
from PySide6.QtWidgets import QApplication

from ursim_gui.model.sketch_document import INK, PAPER
from ursim_gui.tools.sketch_canvas import SketchSizeDialog, SketchWindow


def drag(qtbot, widget, start: QPoint, end: QPoint, steps: int = 5) -> None:
    qtbot.mousePress(widget, Qt.MouseButton.LeftButton, pos=start)
    for i in range(1, steps + 1):
        point = start + (end - start) * (i / steps)
        # QTest moves carry no button state; send real events with the left button held.
        from PySide6.QtCore import QEvent, QPointF
        from PySide6.QtGui import QMouseEvent

        event = QMouseEvent(
            QEvent.Type.MouseMove,
            QPointF(point),
            QPointF(widget.mapToGlobal(point)),
            Qt.MouseButton.NoButton,
            Qt.MouseButton.LeftButton,
            Qt.KeyboardModifier.NoModifier,
        )
        QApplication.sendEvent(widget, event)
    qtbot.mouseRelease(widget, Qt.MouseButton.LeftButton, pos=end)


def test_new_sketch_from_the_menu_draw_undo_save_and_use(window, qtbot, tmp_path):
    def accept_size_dialog():
        dialog = next(w for w in QApplication.topLevelWidgets() if isinstance(w, SketchSizeDialog) and w.isVisible())
        dialog.rows.setValue(120)
        dialog.cols.setValue(200)
        dialog.accept()

    QTimer.singleShot(0, accept_size_dialog)
    window.actions["new_sketch"].trigger()
    sketch = window.tools.sketch_windows[-1]
    qtbot.waitExposed(sketch)
    assert isinstance(sketch, SketchWindow) and sketch.document.image.shape == (120, 200)
    canvas = sketch.canvas

    sketch.width_spin.setValue(4)
    drag(qtbot, canvas, QPoint(20, 30), QPoint(150, 30))  # pen stroke
    assert (sketch.document.image[30, 25:145] == INK).all()
    sketch.tool_actions["rectangle"].trigger()
    drag(qtbot, canvas, QPoint(40, 60), QPoint(120, 100))
    assert sketch.document.image[60, 80] == INK and sketch.document.image[80, 80] == PAPER
    sketch.tool_actions["eraser"].trigger()
    drag(qtbot, canvas, QPoint(60, 30), QPoint(100, 30))
    assert sketch.document.image[30, 80] == PAPER
    sketch.tool_actions["wall"].trigger()
    drag(qtbot, canvas, QPoint(10, 110), QPoint(190, 110))
    assert (sketch.document.image[110, 12:188] == INK).all()

    assert sketch.undo_action.isEnabled()
    sketch.undo_action.trigger()  # wall gone
    assert sketch.document.image[110, 100] == PAPER
    sketch.redo_action.trigger()
    assert sketch.document.image[110, 100] == INK

    saved = tmp_path / "drawn.png"
    assert sketch.save_to(str(saved))
    # Saved as the map it stands for: paper around the drawing is outside; the rectangle's
    # inside (closed by the walls) stays free.
    written = cv2.imread(str(saved), cv2.IMREAD_UNCHANGED)
    assert np.array_equal(written, sketch.document.map_image())
    assert written[5, 5] == INK and written[80, 80] == PAPER

    sketch.findChild(type(sketch.undo_action), "sketch_use").trigger()
    session_sketch = window.session.map("sketch")
    assert session_sketch.shape == (120, 200)
    assert not session_sketch.free[110, 100] and session_sketch.free[80, 80]
    assert not session_sketch.free[5, 5], "paper outside the drawn walls is not free space"
    assert np.array_equal(session_sketch.free, written > 250)
    assert window.views["sketch"].sceneRect().width() == 200
    sketch.close()


def test_failed_sketch_save_shows_an_error(qtbot, tmp_path):
    sketch = SketchWindow(40, 40)
    qtbot.addWidget(sketch)
    assert not sketch.save_to(str(tmp_path / "missing" / "s.png"))
    from PySide6.QtWidgets import QMessageBox

    assert sketch.findChildren(QMessageBox)


def test_closing_a_drawing_neither_saved_nor_used_asks_first(qtbot, monkeypatch, tmp_path):
    import ursim_gui.tools.sketch_canvas as sketch_canvas

    sketch = SketchWindow(60, 80)
    qtbot.addWidget(sketch)
    sketch.show()
    asked = []
    monkeypatch.setattr(sketch_canvas, "ask_keep_drawing", lambda parent: asked.append(1) or answer)
    answer = "cancel"
    assert sketch.close()  # blank paper: nothing to lose, no question
    assert not asked

    sketch = SketchWindow(60, 80)
    qtbot.addWidget(sketch)
    sketch.show()
    sketch.document.begin(10, 10)
    sketch.document.end(10, 70)
    assert not sketch.close() and sketch.isVisible() and asked == [1]  # cancel keeps it open
    sketch._use_as_sketch()
    assert sketch.close() and asked == [1]  # used as the sketch: kept in the document

    sketch = SketchWindow(60, 80)
    qtbot.addWidget(sketch)
    sketch.show()
    sketch.document.begin(10, 10)
    sketch.document.end(10, 70)
    assert sketch.save_to(str(tmp_path / "s.png"))
    assert sketch.close() and asked == [1]  # saved
    sketch = SketchWindow(60, 80)
    qtbot.addWidget(sketch)
    sketch.show()
    sketch.document.begin(10, 10)
    sketch.document.end(10, 70)
    answer = "discard"
    assert sketch.close() and asked == [1, 1]


def test_using_a_drawing_over_a_saved_document_starts_a_new_one_and_saves_the_drawing_beside_it(
    window, qtbot, tmp_path, monkeypatch
):
    from conftest import answer_file_dialogs, link_by_clicks

    link_by_clicks(qtbot, window, 1, 1)
    document = tmp_path / "pair.json"
    answer_file_dialogs(monkeypatch, document)
    window.actions["save"].trigger()
    saved = document.read_bytes()

    sketch = window.tools.new_sketch((60, 150))
    qtbot.addWidget(sketch)
    sketch.document.begin(30, 5)
    sketch.document.end(30, 145)
    sketch._use_as_sketch()
    session = window.session
    assert session.path is None and session.correspondences.cliques == ()
    assert session.map("sketch").path is None and session.map("metric") is not None
    assert session.dirty and window.windowTitle().endswith("*")  # the drawing is unsaved work

    drawn_document = tmp_path / "drawn.json"
    answer_file_dialogs(monkeypatch, drawn_document)
    window.actions["save"].trigger()
    assert document.read_bytes() == saved  # the old pair's file untouched
    assert (tmp_path / "drawn.sketch.png").is_file() and not session.dirty
    assert session.map("sketch").path == tmp_path / "drawn.sketch.png"
    assert "map" not in window.view_titles["sketch"].text()
    sketch.close()


def test_closing_the_app_asks_about_an_open_drawing(window, qtbot, monkeypatch):
    import ursim_gui.tools.sketch_canvas as sketch_canvas

    sketch = window.tools.new_sketch((60, 80))
    qtbot.addWidget(sketch)
    sketch.document.begin(10, 10)
    sketch.document.end(10, 70)
    monkeypatch.setattr(sketch_canvas, "ask_keep_drawing", lambda parent: "cancel")
    assert not window.close() and window.isVisible() and sketch.isVisible()
    monkeypatch.setattr(sketch_canvas, "ask_keep_drawing", lambda parent: "discard")
    assert window.close() and not sketch.isVisible()
