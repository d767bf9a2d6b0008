"""Campaign panel: the pairs of a campaign with status, counts and reading, a progress bar, previous / next.

A thin view: it shows what the campaign controller tells it and asks for a pair by
index; the statuses are computed in :mod:`ursim_gui.model.campaign`.
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QProgressBar,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from ursim_gui.model.wording import counted

__all__ = ["CampaignPanel", "STATUS_COLOURS", "CLOSE_CALL_COLOUR"]

#: Text colour of each status in the list (readable on light and dark backgrounds).
STATUS_COLOURS = {
    "not started": QColor(128, 128, 128),
    "automatic": QColor(40, 120, 200),
    "in review": QColor(210, 130, 0),
    "done": QColor(40, 150, 70),
}


#: Text colour of a reading the matcher found a close call (a pair to check the orientation of).
CLOSE_CALL_COLOUR = QColor(210, 130, 0)


class CampaignPanel(QWidget):
    """Pairs list (name, status, reviewed / cliques, how the matcher read the sketch), progress,
    Previous / Next.

    Signals
    -------
    pair_requested(int) : the user picked a pair (by row)
    """

    pair_requested = Signal(int)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.title = QLabel("No campaign open (File > Open campaign…)")
        self.title.setWordWrap(True)
        self.output = QLabel("")
        self.output.setObjectName("campaign_output")
        self.output.setWordWrap(True)
        self.output.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.progress = QProgressBar()
        self.progress.setObjectName("campaign_progress")
        self.progress.setFormat("%v / %m done")
        self.table = QTableWidget(0, 4)
        self.table.setObjectName("campaign_pairs")
        self.table.setHorizontalHeaderLabels(["Pair", "Status", "Reviewed", "Reading"])
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.verticalHeader().setVisible(False)
        header = self.table.horizontalHeader()
        for column in (0, 1, 2):
            header.setSectionResizeMode(column, QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(3, QHeaderView.ResizeMode.Stretch)
        self.previous_button = QPushButton("◀ Previous (A)")
        self.previous_button.setObjectName("campaign_previous")
        self.next_button = QPushButton("Next (D) ▶")
        self.next_button.setObjectName("campaign_next")
        buttons = QHBoxLayout()
        buttons.addWidget(self.previous_button)
        buttons.addWidget(self.next_button)
        layout = QVBoxLayout(self)
        layout.addWidget(self.title)
        layout.addWidget(self.progress)
        layout.addLayout(buttons)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.output)
        self.table.cellClicked.connect(lambda row, _col: self.pair_requested.emit(row))
        self._current = -1
        self.set_enabled(False)

    def set_enabled(self, enabled: bool) -> None:
        for widget in (self.previous_button, self.next_button, self.table):
            widget.setEnabled(enabled)

    def show_campaign(self, name: str, names: list[str], output: str) -> None:
        """A new campaign: its name, pair names and output folder."""
        self.title.setText(f"Campaign {name}: {counted(len(names), 'pair')}")
        self.output.setText(f"Files: {output}/<pair>.json")
        self.table.setRowCount(len(names))
        for row, pair in enumerate(names):
            self.table.setItem(row, 0, QTableWidgetItem(pair))
            for column in (1, 2, 3):
                self.table.setItem(row, column, QTableWidgetItem(""))
        self.progress.setRange(0, max(1, len(names)))
        self.set_enabled(True)

    def show_pair(self, row: int, summary) -> None:
        """One pair's status, counts and reading (a :class:`~ursim_gui.model.campaign.PairSummary`)."""
        item = self.table.item(row, 1)
        item.setText(summary.status)
        item.setForeground(STATUS_COLOURS.get(summary.status, QColor(128, 128, 128)))
        self.table.item(row, 2).setText(f"{summary.reviewed} / {summary.cliques}" if summary.cliques else "–")
        reading = self.table.item(row, 3)
        reading.setText(summary.reading)
        # A close call stands out: the pair to open and compare the readings of.
        reading.setForeground(CLOSE_CALL_COLOUR if summary.close_call else self.palette().text().color())
        reading.setToolTip(
            "A close call: check the orientation (Edit > Compare the readings)" if summary.close_call else ""
        )

    def show_progress(self, done: int, total: int) -> None:
        self.progress.setRange(0, max(1, total))
        self.progress.setValue(done)

    def show_current(self, row: int) -> None:
        """Mark the pair being worked on (bold, selected, scrolled to)."""
        for index in range(self.table.rowCount()):
            font = self.table.item(index, 0).font()
            font.setBold(index == row)
            self.table.item(index, 0).setFont(font)
        self._current = row
        self.table.selectRow(row)
        self.table.scrollToItem(self.table.item(row, 0))
        self.previous_button.setEnabled(row > 0)
        self.next_button.setEnabled(row < self.table.rowCount() - 1)

    def status_text(self, row: int) -> str:
        return self.table.item(row, 1).text()

    def reading_text(self, row: int) -> str:
        return self.table.item(row, 3).text()
