"""Matching panel: Match, the sketch's orientation, the last result, then the matcher's settings (m, variant,
matcher, scale, input kind, where a sketch's pairs come from and where it is laid).

The orientation buttons turn (90-degree steps or a free angle) and mirror the sketch
view and tell the matcher the orientation is known (when the core's ``MatchConfig`` has
``orientation`` / ``mirrored``; until then only the view turns).
"""

from __future__ import annotations

import dataclasses
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
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from ursim_core.matching.orientation import describe_gap
from ursim_gui.model.orientation import SketchOrientation
from ursim_gui.model.pair_settings import MAX_SCALE
from ursim_gui.model.wording import counted
from ursim_gui.views.orientation_bar import ORIENTATION_TIPS

__all__ = ["MatchingPanel", "VARIANTS", "MATCHERS", "INPUT_KINDS", "PAIRS_FROM", "describe_result"]

#: Descriptor variants (paper Table 1; T4 = URSIM) and matchers, as ``MatchConfig`` names them.
VARIANTS = (
    ("T4", "T4 – URSIM (anchors + weights)"),
    ("T3", "T3"),
    ("T2", "T2"),
    ("T1", "T1"),
    ("baseline", "baseline"),
)
MATCHERS = (
    ("auto", "automatic (planar for a sketch, overlay for a metric map)"),
    ("planar", "planar expansion"),
    ("hungarian", "Hungarian"),
    ("vf2", "VF2"),
    ("overlay", "overlay (two metric maps)"),
)
#: What the input map is, for the automatic matcher (``MatchConfig.input_kind``).
INPUT_KINDS = (
    (None, "unknown (a sketch, unless the scale is known)"),
    ("sketch", "a sketch (drawn by hand)"),
    ("metric", "a robot map or a plan to scale"),
)
#: Where a sketch's pairs come from (``MatchConfig.elastic``): the planar matcher reads the
#: orientation either way.
PAIRS_FROM = (
    ("completed", "the sketch laid and bent onto the map, completed by the graph"),
    ("alone", "the sketch laid and bent onto the map only"),
    ("off", "the graph matcher's own answer"),
)
#: Where the sketch is laid before it is bent (``MatchConfig.elastic_laying``; its default first).
LAYINGS = (
    ("window", "box onto box, or the part of the map it resembles most (a partial sketch)"),
    ("boxes", "box onto box only (a sketch of the whole map)"),
    ("boxes_or_answer", "box onto box or where the graph answer puts it (slower)"),
    ("window_or_answer", "the window or where the graph answer puts it (slowest)"),
    ("boxes_or_window", "box onto box or the part of the map it resembles, whichever fits (slower)"),
)
#: Characters a settings list shows when the panel is at its narrowest.
_COMBO_CHARACTERS = 18
#: The matchers that use a known scale; those whose pairs may come from the laid sketch.
_SCALED_MATCHERS = ("auto", "overlay")
_ELASTIC_MATCHERS = ("auto", "planar")


def orientation_read(result, *, automatic_cliques: int = 0, record=None):
    """How the matcher read the sketch: from the result in memory, else from the file's ``matcher``
    record while the file holds automatic cliques; None when it was told the orientation."""
    if result is not None:
        return SketchOrientation.found_in(result)
    return SketchOrientation.found_in_record(record) if automatic_cliques else None


