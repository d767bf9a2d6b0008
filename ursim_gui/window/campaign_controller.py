"""Campaign commands of the main window: open a campaign, go to a pair, save each pair on leaving it.

Opening a pair that has no file yet segments and matches it automatically (the
segmentation panel's presets and the matching panel's matcher), loads its reference
when the campaign names one, zooms to fit and writes the result to the pair's file as
soon as the match is applied (status "automatic"). A pair with a file is reopened from
it. Leaving a pair saves it when it changed, and only then, so no other pair's file is
ever rewritten. The metric map and its segmentation are kept from pair to pair when
they are the same file (the usual campaign: many sketches, one metric map).
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import QObject, Signal

from ursim_core.errors import UrsimError
from ursim_gui.model.campaign import Campaign, open_campaign, pair_summary, summary_of
from ursim_gui.model.jobs import MatchJob
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs

__all__ = ["CampaignController"]

_log = logging.getLogger(__name__)
_FAILURES = (UrsimError, OSError, ValueError)


class CampaignController(QObject):
    """Walks a :class:`~ursim_gui.model.campaign.Campaign` in ``window``'s session.

    Signals
    -------
    pair_ready(int) : a pair is open and matched (or reopened from its file)
    opened() : a campaign was opened (before its first pair)
    """

    pair_ready = Signal(int)
    opened = Signal()

    def __init__(self, window, panel, data_dir: Path):
        super().__init__(window)
        self.window = window
        self.session = window.session
        self.panel = panel
        self.data_dir = Path(data_dir)
        self.campaign: Campaign | None = None
        self._awaiting_match: int | None = None
        panel.pair_requested.connect(self.go_to)
        panel.previous_button.clicked.connect(self.previous)
        panel.next_button.clicked.connect(self.next)
        window.jobs.applied.connect(self._job_applied)
        self.session.correspondences_changed.connect(self._show_current_counts)

    # ---- opening -------------------------------------------------------------------------
    def open(self, source: Path | None = None, *, output_dir: Path | None = None) -> bool:
        """Open a campaign (asks for the folder or manifest unless given) at its saved position."""
        if source is None:
            source = file_dialogs.ask_folder(self.window, "Open campaign folder")
            if source is None:
                return False
        if not self._leave_current():
            return False
        annotator = self.window.preferences.annotator(ask=True)
        if annotator:
            self.session.annotator = annotator
        try:
            campaign = open_campaign(source, annotator=annotator, output_dir=output_dir, data_dir=self.data_dir)
        except _FAILURES as error:
            dialogs.show_error(self.window, "Cannot open the campaign", str(error))
            return False
        self.campaign = campaign
        self.panel.show_campaign(campaign.name, [pair.name for pair in campaign.pairs], str(campaign.output_dir))
        for row, pair in enumerate(campaign.pairs):
            self.panel.show_pair(row, pair_summary(pair.output))
        self._show_progress()
        self.window.docks["campaign"].show()
        self.window.docks["campaign"].raise_()
        self.window.preferences.add_recent("campaigns", str(source))
        self.opened.emit()
        return self._open_pair(campaign.current)

    # ---- navigation ------------------------------------------------------------------------
    def next(self) -> bool:
        return self.campaign is not None and self.go_to(self.campaign.current + 1)

    def previous(self) -> bool:
        return self.campaign is not None and self.go_to(self.campaign.current - 1)

    def go_to(self, index: int) -> bool:
        """Save the current pair if it changed, then open pair ``index``."""
        campaign = self.campaign
        if campaign is None or not 0 <= index < len(campaign.pairs):
            return False
        if index == campaign.current and self._is_open(index):
            return True
        if not self._leave_current():
            return False
        return self._open_pair(index)

    def save_current(self) -> bool:
        """Write the current pair's file when it has unsaved changes (or none yet). True when nothing is lost."""
        campaign = self.campaign
        if campaign is None or not self._is_open(campaign.current):
            return True
        pair = campaign.pairs[campaign.current]
        session = self.session
        if not session.correspondences.cliques and not pair.output.is_file():
            return True  # nothing to write yet (e.g. the match is still running)
        if session.path == pair.output and not session.dirty:
            return True
        try:
            pair.output.parent.mkdir(parents=True, exist_ok=True)
            session.save(pair.output)
        except _FAILURES as error:
            dialogs.show_error(self.window, "Cannot save the pair", str(error))
            return False
        self.window.documents.autosaver.discard()
        self._show_row(campaign.current)
        return True

    # ---- internals ---------------------------------------------------------------------------
    def _is_open(self, index: int) -> bool:
        """True when the session holds pair ``index``'s document: its two maps, and its file or
        none yet. Another file opened over the same sketch (another annotator's, say) is not the
        pair's, and the pair's file is never written from it."""
        pair, session = self.campaign.pairs[index], self.session
        sketch, metric = session.map("sketch"), session.map("metric")
        return (
            sketch is not None
            and sketch.path == pair.sketch.absolute()
            and metric is not None
            and metric.path == pair.metric.absolute()
            and session.path in (None, pair.output.absolute())
        )

    def _leave_current(self) -> bool:
        if self.campaign is not None and self._is_open(self.campaign.current):
            return self.save_current()
        what = "opening the campaign" if self.campaign is None else "going to another pair"
        return self.window.documents.confirm_discard(what)

    def _open_pair(self, index: int) -> bool:
        """Open pair ``index`` (the current one was saved or left). Its maps are read before
        anything changes; a pair that cannot be opened is shown as an empty document at its place
        in the list, so the panel never names one pair while the maps show another."""
        campaign, session, window = self.campaign, self.session, self.window
        pair = campaign.pairs[index]
        self._awaiting_match = None
        try:
            if pair.output.is_file():
                session.open(pair.output)  # all at once or not at all
            else:
                metric = session.map("metric")
                keep = (
                    ["metric"]
                    if metric is not None
                    and metric.path == pair.metric.absolute()
                    and session.segmentation("metric") is not None
                    else []
                )
                sketch_map = session.read_map(pair.sketch)
                metric_map = None if keep else session.read_map(pair.metric)
                session.new_document(keep=keep)
                session.set_map("sketch", sketch_map)
                if metric_map is not None:
                    session.set_map("metric", metric_map)
        except _FAILURES as error:
            window.jobs.drop_all()
            session.new_document()
            self._show_position(index)
            dialogs.show_error(window, f"Cannot open pair {pair.name}", str(error))
            return False
        # What was queued or running for the pair left would fail or clear the queue.
        window.jobs.drop_all()
        self._show_position(index)
        self._read_neighbours_ahead(index)
        # What the source says the input map is (the Halmstad robot maps), for every match of the
        # pair: set once its maps are in, since opening another map forgets the last pair's settings.
        if pair.input_kind is not None:
            window.matching_panel.set_input_kind(pair.input_kind)
        if pair.reference is not None:
            window.documents.load_reference(pair.reference)
        window.fit_views()
        if pair.output.is_file():
            self.pair_ready.emit(index)
            return True
        self._awaiting_match = index
        window.documents.segment_unsegmented()
        window.jobs.match(window.matching_panel.config())
        return True

    def _read_neighbours_ahead(self, index: int) -> None:
        """Have the next and the previous pair's map files read on a thread while this pair is
        worked on (:class:`~ursim_gui.model.read_ahead.MapReadAhead`): moving to them then
        decodes nothing on the GUI thread."""
        pairs, session = self.campaign.pairs, self.session
        shown = {getattr(session.map(side), "path", None) for side in ("sketch", "metric")}
        files = [
            path.absolute()
            for neighbour in (index + 1, index - 1)
            if 0 <= neighbour < len(pairs)
            for path in (pairs[neighbour].sketch, pairs[neighbour].metric)
        ]
        session.read_ahead.prefetch(path for path in files if path not in shown)

    def _job_applied(self, job) -> None:
        campaign = self.campaign
        if campaign is None or not isinstance(job, MatchJob) or self._awaiting_match != campaign.current:
            return
        self._awaiting_match = None
        self.window.fit_views()
        if self.save_current():
            self.pair_ready.emit(campaign.current)

    def _show_position(self, index: int) -> None:
        campaign = self.campaign
        campaign.current = index
        self.panel.show_current(index)
        try:
            campaign.save_state()
        except OSError as error:
            _log.warning("campaign state not written: %s", error)

    def _show_row(self, row: int) -> None:
        self.panel.show_pair(row, pair_summary(self.campaign.pairs[row].output))
        self._show_progress()

    def _show_current_counts(self, *_args) -> None:
        campaign = self.campaign
        if campaign is None or not self._is_open(campaign.current):
            return
        self.panel.show_pair(campaign.current, summary_of(self.session.correspondences))
        self._show_progress()

    def _show_progress(self) -> None:
        rows = range(self.panel.table.rowCount())
        done = sum(self.panel.status_text(row) == "done" for row in rows)
        self.panel.show_progress(done, len(rows))
