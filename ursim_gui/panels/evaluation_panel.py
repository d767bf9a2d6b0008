"""Evaluation panel: load a reference (.json or .dat), live precision / recall / F1, clickable misses.

The score is the session's (recomputed by the model on every change); the panel only
shows it. Loading the file is the main window's job (it owns dialogs and errors).
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

__all__ = ["EvaluationPanel", "format_regions"]


def format_regions(regions) -> str:
    """``{3, 1}`` -> ``'1, 3'``."""
    return ", ".join(str(r) for r in sorted(regions))


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
        self.source = QLabel("no reference loaded")
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
        if reference is None or score is None:
            self.source.setText("no reference loaded")
            for label in self.values.values():
                label.setText("–")
            self.missed.clear()
            return
        self.source.setText(f"{len(reference)} reference cliques")
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
            self.values["place"].setText(f"{place.accuracy:.3f} ({place.successes} / {place.n_points} points)")
        self.missed.clear()
        for index in self._session.missed_reference():
            sketch, metric = reference[index]
            item = QListWidgetItem(f"{format_regions(sketch)}  ↔  {format_regions(metric)}")
            item.setData(Qt.ItemDataRole.UserRole, index)
            item.setToolTip("Click to select these regions on both maps")
            self.missed.addItem(item)

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
