"""File > New sketch: a drawing window over :class:`~ursim_gui.model.sketch_document.SketchDocument`.

The window translates mouse events to document strokes and shows the image; the
document owns the pixels, the tools and the undo stack.
"""

from __future__ import annotations

from PySide6.QtCore import QPoint, QRect, Qt, Signal
from PySide6.QtGui import QAction, QActionGroup, QKeySequence, QPainter
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QLabel,
    QMainWindow,
    QScrollArea,
    QSpinBox,
    QWidget,
)

from ursim_gui.model.sketch_document import TOOLS, SketchDocument
from ursim_gui.views import file_dialogs
from ursim_gui.views.map_items import grey_to_qimage
from ursim_gui.views.messages import ask_keep_drawing, show_error

__all__ = ["SketchSizeDialog", "SketchCanvas", "SketchWindow"]


class SketchSizeDialog(QDialog):
    """Asks for the canvas size in pixels."""

    def __init__(self, parent=None, rows: int = 600, cols: int = 800):
        super().__init__(parent)
        self.setWindowTitle("New sketch")
        self.rows = _spin(rows, "sketch_rows")
        self.cols = _spin(cols, "sketch_cols")
        form = QFormLayout(self)
        form.addRow("Height (px)", self.rows)
        form.addRow("Width (px)", self.cols)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def size_rc(self) -> tuple[int, int]:
        return self.rows.value(), self.cols.value()


def _spin(value: int, name: str) -> QSpinBox:
    spin = QSpinBox()
    spin.setRange(32, 4000)
    spin.setValue(value)
    spin.setObjectName(name)
    return spin


class SketchCanvas(QWidget):
    """Shows the document at an integer zoom and turns mouse drags into strokes."""

    def __init__(self, document: SketchDocument, parent=None):
        super().__init__(parent)
        self.document = document
        self.zoom = 1
        self.setCursor(Qt.CursorShape.CrossCursor)
        self.setFixedSize(document.image.shape[1], document.image.shape[0])
        document.changed.connect(self.update)

    def set_zoom(self, zoom: int) -> None:
        self.zoom = max(1, int(zoom))
        rows, cols = self.document.image.shape
        self.setFixedSize(cols * self.zoom, rows * self.zoom)
        self.update()

    def pixel_at(self, position: QPoint) -> tuple[int, int]:
        """Image pixel (row, col) under a widget position."""
        return int(position.y()) // self.zoom, int(position.x()) // self.zoom

    def paintEvent(self, event) -> None:
        image, _keepalive = grey_to_qimage(self.document.image)
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, False)
        rows, cols = self.document.image.shape
        painter.drawImage(QRect(0, 0, cols * self.zoom, rows * self.zoom), image)

    def mousePressEvent(self, event) -> None:
        if event.button() == Qt.MouseButton.LeftButton:
            self.document.begin(*self.pixel_at(event.position().toPoint()))

    def mouseMoveEvent(self, event) -> None:
        if event.buttons() & Qt.MouseButton.LeftButton:
            self.document.extend(*self.pixel_at(event.position().toPoint()))

    def mouseReleaseEvent(self, event) -> None:
        if event.button() == Qt.MouseButton.LeftButton:
            self.document.end(*self.pixel_at(event.position().toPoint()))


