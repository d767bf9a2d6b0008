"""Correspondence table: a QAbstractTableModel adapter over the session and its view.

Rows are the session's cliques in file order. The adapter reads the session on every
change signal (it keeps no copy of the annotations); selecting a row selects the clique
in the session, and a selection made elsewhere (a click in a map) selects the row.
"""

from __future__ import annotations

from PySide6.QtCore import QAbstractTableModel, QItemSelectionModel, QModelIndex, Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QTableView, QVBoxLayout, QWidget

from ursim_core.correspondences.exporters import clique_label

__all__ = ["CorrespondenceTableModel", "CorrespondenceTable", "COLUMNS"]

COLUMNS = ("Clique", "Sketch", "Metric", "Source", "Score", "Status", "Eval", "Label", "Note")
#: What the terse headers stand for (the header's tooltip).
_HEADER_TIPS = {
    "Sketch": "The clique's regions on the sketch",
    "Metric": "The clique's regions on the metric map",
    "Source": "auto: the matcher's pair; manual: linked by hand",
    "Status": "pending, accepted (Y) or rejected (R)",
    "Eval": "TP or FP against the reference loaded in the Evaluation panel",
    "Label": "Room name or type (double-click a cell to edit)",
    "Note": "Free note (double-click a cell to edit)",
}
_NOTE_COLUMN = COLUMNS.index("Note")
_LABEL_COLUMN = COLUMNS.index("Label")
_EDITABLE = (_NOTE_COLUMN, _LABEL_COLUMN)
#: Columns of free text: they share the width left and elide; the others are sized to their values.
FREE_TEXT_COLUMNS = _EDITABLE
_STATUSES = ("pending", "accepted", "rejected")
_MARK_COLOURS = {"TP": QColor(30, 140, 60), "FP": QColor(200, 40, 40)}
_STATUS_COLOURS = {"accepted": QColor(30, 120, 60), "rejected": QColor(170, 40, 40), "pending": QColor(120, 120, 120)}


def _regions_text(regions) -> str:
    return ", ".join(str(r) for r in regions) or "–"