def describe_result(result, *, automatic_cliques: int = 0, record=None) -> str:
    """One-paragraph summary of a ``MatchResult`` for the panel.

    Without a result in memory (a document reopened from its file), ``automatic_cliques`` says
    whether the file already holds the matcher's answer, and ``record`` (the file's ``matcher``
    record) how the matcher read the sketch.

    Examples
    --------
    >>> describe_result(None), describe_result(None, automatic_cliques=6)
    ('not matched yet', '6 automatic cliques from the file (press Match to run the matcher again)')
    """
    if result is None:
        if not automatic_cliques:
            return "not matched yet"
        text = f"{counted(automatic_cliques, 'automatic clique')} from the file (press Match to run the matcher again)"
    else:
        text = f"{counted(len(result.pairs), 'pair')}, {counted(len(result.anchors), 'anchor')}, m = {result.m:.3f}"
        if math.isfinite(result.cost):
            text += f", cost {result.cost:.3g}"
        if getattr(result, "resampling_votes", 0):
            # The pairs are a vote; m and the cost are the first segmentation's answer's.
            text += f"\nvoted over {counted(result.resampling_votes, 'resampling')} of the turned sketch"
        if getattr(result, "laid", False):
            # m and the cost are the planar matcher's, which read the orientation.
            text += "\npairs from the sketch laid and bent onto the map"
            from ursim_core.matching.results import laid_by

            if laid_by(result) == "answer":
                text += ", laid where the graph answer puts it"
            elif laid_by(result) == "window":
                text += ", laid on the part of the map it resembles most"
    found = orientation_read(result, automatic_cliques=automatic_cliques, record=record)
    if found is not None:
        text += f"\nread the sketch {found.describe()}"
        runner_up = SketchOrientation.runner_up_in(result, None if result is not None else record)
        if runner_up is not None:
            # How close the matcher came to reading it otherwise: a small gap asks for a look.
            other, gap = runner_up
            text += f"\nnext best: {other.describe()}, {describe_gap(gap)}"
    if result is not None and result.reason:
        text += f"\n{result.reason}"
    return text


