"""Segmentation panel: per side preset, parameters, Segment / Load label image; display options.

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

__all__ = ["SegmentationPanel", "SideSegmentationBox", "preset_names", "preset_values"]

_log = logging.getLogger(__name__)

#: Parameters shown in the panel (the others keep their preset value).
_SHOWN = ("threshold", "margin", "ripples", "doors")
_TIPS = {
    "threshold": "Watershed relative-difference threshold t in [0, 1): higher merges more",
    "margin": "Extra watershed tolerance when a close neighbour exists, in [0, 1)",
    "ripples": "Percent of a zone's contour touching a neighbour that makes it a ripple of it",
    "doors": "Percent of a region's contour touching other regions above which it is a door and is fused",
}


def preset_names() -> list[str]:
    """Names of the MAORIS presets known to the core."""
    from ursim_core.segmentation.maoris import PRESETS

    return list(PRESETS)


def preset_values(preset: str) -> dict:
    """All parameter values of a preset."""
    from ursim_core.segmentation import resolve_params

    return resolve_params("maoris", preset, None)


class SideSegmentationBox(QGroupBox):
    """Preset, main parameters and the two buttons for one side.

    Signals
    -------
    segment_requested(str, str, dict) : side, preset, parameter overrides
    load_labels_requested(str) : side
    """

    segment_requested = Signal(str, str, dict)
    load_labels_requested = Signal(str)

    def __init__(self, side: str, parent=None):
        super().__init__(f"{side.capitalize()} map", parent)
        self.side = side
        self.preset = QComboBox()
        self.preset.setObjectName(f"{side}_preset")
        self.preset.addItems(preset_names())
        self.spins: dict[str, QSpinBox | QDoubleSpinBox] = {}
        # Two parameters per row keeps both sides' boxes visible without scrolling.
        grid = QGridLayout()
        grid.addWidget(QLabel("Preset"), 0, 0)
        grid.addWidget(self.preset, 0, 1, 1, 3)
        for name, value in preset_values(self.preset.itemText(0)).items():
            if name not in _SHOWN:
                continue
            spin = QDoubleSpinBox() if isinstance(value, float) else QSpinBox()
            if isinstance(spin, QDoubleSpinBox):
                spin.setDecimals(3)
                spin.setSingleStep(0.01)
                spin.setRange(0.0, 0.999)
            else:
                spin.setRange(0, 100 if name == "ripples" else 10_000)
                spin.setSuffix(" %")
            spin.setObjectName(f"{side}_{name}")
            spin.setToolTip(_TIPS.get(name, ""))
            row, column = divmod(len(self.spins), 2)
            grid.addWidget(QLabel(name.replace("_", " ").capitalize()), row + 1, 2 * column)
            grid.addWidget(spin, row + 1, 2 * column + 1)
            self.spins[name] = spin
        self.segment_button = QPushButton("Segment")
        self.segment_button.setObjectName(f"{side}_segment")
        self.load_button = QPushButton("Load label image…")
        self.load_button.setObjectName(f"{side}_load_labels")
        self.summary = QLabel("no segmentation")
        self.summary.setObjectName(f"{side}_summary")
        buttons = QHBoxLayout()
        buttons.addWidget(self.segment_button)
        buttons.addWidget(self.load_button)
        layout = QVBoxLayout(self)
        layout.addLayout(grid)
        layout.addLayout(buttons)
        layout.addWidget(self.summary)
        self.preset.currentTextChanged.connect(self._fill_from_preset)
        index = self.preset.findText(DEFAULT_PRESETS.get(side, "default"))
        self.preset.setCurrentIndex(max(0, index))
        self._fill_from_preset(self.preset.currentText())
        self.segment_button.clicked.connect(
            lambda: self.segment_requested.emit(self.side, self.preset.currentText(), self.overrides())
        )
        self.load_button.clicked.connect(lambda: self.load_labels_requested.emit(self.side))

    def overrides(self) -> dict:
        """Parameters whose value differs from the selected preset."""
        base = preset_values(self.preset.currentText())
        changed = {}
        for name, spin in self.spins.items():
            value = spin.value()
            if abs(value - base[name]) > 1e-9:
                changed[name] = type(base[name])(value)
        return changed

    def set_summary(self, text: str) -> None:
        self.summary.setText(text)

    def _fill_from_preset(self, preset: str) -> None:
        if not preset:
            return
        for name, value in preset_values(preset).items():
            if name in self.spins:
                self.spins[name].setValue(value)


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
