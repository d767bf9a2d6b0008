"""Matching panel: m (auto or a value), descriptor variant, matcher, Match; last result summary."""

from __future__ import annotations

import math

from PySide6.QtCore import Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

__all__ = ["MatchingPanel", "VARIANTS", "MATCHERS", "describe_result"]

#: Descriptor variants (paper Table 1; T4 = URSIM) and matchers, as ``MatchConfig`` names them.
VARIANTS = (
    ("T4", "T4 – URSIM (anchors + weights)"),
    ("T3", "T3"),
    ("T2", "T2"),
    ("T1", "T1"),
    ("baseline", "baseline"),
)
MATCHERS = (("planar", "planar expansion"), ("hungarian", "Hungarian"), ("vf2", "VF2"))


def describe_result(result) -> str:
    """One-paragraph summary of a ``MatchResult`` for the panel."""
    if result is None:
        return "not matched yet"
    text = f"{len(result.pairs)} pairs, {len(result.anchors)} anchors, m = {result.m:.3f}"
    if math.isfinite(result.cost):
        text += f", cost {result.cost:.3g}"
    if result.reason:
        text += f"\n{result.reason}"
    return text


class MatchingPanel(QWidget):
    """Settings of the matcher and the Match button.

    Signals
    -------
    match_requested(object) : the ``ursim_core.matching.MatchConfig`` to run
    """

    match_requested = Signal(object)

    def __init__(self, parent=None):
        super().__init__(parent)
        box = QGroupBox("Matching")
        form = QFormLayout(box)
        self.m_auto = QCheckBox("auto")
        self.m_auto.setObjectName("match_m_auto")
        self.m_auto.setChecked(True)
        self.m_value = QDoubleSpinBox()
        self.m_value.setObjectName("match_m")
        self.m_value.setRange(0.0, 2.0)
        self.m_value.setDecimals(3)
        self.m_value.setSingleStep(0.025)
        self.m_value.setValue(0.1)
        self.m_value.setEnabled(False)
        self.m_auto.toggled.connect(lambda auto: self.m_value.setEnabled(not auto))
        m_row = QHBoxLayout()
        m_row.addWidget(self.m_auto)
        m_row.addWidget(self.m_value, 1)
        form.addRow("m", m_row)
        self.variant = _combo("match_variant", VARIANTS)
        self.matcher = _combo("match_matcher", MATCHERS)
        form.addRow("Variant", self.variant)
        form.addRow("Matcher", self.matcher)
        self.match_button = QPushButton("Match")
        self.match_button.setObjectName("match_button")
        self.match_button.clicked.connect(lambda: self.match_requested.emit(self.config()))
        form.addRow(self.match_button)
        self.summary = QLabel(describe_result(None))
        self.summary.setObjectName("match_summary")
        self.summary.setWordWrap(True)
        form.addRow(self.summary)
        layout = QVBoxLayout(self)
        layout.addWidget(box)
        layout.addStretch(1)

    def config(self):
        """The ``MatchConfig`` the widgets describe."""
        from ursim_core.matching import MatchConfig

        m = "auto" if self.m_auto.isChecked() else float(self.m_value.value())
        return MatchConfig(variant=self.variant.currentData(), matcher=self.matcher.currentData(), m=m)

    def set_ready(self, ready: bool) -> None:
        """Enable Match only when both maps are segmented and no job runs."""
        self.match_button.setEnabled(ready)

    def show_result(self, result) -> None:
        self.summary.setText(describe_result(result))


def _combo(name: str, items) -> QComboBox:
    combo = QComboBox()
    combo.setObjectName(name)
    for value, text in items:
        combo.addItem(text, value)
    return combo
