"""Segmentation panel: per side method (the core's registry), preset, parameters, Segment / Load label image; display options.

The panel does not segment: it emits what the user asked for and the main window runs
the job. Display options (opacity, outlines, ids, graph) drive both map views.
"""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from ursim_gui.model.session import DEFAULT_PRESETS

__all__ = ["SegmentationPanel", "SideSegmentationBox", "method_names", "preset_names", "preset_values"]

_log = logging.getLogger(__name__)

#: MAORIS parameters shown in the panel (the others keep their preset value). The other
#: segmenters show every numeric parameter of theirs.
_SHOWN_MAORIS = ("threshold", "margin", "ripples", "doors")
_TIPS = {
    "threshold": "Watershed relative-difference threshold t in [0, 1): higher merges more",
    "margin": "Extra watershed tolerance when a close neighbour exists, in [0, 1)",
    "ripples": "Percent of a zone's contour touching a neighbour that makes it a ripple of it",
    "doors": "Percent of a region's contour touching other regions above which it is a door and is fused",
    "door_ratio": "Clearance at the boundary over the smaller peak clearance above which two basins merge",
    "min_size": "Regions smaller than this many pixels join a neighbour",
    "watershed_min_size": "Watershed pieces smaller than this many pixels join a neighbour",
    "min_piece": "Candidate pieces smaller than this many pixels join a neighbour",
}
_METHOD_TIPS = {
    "maoris": "MAORIS (Mielle et al. 2018): the authors' method; 'default' is what matching uses",
    "watershed": "Distance-transform watershed with saddle-ratio doors: best on robot occupancy maps",
    "learned": "MAORIS and watershed pieces merged by a trained classifier: best on sketches (slower)",
}


def method_names() -> list[str]:
    """The segmenters of the core's registry (``ursim_core.segmentation.SEGMENTERS``)."""
    from ursim_core.segmentation import SEGMENTERS

    return list(SEGMENTERS)


def preset_names(method: str = "maoris") -> list[str]:
    """Names of the presets of a segmenter known to the core."""
    from ursim_core.segmentation import method_presets

    return list(method_presets(method))


def preset_values(preset: str, method: str = "maoris") -> dict:
    """All parameter values of a segmenter's preset."""
    from ursim_core.segmentation import resolve_params

    return resolve_params(method, preset, None)


def _shown(method: str, values: dict) -> list[str]:
    if method == "maoris":
        return [name for name in _SHOWN_MAORIS if name in values]
    return [name for name, value in values.items() if type(value) in (int, float)]