class MatchingPanel(QWidget):
    """Settings of the matcher and the Match button.

    Signals
    -------
    match_requested(object) : the ``ursim_core.matching.MatchConfig`` to run
    """

    match_requested = Signal(object)
    #: The sketch orientation changed (a :class:`~ursim_gui.model.orientation.SketchOrientation`).
    orientation_changed = Signal(object)
    #: Whether a runner-up reading, or readings to compare, are offered may have changed
    #: (:meth:`runner_up_offered`, :meth:`readings_offered`).
    runner_up_changed = Signal()
    #: The user asked to compare the readings side by side (:attr:`readings`).
    readings_requested = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        # Match and the sketch's orientation come first: the dock is short and scrolls, and a
        # review comes back to them after every few edits; the settings below are set once a pair.
        self.match_button = QPushButton("Match")
        self.match_button.setObjectName("match_button")
        self.match_button.setStyleSheet("font-weight: 600;")
        self.match_button.setToolTip(
            "Run the matcher (Ctrl+M). Cliques you linked, accepted or rejected are kept: the answer contains "
            "your pairs and never proposes a rejected one again; pending automatic cliques are replaced."
        )
        self.match_button.clicked.connect(lambda: self.match_requested.emit(self.config()))
        self.summary = QLabel(describe_result(None))
        self.summary.setObjectName("match_summary")
        self.summary.setWordWrap(True)
        orientation_box = QGroupBox("Sketch orientation")
        orientation_form = QFormLayout(orientation_box)
        settings_box = QGroupBox("Matcher settings")
        form = QFormLayout(settings_box)
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
        # The known scale (metric pixels per input pixel; 0 = unknown): with it, 'auto' overlays.
        self.scale = QDoubleSpinBox()
        self.scale.setObjectName("match_scale")
        self.scale.setRange(0.0, MAX_SCALE)
        self.scale.setDecimals(3)
        self.scale.setSingleStep(0.05)
        self.scale.setSpecialValueText("unknown (estimated)")
        self.scale.setValue(0.0)
        self._add_option(
            form,
            "Scale",
            self.scale,
            _SCALED_MATCHERS,
            "Metric-map pixels per input-map pixel when known (1 for two robot maps of one resolution): "
            "the automatic matcher then lays the maps on each other (overlay), and the input may cover "
            "any part of the metric map; leave it unknown for a sketch",
        )
        # What the input map is: a robot map makes the automatic matcher overlay the maps (a
        # campaign of robot maps says so for each pair).
        self.input_kind = _combo("match_input_kind", INPUT_KINDS)
        self._add_option(
            form,
            "Input",
            self.input_kind,
            ("auto",),
            "What the input (left) map is: a robot map or a plan drawn to scale makes the automatic "
            "matcher lay the maps on each other (overlay); a sketch is matched by its structure (planar)",
        )
        self.pairs_from = _combo("match_pairs_from", PAIRS_FROM)
        self._add_option(
            form,
            "Pairs",
            self.pairs_from,
            _ELASTIC_MATCHERS,
            "Where a sketch's pairs come from once the planar matcher has read its orientation: the "
            "sketch laid on the map by its box and bent by an optical flow, regions paired where they "
            "overlap (hand-drawn rooms out of proportion still land on theirs), or the graph matcher's "
            "own answer",
        )
        self.laying = _combo("match_laying", LAYINGS)
        self._add_option(
            form,
            "Laying",
            self.laying,
            _ELASTIC_MATCHERS,
            "Where the sketch is laid before it is bent: box onto box stretches a sketch of part of the "
            "map over all of it; the window is the part of the map the sketch resembles most, used when it "
            "resembles it clearly better than the whole map; the graph answer's pairs lay it where they put it, "
            "and the laying whose bent sketch lands more on the map's free space is kept (a second optical flow "
            "per match)",
        )
        self.partial = QCheckBox("the sketch shows only part of the map")
        self.partial.setObjectName("match_partial")
        self._add_option(
            form,
            "Part",
            self.partial,
            _ELASTIC_MATCHERS,
            "For a sketch of part of the map: lay it in the part of the map it resembles or box onto box, "
            "whichever lands better (the Laying above), read its orientation where it resembles a part of "
            "the map, and start placing its regions there. Off for a whole sketch: a whole hand-drawn sketch "
            "can land better in a window that pairs it worse. Left off, the matcher still does this when it "
            "lays the sketch in part of the map (the answer's reason then says so)",
        )
        self.partial.toggled.connect(self._lay_partial)
        self.orientation = SketchOrientation()
        # Tool buttons, not push buttons: the style's minimum push-button width would make this
        # row, and so the whole right column, wider than the rest of the panel.
        self.turn_left = _tool_button("⟲ 90°", "orient_left", ORIENTATION_TIPS["left"])
        self.turn_right = _tool_button("⟳ 90°", "orient_right", ORIENTATION_TIPS["right"])
        self.angle = QDoubleSpinBox()
        self.angle.setObjectName("orient_angle")
        self.angle.setRange(0.0, 359.9)
        self.angle.setDecimals(1)
        self.angle.setSuffix("°")
        self.angle.setWrapping(True)
        self.angle.setToolTip("Free angle, counter-clockwise")
        self.mirror = QCheckBox("mirror")
        self.mirror.setObjectName("orient_mirror")
        self.mirror.setToolTip(ORIENTATION_TIPS["mirror"])
        self.unknown = _tool_button("unknown", "orient_unknown", "Let the matcher try every orientation")
        orient_row = QHBoxLayout()
        for widget in (self.turn_left, self.turn_right, self.angle, self.mirror, self.unknown):
            orient_row.addWidget(widget)
        orient_row.addStretch(1)
        orientation_form.addRow(orient_row)
        self.orientation_label = QLabel("")
        self.orientation_label.setObjectName("orient_summary")
        self.orientation_label.setWordWrap(True)
        orientation_form.addRow(self.orientation_label)
        # The orientation the last match found, offered as the known one: the view turns to it and
        # the next match is told it (shown only while it differs from the orientation set).
        self.found_orientation: SketchOrientation | None = None
        self.keep_found = _row_button(
            orientation_form,
            "orient_keep_found",
            "Turn the sketch view to the orientation the matcher read and tell the matcher it from now on",
            lambda: self.set_orientation(self.found_orientation or self.orientation),
        )
        # The reading the matcher ranked next, one click away: of the 27 generated partial sketches
        # misread (seeds 0-127), 16 are read right in it (docs/studies.md, round 54).
        self.runner_up: SketchOrientation | None = None
        self.try_runner_up = _row_button(
            orientation_form,
            "orient_try_runner_up",
            "Tell the matcher the reading it ranked next and match again (Undo gives the last answer "
            "back; 'unknown' lets the matcher choose the orientation again)",
            self.match_runner_up,
        )
        # Every reading the matcher ranked, kept while the user matches in them one by one (a told
        # match ranks none), until a match ranks readings again or the orientation leaves them.
        self.readings: list[tuple[SketchOrientation, float]] = []
        #: The reading of the answer shown now (the one the last match laid the sketch in).
        self.answer_reading: SketchOrientation | None = None
        self.compare_readings = _row_button(
            orientation_form,
            "orient_compare_readings",
            "See the sketch turned as each reading the matcher ranked, beside the metric map, and "
            "match in the one that fits",
            self.readings_requested,
        )
        self.turn_left.clicked.connect(lambda: self.turn(90))
        self.turn_right.clicked.connect(lambda: self.turn(-90))
        self.angle.editingFinished.connect(lambda: self.set_orientation(self.orientation.at(self.angle.value())))
        self.mirror.clicked.connect(self.set_mirrored)
        self.unknown.clicked.connect(lambda: self.set_orientation(SketchOrientation()))
        self._show_orientation()
        layout = QVBoxLayout(self)
        for widget in (self.match_button, orientation_box, self.summary, settings_box):
            layout.addWidget(widget)
        layout.addStretch(1)

    def _add_option(self, form: QFormLayout, label: str, widget: QWidget, matchers, tooltip: str) -> None:
        """Add a row of ``form`` for an option that applies only to some matchers: ``widget`` is
        enabled only while the matcher chosen is one of ``matchers``."""
        widget.setToolTip(tooltip)
        form.addRow(label, widget)
        widget.setEnabled(self.matcher.currentData() in matchers)
        self.matcher.currentIndexChanged.connect(lambda _: widget.setEnabled(self.matcher.currentData() in matchers))

    def _lay_partial(self, partial: bool) -> None:
        """A partial sketch's laying chosen in the Laying list (which a person may change again);
        the default laying back when the box is cleared, if that laying is still chosen."""
        from ursim_core.matching import MatchConfig
        from ursim_core.matching.config import PARTIAL_SKETCH

        wanted = PARTIAL_SKETCH["elastic_laying"] if partial else MatchConfig().elastic_laying
        if partial or self.laying.currentData() == PARTIAL_SKETCH["elastic_laying"]:
            self.laying.setCurrentIndex(self.laying.findData(wanted))

    def config(self):
        """The ``MatchConfig`` the widgets describe."""
        from ursim_core.matching import MatchConfig
        from ursim_core.matching.config import PARTIAL_SKETCH

        m = "auto" if self.m_auto.isChecked() else float(self.m_value.value())
        fields = {field.name for field in dataclasses.fields(MatchConfig)}
        matcher = self.matcher.currentData()
        extra = {}
        if matcher in _SCALED_MATCHERS and self.scale.value() > 0:
            extra["scale"] = float(self.scale.value())
        if matcher == "auto" and self.input_kind.currentData() is not None:
            extra["input_kind"] = self.input_kind.currentData()
        if matcher in _ELASTIC_MATCHERS and self.partial.isChecked():
            # The laying is the Laying list's own choice (see _lay_partial); the rest as told.
            extra.update({name: value for name, value in PARTIAL_SKETCH.items() if name != "elastic_laying"})
        return MatchConfig(
            variant=self.variant.currentData(),
            matcher=matcher,
            m=m,
            elastic=self.pairs_from.currentData(),
            elastic_laying=self.laying.currentData(),
            **self.orientation.match_options(fields),
            **extra,
        )

    def turn(self, degrees: float) -> None:
        """Turn the sketch ``degrees`` counter-clockwise from the orientation set (the panel's
        buttons and the sketch view's)."""
        self.set_orientation(self.orientation.turned(degrees))

    def set_mirrored(self, mirrored: bool) -> None:
        """Mirror the sketch left-right, or not (the panel's box and the sketch view's button)."""
        self.set_orientation(self.orientation.with_mirror(bool(mirrored)))

    def set_orientation(self, orientation: SketchOrientation) -> None:
        """Show and announce a new sketch orientation."""
        if orientation == self.orientation:
            return
        self.orientation = orientation
        self._show_orientation()
        self.orientation_changed.emit(orientation)

    def _show_orientation(self) -> None:
        orientation = self.orientation
        self.angle.blockSignals(True)
        self.angle.setValue(orientation.angle or 0.0)
        self.angle.blockSignals(False)
        self.mirror.setChecked(orientation.mirrored)
        if not orientation.known:
            self.orientation_label.setText("orientation unknown: the matcher tries them")
        else:
            self.orientation_label.setText(f"known: {orientation.describe()}")
        found = self.found_orientation
        self.keep_found.setVisible(found is not None and found != orientation)
        if found is not None:
            # Two lines: a reading on the same line made the panel, and its dock, 100 px wider.
            self.keep_found.setText(f"Keep the orientation read:\n{found.describe()}")
        self.try_runner_up.setVisible(self.runner_up_offered())
        if self.runner_up is not None:
            self.try_runner_up.setText(f"Match as read next best:\n{self.runner_up.describe()}")
        self.compare_readings.setVisible(self.readings_offered())
        self.compare_readings.setText(f"Compare the {len(self.readings)} readings…")
        self.runner_up_changed.emit()

    def runner_up_offered(self) -> bool:
        """Whether the last match ranked another reading next, not the orientation set now."""
        return self.runner_up is not None and self.runner_up != self.orientation

    def readings_offered(self) -> bool:
        """Whether the last match that chose the orientation ranked more than one reading."""
        return len(self.readings) > 1

    def match_runner_up(self) -> None:
        """Tell the matcher the runner-up reading (the view turns to it) and ask for a match;
        nothing when none is offered."""
        if self.runner_up_offered():
            self.match_reading(self.runner_up)

    def match_reading(self, reading: SketchOrientation) -> None:
        """Tell the matcher ``reading`` (the view turns to it) and ask for a match."""
        self.set_orientation(reading)
        self.match_requested.emit(self.config())

    def set_input_kind(self, kind: str | None) -> None:
        """Say what the input map is (None = unknown; see :data:`INPUT_KINDS`)."""
        self.input_kind.setCurrentIndex(max(0, self.input_kind.findData(kind)))

    def set_scale(self, scale: float | None) -> None:
        """Say the known scale (metric pixels per input pixel; None = unknown, estimated)."""
        self.scale.setValue(0.0 if scale is None else float(scale))

    def set_ready(self, ready: bool) -> None:
        """Enable Match only when both maps are segmented and no job runs."""
        self.match_button.setEnabled(ready)
        self.try_runner_up.setEnabled(ready)
        self.compare_readings.setEnabled(ready)

    def show_result(self, result, *, automatic_cliques: int = 0, record=None) -> None:
        """Summarise the last match, or the file's (``record``: its ``matcher`` record) without one."""
        self.summary.setText(describe_result(result, automatic_cliques=automatic_cliques, record=record))
        self.found_orientation = orientation_read(result, automatic_cliques=automatic_cliques, record=record)
        # Offered only beside a reading the matcher chose (as the summary names it).
        runner_up = SketchOrientation.runner_up_in(result, None if result is not None else record)
        self.runner_up = runner_up[0] if runner_up is not None and self.found_orientation is not None else None
        self.answer_reading = SketchOrientation.laid_in(result, record if automatic_cliques else None)
        readings = SketchOrientation.readings_in(result, None if result is not None else record)
        if readings and self.found_orientation is not None:
            self.readings = readings
        elif self.answer_reading is None or self.answer_reading not in [reading for reading, _ in self.readings]:
            self.readings = []
        self._show_orientation()


def _row_button(form: QFormLayout, name: str, tooltip: str, slot) -> QPushButton:
    """A button of its own row of ``form`` whose text says what it offers (set when it is shown)."""
    button = QPushButton("")
    button.setObjectName(name)
    button.setToolTip(tooltip)
    button.clicked.connect(slot)
    form.addRow(button)
    return button


def _tool_button(text: str, name: str, tooltip: str) -> QToolButton:
    button = QToolButton()
    button.setText(text)
    button.setObjectName(name)
    button.setToolTip(tooltip)
    return button


def _combo(name: str, items) -> QComboBox:
    combo = QComboBox()
    combo.setObjectName(name)
    # As narrow as a few words, not as the longest choice (which sized the whole right column):
    # the list that opens shows every choice in full.
    combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
    combo.setMinimumContentsLength(_COMBO_CHARACTERS)
    for value, text in items:
        combo.addItem(text, value)
    return combo