class SketchWindow(QMainWindow):
    """Drawing window: tools, brush width, undo/redo, save as PNG, use as sketch.

    Signals
    -------
    use_as_sketch(object, object) : the drawn image (uint8, walls black) to set as the session's
        sketch, and the PNG it was last saved to while it is still the drawing (else None)
    """

    use_as_sketch = Signal(object, object)

    def __init__(self, rows: int, cols: int, parent=None):
        super().__init__(parent)
        self.setWindowTitle("New sketch")
        self.document = SketchDocument(rows, cols)
        self.canvas = SketchCanvas(self.document)
        scroll = QScrollArea()
        scroll.setWidget(self.canvas)
        scroll.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setCentralWidget(scroll)
        toolbar = self.addToolBar("Tools")
        toolbar.setObjectName("sketch_tools")
        group = QActionGroup(self)
        self.tool_actions: dict[str, QAction] = {}
        for key, tool in zip("PEWX", TOOLS):
            action = group.addAction(f"{tool.capitalize()} ({key})")
            action.setCheckable(True)
            action.setShortcut(QKeySequence(key))
            action.setObjectName(f"tool_{tool}")
            action.triggered.connect(lambda _checked=False, name=tool: self._set_tool(name))
            toolbar.addAction(action)
            self.tool_actions[tool] = action
        self.tool_actions["pen"].setChecked(True)
        toolbar.addSeparator()
        toolbar.addWidget(QLabel(" Width "))
        self.width_spin = QSpinBox()
        self.width_spin.setRange(1, 40)
        self.width_spin.setValue(self.document.width)
        self.width_spin.setObjectName("sketch_width")
        self.width_spin.valueChanged.connect(lambda value: setattr(self.document, "width", value))
        toolbar.addWidget(self.width_spin)
        toolbar.addWidget(QLabel(" Zoom "))
        self.zoom_spin = QSpinBox()
        self.zoom_spin.setRange(1, 8)
        self.zoom_spin.setSuffix("×")
        self.zoom_spin.valueChanged.connect(self.canvas.set_zoom)
        toolbar.addWidget(self.zoom_spin)
        self.addToolBarBreak()
        commands = self.addToolBar("Document")
        commands.setObjectName("sketch_commands")
        toolbar = commands
        self.undo_action = self._command(
            toolbar, "Undo", QKeySequence.StandardKey.Undo, self.document.undo, "sketch_undo"
        )
        self.redo_action = self._command(
            toolbar, "Redo", QKeySequence.StandardKey.Redo, self.document.redo, "sketch_redo"
        )
        self._command(toolbar, "Clear", None, self.document.clear, "sketch_clear")
        toolbar.addSeparator()
        self._command(toolbar, "Save PNG…", QKeySequence.StandardKey.Save, self.save_dialog, "sketch_save")
        self._command(toolbar, "Use as sketch", None, self._use_as_sketch, "sketch_use")
        self.document.history_changed.connect(self._update_history)
        self._update_history()
        self.resize(max(620, min(cols + 60, 1400)), min(rows + 120, 1000))

    def _command(self, toolbar, text: str, key, slot, name: str) -> QAction:
        action = QAction(text, self)
        action.setObjectName(name)
        if key is not None:
            action.setShortcut(QKeySequence(key))
        action.triggered.connect(lambda _checked=False: slot())
        toolbar.addAction(action)
        return action

    def _set_tool(self, tool: str) -> None:
        self.document.tool = tool

    def _update_history(self) -> None:
        self.undo_action.setEnabled(self.document.can_undo)
        self.redo_action.setEnabled(self.document.can_redo)

    def save_dialog(self) -> bool:
        """Ask for a PNG and save the drawing there. True when it was saved."""
        path = file_dialogs.ask_save_path(self, "Save sketch", "sketch.png", "PNG image (*.png)")
        return path is not None and self.save_to(str(path))

    def save_to(self, path: str) -> bool:
        """Save the PNG; a failure is shown in a dialog and logged. True on success."""
        try:
            self.document.save_png(path)
        except OSError as error:
            show_error(self, "Save failed", f"The sketch was not saved:\n{error}")
            return False
        self.statusBar().showMessage(f"Saved {path}", 4000)
        self.setWindowTitle(f"Sketch — {self.document.saved_path.name}")
        return True

    def _use_as_sketch(self) -> None:
        self.use_as_sketch.emit(self.document.map_image(), self.document.file_of_drawing)
        self.document.mark_used()

    def closeEvent(self, event) -> None:
        """A drawing neither saved nor used as the sketch is not closed without asking."""
        if self.document.unkept:
            answer = ask_keep_drawing(self)
            if answer == "cancel" or (answer == "save" and not self.save_dialog()):
                event.ignore()
                return
        super().closeEvent(event)