class SideSegmentationBox(QGroupBox):
    """Method, preset, main parameters and the two buttons for one side.

    Signals
    -------
    segment_requested(str, str, str, dict) : side, method, preset, parameter overrides
    load_labels_requested(str) : side
    """

    segment_requested = Signal(str, str, str, dict)
    load_labels_requested = Signal(str)

    def __init__(self, side: str, parent=None):
        super().__init__(f"{side.capitalize()} map", parent)
        self.side = side
        self.method = QComboBox()
        self.method.setObjectName(f"{side}_method")
        for name in method_names():
            self.method.addItem(name)
            self.method.setItemData(self.method.count() - 1, _METHOD_TIPS.get(name, ""), Qt.ItemDataRole.ToolTipRole)
        self.preset = QComboBox()
        self.preset.setObjectName(f"{side}_preset")
        self.spins: dict[str, QSpinBox | QDoubleSpinBox] = {}
        self._spin_labels: list[QLabel] = []
        # Two parameters per row keeps both sides' boxes visible without scrolling.
        self.grid = QGridLayout()
        self.grid.addWidget(QLabel("Method"), 0, 0)
        self.grid.addWidget(self.method, 0, 1, 1, 3)
        self.grid.addWidget(QLabel("Preset"), 1, 0)
        self.grid.addWidget(self.preset, 1, 1, 1, 3)
        self.segment_button = QPushButton("Segment")
        self.segment_button.setObjectName(f"{side}_segment")
        self.load_button = QPushButton("Load label image…")
        self.load_button.setObjectName(f"{side}_load_labels")
        self.summary = QLabel("no segmentation")
        self.summary.setObjectName(f"{side}_summary")
        self.summary.setWordWrap(True)  # a segmentation with no region says why, at length
        buttons = QHBoxLayout()
        buttons.addWidget(self.segment_button)
        buttons.addWidget(self.load_button)
        layout = QVBoxLayout(self)
        layout.addLayout(self.grid)
        layout.addLayout(buttons)
        layout.addWidget(self.summary)
        self._fill_method("maoris", DEFAULT_PRESETS.get(side, "default"))
        self.method.currentTextChanged.connect(lambda method: self._fill_method(method, None))
        self.preset.currentTextChanged.connect(self._fill_from_preset)
        self.segment_button.clicked.connect(
            lambda: self.segment_requested.emit(
                self.side, self.method_name(), self.preset.currentText(), self.overrides()
            )
        )
        self.load_button.clicked.connect(lambda: self.load_labels_requested.emit(self.side))

    def method_name(self) -> str:
        """The segmenter chosen (a key of ``SEGMENTERS``)."""
        return self.method.currentText() or "maoris"

    def set_method(self, method: str, preset: str | None = None) -> None:
        """Show ``method`` (and ``preset``, else the method's default) as chosen."""
        if self.method.findText(method) < 0:
            return
        self.method.blockSignals(True)
        self.method.setCurrentText(method)
        self.method.blockSignals(False)
        self._fill_method(method, preset)

    def overrides(self) -> dict:
        """Parameters whose value differs from the selected preset."""
        base = preset_values(self.preset.currentText(), self.method_name())
        changed = {}
        for name, spin in self.spins.items():
            value = spin.value()
            if abs(value - base[name]) > 1e-9:
                changed[name] = type(base[name])(value)
        return changed

    def set_summary(self, text: str) -> None:
        self.summary.setText(text)

    def _fill_method(self, method: str, preset: str | None) -> None:
        """The presets and parameter fields of ``method``; ``preset`` chosen if it has one."""
        names = preset_names(method)
        self.method.setToolTip(_METHOD_TIPS.get(method, ""))
        self.preset.blockSignals(True)
        self.preset.clear()
        self.preset.addItems(names)
        self.preset.setCurrentIndex(max(0, self.preset.findText(preset)) if preset else 0)
        self.preset.blockSignals(False)
        for widget in [*self.spins.values(), *self._spin_labels]:
            self.grid.removeWidget(widget)
            widget.deleteLater()
        self.spins, self._spin_labels = {}, []
        values = preset_values(self.preset.currentText(), method)
        for name in _shown(method, values):
            spin = _spin_for(name, values[name])
            spin.setObjectName(f"{self.side}_{name}")
            spin.setToolTip(_TIPS.get(name, ""))
            label = QLabel(name.replace("_", " ").capitalize())
            row, column = divmod(len(self.spins), 2)
            self.grid.addWidget(label, row + 2, 2 * column)
            self.grid.addWidget(spin, row + 2, 2 * column + 1)
            self.spins[name] = spin
            self._spin_labels.append(label)
        self._fill_from_preset(self.preset.currentText())
        # Listeners (the session) hear the preset of the new method too.
        self.preset.currentTextChanged.emit(self.preset.currentText())

    def _fill_from_preset(self, preset: str) -> None:
        if not preset:
            return
        for name, value in preset_values(preset, self.method_name()).items():
            if name in self.spins:
                self.spins[name].setValue(value)


def _spin_for(name: str, value) -> QSpinBox | QDoubleSpinBox:
    if isinstance(value, float):
        spin = QDoubleSpinBox()
        spin.setDecimals(3)
        spin.setSingleStep(0.01)
        spin.setRange(0.0, 0.999 if name in ("threshold", "margin") else 1.0)
        return spin
    spin = QSpinBox()
    if name in ("ripples", "doors"):
        spin.setRange(0, 100 if name == "ripples" else 10_000)
        spin.setSuffix(" %")
    else:
        spin.setRange(0, 1_000_000)
        spin.setSuffix(" px")
    return spin


class SegmentationPanel(QWidget):
    """Both sides' boxes and the overlay display options.

    Signals
    -------
    opacity_changed(float)
    """

    opacity_changed = Signal(float)

    def __init__(self, display_actions: dict, parent=None):
        super().__init__(parent)
        self.boxes = {side: SideSegmentationBox(side) for side in ("sketch", "metric")}
        display = QGroupBox("Display")
        form = QFormLayout(display)
        self.opacity = QSlider(Qt.Orientation.Horizontal)
        self.opacity.setObjectName("overlay_opacity")
        self.opacity.setRange(0, 100)
        self.opacity.setValue(45)
        self.opacity.valueChanged.connect(lambda value: self.opacity_changed.emit(value / 100.0))
        form.addRow("Overlay opacity", self.opacity)
        self.toggles: dict[str, QCheckBox] = {}
        for key, action in display_actions.items():
            box = QCheckBox(action.text().replace("&", ""))
            box.setObjectName(f"toggle_{key}")
            box.setChecked(action.isChecked())
            box.setToolTip(action.toolTip())
            # Two-way sync with the View menu; setChecked with an equal value emits nothing.
            box.toggled.connect(action.setChecked)
            action.toggled.connect(box.setChecked)
            form.addRow(box)
            self.toggles[key] = box
        layout = QVBoxLayout(self)
        for box in self.boxes.values():
            layout.addWidget(box)
        layout.addWidget(display)
        layout.addStretch(1)
