"""Agreement panel: pick a second annotator, per-pair and whole-set F1 / place accuracy, CSV export.

A thin view: the rows are :class:`~ursim_gui.model.agreement.PairAgreement` values the
agreement controller computes; the panel only lays them out.
"""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from ursim_gui.model.agreement import COMPARISONS, pooled
from ursim_gui.model.wording import counted

__all__ = ["AgreementPanel", "FOLDER_CHOICE"]

#: What the ceiling columns are (their header's tooltip).
CEILING_TIP = (
    "The one-to-one answer with the best mean F1 against A and B at once: "
    "what any matcher can reach where the annotators disagree"
)
#: The combo entry that asks for a folder of the second annotator's JSON files.
FOLDER_CHOICE = "Folder of JSON files…"


def _text(value) -> str:
    return "–" if value is None else f"{value:.3f}"


class AgreementPanel(QWidget):
    """Second annotator, Compute, Export CSV, and the table of comparisons.

    Signals
    -------
    second_chosen(str) : an annotator name, or :data:`FOLDER_CHOICE`
    compute_requested() ; export_requested()
    """

    second_chosen = Signal(str)
    compute_requested = Signal()
    export_requested = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.second = QComboBox()
        self.second.setObjectName("agreement_second")
        self.compute_button = QPushButton("Compute for the campaign")
        self.compute_button.setObjectName("agreement_compute")
        self.export_button = QPushButton("Export CSV…")
        self.export_button.setObjectName("agreement_export")
        self.export_button.setEnabled(False)
        self.note = QLabel("Open a campaign, then pick the second annotator (B). A = your files.")
        self.note.setWordWrap(True)
        self.table = QTableWidget(0, 1 + 2 * len(COMPARISONS))
        self.table.setObjectName("agreement_table")
        headers = ["Pair"]
        for label, _c, _r in COMPARISONS:
            headers += [f"F1 {label}", f"place {label}"]
        self.table.setHorizontalHeaderLabels(headers)
        for column, (_label, claimed, _r) in enumerate(COMPARISONS):
            if claimed == "ceiling":
                for offset in (1, 2):
                    self.table.horizontalHeaderItem(offset + 2 * column).setToolTip(CEILING_TIP)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.verticalHeader().setVisible(False)
        top = QHBoxLayout()
        top.addWidget(QLabel("Second annotator (B):"))
        top.addWidget(self.second, 1)
        buttons = QHBoxLayout()
        buttons.addWidget(self.compute_button)
        buttons.addWidget(self.export_button)
        layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addLayout(buttons)
        layout.addWidget(self.note)
        layout.addWidget(self.table, 1)
        self.second.activated.connect(lambda _index: self.second_chosen.emit(self.second.currentText()))
        self.compute_button.clicked.connect(self.compute_requested)
        self.export_button.clicked.connect(self.export_requested)

    def set_choices(self, annotators: list[str]) -> None:
        self.second.clear()
        self.second.addItems(["(none)", *annotators, FOLDER_CHOICE])

    def show_rows(self, rows) -> None:
        """One line per pair, then the whole set ('ALL', pooled)."""
        lines = [(row.name, row.comparisons) for row in rows] + [("ALL", pooled(list(rows)))]
        self.table.setRowCount(len(lines))
        for index, (name, comparisons) in enumerate(lines):
            self.table.setItem(index, 0, QTableWidgetItem(name))
            for column, (label, _c, _r) in enumerate(COMPARISONS):
                value = comparisons.get(label)
                self.table.setItem(index, 1 + 2 * column, QTableWidgetItem(_text(value and value.f1)))
                self.table.setItem(index, 2 + 2 * column, QTableWidgetItem(_text(value and value.place)))
        self.export_button.setEnabled(bool(rows))
        # No place accuracy without the segmentations it is read on: no empty columns then.
        has_place = any(value.place is not None for _name, comparisons in lines for value in comparisons.values())
        for column in range(len(COMPARISONS)):
            self.table.setColumnHidden(2 + 2 * column, not has_place)
        self.table.resizeColumnsToContents()

    def show_second(self, name: str, pairs: int | None = None) -> None:
        """Reflect the chosen second annotator (also when chosen by code)."""
        index = self.second.findText(name)
        if index >= 0:
            self.second.setCurrentIndex(index)
        elif name:
            self.second.insertItem(self.second.count() - 1, name)
            self.second.setCurrentIndex(self.second.count() - 2)
        suffix = "" if pairs is None else f": {counted(pairs, 'pair')} compared"
        self.note.setText(
            f"A = your files, B = {name or '(none)'}{suffix}. On the maps: FP = A's clique B does not share, FN = B's clique A misses."
        )

    def cell(self, row: int, column: int) -> str:
        item = self.table.item(row, column)
        return "" if item is None else item.text()
