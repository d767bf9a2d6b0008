"""Anchors of the last match: a list of (sketch region, metric region); click selects both.

The anchors are the heat sources of the region descriptors: unique regions paired before the
matching. The answer may pair them otherwise (the matcher corrects a wrong anchor, or the
sketch laid on the map gives other partners), so each entry says whether the answer agrees.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QListWidget, QListWidgetItem, QVBoxLayout, QWidget

__all__ = ["AnchorsList"]


class AnchorsList(QWidget):
    """Lists ``session.anchors``; clicking an entry selects its two regions in the session."""

    def __init__(self, session, parent=None):
        super().__init__(parent)
        self._session = session
        self.list = QListWidget()
        self.list.setObjectName("anchors_list")
        self.hint = QLabel(
            "Unique regions paired before matching, the sources of the region descriptors; drawn with "
            "a dashed outline. The answer may pair them otherwise."
        )
        self.hint.setWordWrap(True)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.hint)
        layout.addWidget(self.list)
        self.list.itemClicked.connect(self._select)
        session.correspondences_changed.connect(self.refresh)
        self.refresh()

    def refresh(self, *_args) -> None:
        self.list.clear()
        session = self._session
        for sketch, metric in session.anchors:
            kept = int(metric) in session.partners("sketch", int(sketch))
            verdict = "in the answer" if kept else "not in the answer"
            item = QListWidgetItem(f"sketch {sketch}  ↔  metric {metric}   ({verdict})")
            item.setToolTip(
                "The answer pairs these two regions too."
                if kept
                else "The answer does not pair these two regions: the matcher found other partners."
            )
            item.setData(Qt.ItemDataRole.UserRole, (int(sketch), int(metric)))
            self.list.addItem(item)

    def _select(self, item: QListWidgetItem) -> None:
        sketch, metric = item.data(Qt.ItemDataRole.UserRole)
        self._session.select("sketch", [sketch])
        self._session.select("metric", [metric])
