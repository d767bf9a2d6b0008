"""Evaluation panel: load a reference (.json or .dat), live precision / recall / F1, clickable misses.

The score is the session's (recomputed by the model on every change); the panel only
shows it, and names the reference it scores against. Loading the file is the main window's
job (it owns dialogs and errors).
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSizePolicy,
    QVBoxLayout,
    QWidget,
)

from ursim_gui.model.wording import counted

__all__ = ["EvaluationPanel", "ElidedLabel", "format_regions"]


def format_regions(regions) -> str:
    """``{3, 1}`` -> ``'1, 3'``."""
    return ", ".join(str(r) for r in sorted(regions))


class ElidedLabel(QLabel):
    """A one-line label that elides its text in the middle to the width it is given, instead of
    widening its panel: a file name keeps its start and its extension."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self._full_text = ""
        # Its own text as elided would be its minimum width, and it could never shrink again.
        self.setMinimumWidth(1)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)

    def full_text(self) -> str:
        return self._full_text

    def set_full_text(self, text: str) -> None:
        self._full_text = text
        self._elide()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._elide()

    def _elide(self) -> None:
        self.setText(self.fontMetrics().elidedText(self._full_text, Qt.TextElideMode.ElideMiddle, self.width()))


class EvaluationPanel(QWidget):
    """Shows the session's evaluation against its reference.

    Signals
    -------
    load_requested() : the user wants to pick a reference file
    """

    load_requested = Signal()

    def __init__(self, session, parent=None):
        super().__init__(parent)
        self._session = session
        box = QGroupBox("Evaluation against a reference")
        self.load_button = QPushButton("Load reference…")
        self.load_button.setObjectName("eval_load")
        self.clear_button = QPushButton("Clear")
        self.clear_button.setObjectName("eval_clear")
        buttons = QHBoxLayout()
        buttons.addWidget(self.load_button)
        buttons.addWidget(self.clear_button)
        # Which file the scores are against (two annotators' files look alike by their counts).
        self.reference_name = ElidedLabel()
        self.reference_name.setObjectName("eval_reference")
        self.source = QLabel("no reference loaded")
        self.source.setObjectName("eval_source")
        self.source.setWordWrap(True)
        self.values = {name: QLabel("–") for name in ("precision", "recall", "f1", "counts", "place")}
        for name, label in self.values.items():
            label.setObjectName(f"eval_{name}")
        form = QFormLayout()
        form.addRow("Precision", self.values["precision"])
        form.addRow("Recall", self.values["recall"])
        form.addRow("F1", self.values["f1"])
        form.addRow("TP / FP / FN", self.values["counts"])
        place_label = QLabel("Place accuracy")
        place_label.setToolTip(
            "Would a robot sent to each sketched reference point reach the annotated place? "
            "(interior point of the largest matched metric region; mean over a clique's points, then cliques)"
        )
        form.addRow(place_label, self.values["place"])
        self.missed = QListWidget()
        self.missed.setObjectName("eval_missed")
        inner = QVBoxLayout(box)
        inner.addLayout(buttons)
        inner.addWidget(self.reference_name)
        inner.addWidget(self.source)
        inner.addLayout(form)
        inner.addWidget(QLabel("Missed reference cliques (sketch ↔ metric)"))
        inner.addWidget(self.missed, 1)
        layout = QVBoxLayout(self)
        layout.addWidget(box)
        self.load_button.clicked.connect(self.load_requested)
        self.clear_button.clicked.connect(lambda: self._session.clear_reference())
        self.missed.itemClicked.connect(self._select_missed)
        session.reference_changed.connect(self.refresh)
        session.correspondences_changed.connect(self.refresh)
        self.refresh()

    def refresh(self, *_args) -> None:
        """Re-read the score, the reference and the misses from the session."""
        reference = self._session.reference
        score = self._session.evaluation
        self.clear_button.setEnabled(reference is not None)
        self._name_reference(reference is not None)
        if reference is None or score is None:
            self.source.setText("no reference loaded")
            for label in self.values.values():
                label.setText("–")
            self.missed.clear()
            return
        self.source.setText(counted(len(reference), "reference clique"))
        # A ratio over nothing is undefined, not perfect: no pairs means no precision, and
        # a reference none of whose cliques falls on a region means no recall.
        predicted, findable = score.tp + score.fp, score.tp + score.fn
        self.values["precision"].setText(f"{score.precision:.3f}" if predicted else "– (no matched pairs)")
        self.values["recall"].setText(f"{score.recall:.3f}" if findable else "– (nothing to find)")
        self.values["f1"].setText(f"{score.f1:.3f}" if predicted and findable else "–")
        self.values["counts"].setText(f"{score.tp} / {score.fp} / {score.fn}")
        place = self._session.place
        if place is None or place.accuracy != place.accuracy:  # None or NaN: no clique could be scored
            self.values["place"].setText("– (no clique with points on both maps)")
        else:
            points = counted(place.n_points, "point")
            self.values["place"].setText(f"{place.accuracy:.3f} ({place.successes} / {points})")
        self.missed.clear()
        for index in self._session.missed_reference():
            sketch, metric = reference[index]
            item = QListWidgetItem(f"{format_regions(sketch)}  ↔  {format_regions(metric)}")
            item.setData(Qt.ItemDataRole.UserRole, index)
            item.setToolTip("Click to select these regions on both maps")
            self.missed.addItem(item)

    def _name_reference(self, loaded: bool) -> None:
        """Name the reference scored against: its file (elided, the whole path in the tooltip) and
        who annotated it."""
        path = self._session.reference_path if loaded else None
        annotator = self._session.reference_correspondences.annotator if loaded else ""
        name = f"Reference: {Path(path).name}" if path else "Reference"
        self.reference_name.set_full_text(f"{name} by {annotator}" if annotator else name)
        self.reference_name.setToolTip(str(path) if path else self.reference_name.full_text())
        self.reference_name.setVisible(bool(path or annotator))

    def _select_missed(self, item: QListWidgetItem) -> None:
        """Select a missed reference clique's regions on both maps (then L links them)."""
        reference = self._session.reference
        index = item.data(Qt.ItemDataRole.UserRole)
        if reference is None or index is None or index >= len(reference):
            return
        sketch, metric = reference[index]
        self._session.clear_selection()
        self._session.select("sketch", sorted(sketch))
        self._session.select("metric", sorted(metric))
