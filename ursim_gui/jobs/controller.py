"""Runs segmentation and matching jobs off the GUI thread and hands results to the session.

Jobs are queued (segment sketch, segment metric, match) and run one at a time by a
:class:`~ursim_gui.jobs.runner.JobRunner`; the status bar shows progress and a Cancel button
that drops the whole queue. Results are applied in the GUI thread through the session's
own methods (``set_segmentation``, ``apply_match``).
"""

from __future__ import annotations

import logging
from collections import deque

from PySide6.QtCore import QObject, Signal

from ursim_core.errors import UrsimError
from ursim_gui.jobs.runner import JobRunner
from ursim_gui.model.jobs import LaidMatch, MatchJob, SegmentJob, compiling_note
from ursim_gui.model.wording import counted
from ursim_gui.views.messages import show_error

__all__ = ["JobController", "MatchRequest"]

_log = logging.getLogger(__name__)


class JobController(QObject):
    """Queue of jobs for one session.

    Signals
    -------
    busy_changed(bool) : a job started, or the queue emptied
    """

    busy_changed = Signal(bool)
    #: A job's result was applied to the session (SegmentJob or MatchJob).
    applied = Signal(object)
    #: Any other job finished: (job, result), for the code that queued it (see :meth:`submit`).
    result_ready = Signal(object, object)

    def __init__(self, session, status_bar, parent_widget=None):
        super().__init__(parent_widget)
        self._session = session
        self._status = status_bar
        self._parent = parent_widget
        self.runner = JobRunner(self)
        self._queue: deque = deque()
        self._note = ""
        self.runner.progress.connect(self._progress)
        self.runner.finished.connect(self._finished)
        self.runner.failed.connect(self._failed)
        self.runner.cancelled.connect(self._cancelled)
        status_bar.cancel_button.clicked.connect(self.cancel)

    @property
    def busy(self) -> bool:
        return self.runner.busy or bool(self._queue)

    # ---- requests --------------------------------------------------------------------
    def segment(self, side: str, preset: str, params: dict | None = None, *, method: str = "maoris") -> None:
        """Queue the segmentation of one side's map with a segmenter, a preset and overrides."""
        map_ = self._session.map(side)
        if map_ is None:
            show_error(self._parent, "Cannot segment", f"Open a {side} map first.")
            return
        self._enqueue(SegmentJob(map_, preset, params, method=method, side=side))

    def match(self, config=None) -> None:
        """Queue a match of the two segmentations (taken when the job starts).

        ``config`` becomes the session's ``match_config``; None uses the session's.
        """
        if config is not None:
            self._session.match_config = config
        self._enqueue(MatchRequest(self._session.match_config))

    def cancel(self) -> None:
        """Cancel the running job and drop the queued ones."""
        self._queue.clear()
        self.runner.cancel()
        self._status.cancel_button.setEnabled(False)
        self._status.showMessage("Cancelling…")

    def drop_all(self) -> None:
        """Drop every job, queued or running, without a word: the document they were for is
        gone (a campaign moved to another pair). Jobs queued afterwards run as usual."""
        if self.busy:
            self._queue.clear()
            self.runner.cancel()

    def run_now(self, job) -> bool:
        """Run a job in the calling thread and apply its result (scripted use: --screenshot).

        A failure is shown and logged like a worker failure; returns True on success.
        """
        job = self._resolve(job)
        if job is None:
            return False
        try:
            result = job.run(lambda fraction, message="": None, lambda: False)
            self._apply(job, result)
        except Exception as error:
            _log.exception("%s failed", job.description)
            show_error(self._parent, "Job failed", f"{job.description} failed:\n{error}")
            return False
        return True

    def wait(self, msecs: int = 120_000) -> None:
        """Process events until the queue is empty (tests, scripted runs)."""
        from PySide6.QtCore import QDeadlineTimer, QEventLoop
        from PySide6.QtWidgets import QApplication

        deadline = QDeadlineTimer(msecs)
        while self.busy and not deadline.hasExpired():
            QApplication.processEvents(QEventLoop.ProcessEventsFlag.AllEvents, 20)

    # ---- queue ------------------------------------------------------------------------
    def _enqueue(self, job) -> None:
        self._queue.append(job)
        self._start_next()

    def _start_next(self) -> None:
        while not self.runner.busy and self._queue:
            job = self._resolve(self._queue.popleft())
            if job is None:
                continue
            self._status.show_job(True)
            # Said for as long as the job runs: the first MAORIS run compiles for seconds.
            self._note = compiling_note(job) or ""
            self._status.progress_bar.setToolTip(self._note)
            self._status.showMessage(job.description + "…" + (f"  {self._note}" if self._note else ""))
            self.runner.start(job)
            self.busy_changed.emit(True)
        if not self.busy:
            self._status.show_job(False)
            self.busy_changed.emit(False)

    def _resolve(self, job):
        if not isinstance(job, MatchRequest):
            return job
        sketch, metric = self._session.segmentation("sketch"), self._session.segmentation("metric")
        if sketch is None or metric is None:
            show_error(self._parent, "Cannot match", "Segment both maps (or load their label images) first.")
            self._queue.clear()
            return None
        config = job.config
        sketch_map, metric_map = self._session.map("sketch"), self._session.map("metric")
        if config is not None and sketch_map is not None and metric_map is not None:
            # As `ursim match`: two georeferenced maps (ROS YAML) tell their relative scale.
            config = config.with_resolutions(sketch_map.resolution, metric_map.resolution)
        # The person's manual, accepted and rejected cliques steer the answer (see
        # AnnotationSession.review_constraints), read now: edits made while it was queued count.
        # VF2 takes no constraints: the session still keeps the review when it applies its answer.
        from ursim_core.matching import CONSTRAINED_MATCHERS, MatchConfig

        steered = (config or MatchConfig()).resolved().matcher in CONSTRAINED_MATCHERS
        return MatchJob(
            sketch,
            metric,
            config,
            constraints=self._session.review_constraints() if steered else None,
            laid_sketch=True,
        )

    def submit(self, job) -> None:
        """Queue any other job (``run(progress, cancelled)``); its result comes as ``result_ready``."""
        self._enqueue(job)

    def _is_stale(self, job) -> bool:
        """True when the inputs changed while the job ran (its result belongs to nothing now)."""
        if not isinstance(job, (SegmentJob, MatchJob)):
            return False
        if isinstance(job, SegmentJob):
            return self._session.map(job.side) is not job.map
        return (
            self._session.segmentation("sketch") is not job.sketch_seg
            or self._session.segmentation("metric") is not job.metric_seg
        )

    def _apply(self, job, result) -> None:
        if self._is_stale(job):
            _log.info("%s: inputs changed meanwhile, result dropped", job.description)
            self._status.showMessage(f"{job.description}: the maps changed meanwhile; result dropped", 6000)
            return
        if isinstance(job, SegmentJob):
            self._session.set_segmentation(job.side, result)
            if result.n_regions == 0:
                reason = self._session.no_region_reason(job.side)
                self._status.showMessage(f"{job.side.capitalize()}: 0 regions: {reason}", 15000)
            else:
                self._status.showMessage(f"{job.side.capitalize()}: {result.n_regions} regions", 5000)
        elif isinstance(job, MatchJob):
            if isinstance(result, LaidMatch):
                self._session.apply_match(result.result, laid=result.laid)
                result = result.result
            else:
                self._session.apply_match(result)
            kept = ""
            if job.constraints is not None:
                reviewed = len(job.constraints.fixed) + len(job.constraints.forbidden)
                kept = f" (building on {counted(reviewed, 'reviewed pair')})"
            self._status.showMessage(f"Matched: {counted(len(result.pairs), 'pair')}{kept}", 5000)
        else:
            self._status.showMessage(f"{job.description}: done", 5000)
            self.result_ready.emit(job, result)
            return
        self.applied.emit(job)

    def _progress(self, fraction: float, message: str) -> None:
        job = self.runner.job
        prefix = f"{job.description}: " if job is not None and message else ""
        suffix = f"  {self._note}" if message and self._note else ""
        self._status.show_progress(fraction, prefix + message + suffix)

    def _finished(self, job, result) -> None:
        try:
            self._apply(job, result)
        except (UrsimError, ValueError) as error:
            self._queue.clear()
            show_error(self._parent, "Cannot use the result", f"{job.description}:\n{error}")
        finally:
            self._start_next()

    def _failed(self, job, message: str) -> None:
        self._queue.clear()
        self._start_next()
        show_error(self._parent, "Job failed", f"{job.description} failed:\n{message}")

    def _cancelled(self, job) -> None:
        # The queue was emptied when the cancel was asked for; what is queued now came after it.
        _log.info("%s cancelled", job.description)
        self._start_next()
        self._status.showMessage(f"{job.description} cancelled", 5000)


class MatchRequest:
    """A match request whose inputs are read when it starts (after queued segmentations)."""

    def __init__(self, config):
        self.config = config
