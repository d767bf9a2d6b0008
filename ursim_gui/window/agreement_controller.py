"""Agreement commands: choose the second annotator, compute the campaign's table, export it.

With a second annotator chosen, each pair the campaign opens loads B's file as the
reference, so the evaluation panel reads "A against B" and the maps mark the cliques
they disagree on (FP: A's claim B does not share; FN: B's clique A misses). The whole
campaign's table is computed in the worker process (:class:`AgreementJob`).
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QObject

from ursim_gui.model.agreement import AgreementJob, agreement_csv
from ursim_gui.panels.agreement_panel import FOLDER_CHOICE
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs

__all__ = ["AgreementController"]


class AgreementController(QObject):
    """Connects the agreement panel to the campaign, the session's reference and the worker."""

    def __init__(self, window, panel):
        super().__init__(window)
        self.window = window
        self.panel = panel
        self.second: str | Path | None = None
        self.rows: list = []
        panel.second_chosen.connect(self.choose)
        panel.compute_requested.connect(self.compute)
        panel.export_requested.connect(lambda: self.export())
        window.campaigns.opened.connect(self._campaign_opened)
        window.campaigns.pair_ready.connect(self._pair_ready)
        window.jobs.result_ready.connect(self._result)

    def _campaign_opened(self) -> None:
        campaign = self.window.campaigns.campaign
        names = sorted({name for files in campaign.ground_truth.values() for name in files})
        self.panel.set_choices(names)
        self.second, self.rows = None, []

    def choose(self, choice: str | Path | None) -> None:
        """The second annotator: a name of the dataset's ground truth, a folder, or None."""
        if choice == FOLDER_CHOICE:
            choice = file_dialogs.ask_folder(self.window, "Folder of the second annotator's files")
        self.second = None if choice in (None, "(none)") else choice
        self.panel.show_second("" if self.second is None else str(self.second))
        self._pair_ready(self.window.campaigns.campaign.current if self.window.campaigns.campaign else -1)

    def b_file(self, pair) -> Path | None:
        """The second annotator's file of ``pair``, or None."""
        if self.second is None:
            return None
        if isinstance(self.second, Path):
            path = self.second / f"{pair.name}.json"
            return path if path.is_file() else None
        return self.window.campaigns.campaign.ground_truth.get(pair.name, {}).get(self.second)

    def compute(self) -> bool:
        campaign = self.window.campaigns.campaign
        if campaign is None or self.second is None:
            dialogs.show_error(self.window, "No comparison", "Open a campaign and choose the second annotator first.")
            return False
        self.window.campaigns.save_current()
        pairs = [
            (pair.name, pair.sketch, pair.metric, pair.output, self.b_file(pair))
            for pair in campaign.pairs
            if pair.output.is_file() and self.b_file(pair) is not None
        ]
        if not pairs:
            dialogs.show_error(self.window, "No comparison", "No pair has both annotators' files yet.")
            return False
        panel = self.window.segmentation_panel
        presets = {side: panel.boxes[side].preset.currentText() for side in ("sketch", "metric")}
        self.window.jobs.submit(AgreementJob(pairs, presets))
        return True

    def export(self, path: Path | None = None) -> bool:
        if path is None:
            path = file_dialogs.ask_save_path(self.window, "Export agreement", "agreement.csv", "CSV (*.csv)")
            if path is None:
                return False
        try:
            agreement_csv(self.rows, path)
        except OSError as error:
            dialogs.show_error(self.window, "Export failed", str(error))
            return False
        self.window.statusBar().showMessage(f"Agreement written to {path}", 4000)
        return True

    def _pair_ready(self, index: int) -> None:
        campaign = self.window.campaigns.campaign
        if campaign is None or not 0 <= index < len(campaign.pairs):
            return
        b_file = self.b_file(campaign.pairs[index])
        if b_file is not None:
            self.window.documents.load_reference(b_file)
        elif self.second is not None or campaign.pairs[index].reference is None:
            self.window.session.clear_reference()

    def _result(self, job, rows) -> None:
        if isinstance(job, AgreementJob):
            self.rows = list(rows)
            self.panel.show_rows(self.rows)
            self.panel.show_second(str(self.second), len(self.rows))