class CorrespondenceTableModel(QAbstractTableModel):
    """Read-only table of the session's cliques."""

    def __init__(self, session, parent=None):
        super().__init__(parent)
        self._session = session
        self._cliques = tuple(session.correspondences.cliques)
        session.correspondences_changed.connect(self.refresh)
        session.reference_changed.connect(self.reset)

    def refresh(self, *_args) -> None:
        """Re-read the cliques and evaluation marks from the session.

        When the rows are the same cliques (a status or region edit), only their cells
        are announced as changed; a reset would make the view re-measure every row.
        """
        cliques = tuple(self._session.correspondences.cliques)
        if [c.id for c in cliques] == [c.id for c in self._cliques]:
            # Marks can change for any row when one clique changes, so compare them too.
            changed = [row for row, (old, new) in enumerate(zip(self._cliques, cliques)) if old != new]
            self._cliques = cliques
            if self._session.reference is not None:
                changed = range(len(cliques))
            if changed:
                self.dataChanged.emit(self.index(min(changed), 0), self.index(max(changed), len(COLUMNS) - 1))
            return
        self.reset()

    def reset(self, *_args) -> None:
        """Re-read everything (the reference changed: every Eval cell may differ)."""
        self.beginResetModel()
        self._cliques = tuple(self._session.correspondences.cliques)
        self.endResetModel()

    def rowCount(self, parent=QModelIndex()) -> int:
        return 0 if parent.isValid() else len(self._cliques)

    def columnCount(self, parent=QModelIndex()) -> int:
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section: int, orientation, role=Qt.ItemDataRole.DisplayRole):
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.DisplayRole:
            return COLUMNS[section]
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.ToolTipRole:
            return _HEADER_TIPS.get(COLUMNS[section])
        return None

    def data(self, index: QModelIndex, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        clique = self._cliques[index.row()]
        column = index.column()
        if role == Qt.ItemDataRole.DisplayRole:
            return self._text(clique, column)
        if role == Qt.ItemDataRole.DecorationRole and column == 0:
            return QColor(*self._session.color_of_clique(clique.id))
        if role == Qt.ItemDataRole.ForegroundRole:
            if column == 6:
                return _MARK_COLOURS.get(self._mark(clique.id))
            if column == 5:
                return _STATUS_COLOURS.get(clique.effective_status)
        if role == Qt.ItemDataRole.UserRole:
            return clique.id
        if role == Qt.ItemDataRole.ToolTipRole and column == _LABEL_COLUMN:
            # The cell may be elided: the tooltip gives the label in full.
            label = clique_label(clique)
            hint = "Room name or type (double-click to edit); saved in the JSON and carried into the exports"
            return f"{label}\n\n{hint}" if label else hint
        if role == Qt.ItemDataRole.ToolTipRole and clique.note:
            return clique.note
        return None

    def _text(self, clique, column: int) -> str:
        if column == 0:
            return str(clique.id)
        if column == 1:
            return _regions_text(clique.sketch_regions)
        if column == 2:
            return _regions_text(clique.metric_regions)
        if column == 3:
            return clique.source
        if column == 4:
            return "" if clique.score is None else f"{clique.score:.3g}"
        if column == 5:
            return clique.effective_status
        if column == 6:
            return self._mark(clique.id)
        if column == _LABEL_COLUMN:
            return clique_label(clique) or ""
        return clique.note

    def _mark(self, clique_id: int) -> str:
        status = self._session.clique_status(clique_id)
        return status.upper() if status else ""

    def flags(self, index: QModelIndex):
        flags = super().flags(index)
        if index.isValid() and index.column() in _EDITABLE:
            flags |= Qt.ItemFlag.ItemIsEditable
        return flags

    def setData(self, index: QModelIndex, value, role=Qt.ItemDataRole.EditRole) -> bool:
        """Editing the Note or Label cell sets the clique's note or label in the session (one undo step)."""
        if not index.isValid() or index.column() not in _EDITABLE or role != Qt.ItemDataRole.EditRole:
            return False
        clique = self._cliques[index.row()]
        if index.column() == _LABEL_COLUMN:
            self._session.set_label(clique.id, str(value))
        elif str(value) != clique.note:
            self._session.set_note(clique.id, str(value))
        return True

    def clique_id(self, row: int) -> int:
        return self._cliques[row].id

    def row_of(self, clique_id: int | None) -> int:
        """Row of a clique id, -1 when absent."""
        for row, clique in enumerate(self._cliques):
            if clique.id == clique_id:
                return row
        return -1


class CorrespondenceTable(QWidget):
    """The table view, kept in sync with the session's selected clique both ways."""

    def __init__(self, session, parent=None):
        super().__init__(parent)
        self._session = session
        self.model = CorrespondenceTableModel(session, self)
        self.view = QTableView()
        self.view.setObjectName("correspondence_table")
        self.view.setModel(self.model)
        self.view.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.view.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        # Only the Label and Note columns are editable (see the model's flags).
        self.view.setEditTriggers(
            QAbstractItemView.EditTrigger.DoubleClicked | QAbstractItemView.EditTrigger.EditKeyPressed
        )
        self.view.verticalHeader().setVisible(False)
        self.view.verticalHeader().setDefaultSectionSize(22)
        self.view.setAlternatingRowColors(True)
        header = self.view.horizontalHeader()
        # Measured once per reset, not on every change (ResizeToContents re-reads every row).
        header.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        # The free text takes what is left, elided, so the short values never need a scroll bar.
        for column in FREE_TEXT_COLUMNS:
            header.setSectionResizeMode(column, QHeaderView.ResizeMode.Stretch)
        self.view.setTextElideMode(Qt.TextElideMode.ElideRight)
        # The scroll bar always there: appearing when a match fills the table, it narrowed the
        # view, and the stretched columns were laid out and the table painted again (8-17 ms on
        # the next event, a hover of a map in the app bench); the columns no longer jump either.
        self.view.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOn)
        self.model.modelReset.connect(self._fit_columns)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.view)
        self._syncing = False
        self.view.selectionModel().selectionChanged.connect(self._row_selected)
        self.model.modelReset.connect(self.show_session_selection)
        session.selection_changed.connect(self.show_session_selection)

    def _fit_columns(self) -> None:
        self.view.resizeColumnsToContents()
        # A status can change without a reset; leave room for the widest one.
        status_column = COLUMNS.index("Status")
        widest = max(self.view.fontMetrics().horizontalAdvance(status) for status in _STATUSES) + 24
        if self.view.columnWidth(status_column) < widest:
            self.view.setColumnWidth(status_column, widest)

    def _row_selected(self, *_args) -> None:
        if self._syncing:
            return
        rows = self.view.selectionModel().selectedRows()
        clique_id = self.model.clique_id(rows[0].row()) if rows else None
        if clique_id != self._session.selected_clique:
            self._session.select_clique(clique_id)

    def show_session_selection(self, *_args) -> None:
        """Select the row of the session's selected clique (none when there is none)."""
        row = self.model.row_of(self._session.selected_clique)
        self._syncing = True
        try:
            selection = self.view.selectionModel()
            if row < 0:
                selection.clearSelection()
            else:
                index = self.model.index(row, 0)
                flags = QItemSelectionModel.SelectionFlag.ClearAndSelect | QItemSelectionModel.SelectionFlag.Rows
                selection.select(index, flags)
                self.view.scrollTo(index)
        finally:
            self._syncing = False
