"""Run a long job (segmentation, matching) off the GUI thread and report back in Qt signals.

A job is any picklable object with ``run(progress, cancelled)`` (see
:mod:`ursim_gui.model.jobs`). :class:`JobRunner` runs one job at a time: a pool thread
hands it to a child process (:class:`~ursim_gui.jobs.process.JobProcess`, so the GUI
thread never waits for the interpreter lock) and relays progress and the outcome as
signals delivered in the GUI thread (queued connections), so slots may touch widgets and
the session. Cancel stops the child at once; a cancelled job's result is never applied.
``in_process=True`` runs jobs in the pool thread instead (jobs that cannot be pickled).
"""

from __future__ import annotations

import logging
import threading
import traceback
from typing import Any

from PySide6.QtCore import QObject, QRunnable, QThreadPool, Signal

from ursim_gui.jobs.process import JobProcess

__all__ = ["JobRunner"]

_log = logging.getLogger(__name__)


class _Relay(QObject):
    """Lives in the GUI thread; the worker emits through it (queued across threads)."""

    progress = Signal(int, float, str)
    done = Signal(int, object)
    failed = Signal(int, str, str)


class _Task(QRunnable):
    def __init__(self, ticket: int, job: Any, relay: _Relay, cancel: threading.Event, process: JobProcess | None):
        super().__init__()
        self.setAutoDelete(True)
        self._ticket, self._job, self._relay, self._cancel, self._process = ticket, job, relay, cancel, process

    def run(self) -> None:
        def progress(fraction: float, message: str = "") -> None:
            self._relay.progress.emit(self._ticket, float(fraction), str(message))

        try:
            if self._process is None:
                result = self._job.run(progress, self._cancel.is_set)
            else:
                result = self._process.run(self._job, progress, self._cancel.is_set)
        except Exception as error:  # reported to the GUI thread, which shows it
            if self._cancel.is_set():
                self._relay.done.emit(self._ticket, None)
            else:
                details = getattr(error, "details", "") or traceback.format_exc()
                self._relay.failed.emit(self._ticket, str(error) or type(error).__name__, details)
            return
        self._relay.done.emit(self._ticket, result)


class JobRunner(QObject):
    """Runs one job at a time off the GUI thread.

    Signals
    -------
    started(object) : the job that started
    progress(float, str) : fraction 0..1 and a short message
    finished(object, object) : (job, result) of a job that completed and was not cancelled
    failed(object, str) : (job, message) of a job that raised
    cancelled(object) : the job whose cancellation completed
    busy_changed(bool)
    """

    started = Signal(object)
    progress = Signal(float, str)
    finished = Signal(object, object)
    failed = Signal(object, str)
    cancelled = Signal(object)
    busy_changed = Signal(bool)

    def __init__(self, parent: QObject | None = None, *, in_process: bool = False):
        super().__init__(parent)
        self._process = None if in_process else JobProcess()
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._relay = _Relay(self)
        self._relay.progress.connect(self._on_progress)
        self._relay.done.connect(self._on_done)
        self._relay.failed.connect(self._on_failed)
        self._ticket = 0
        self._job: Any = None
        self._cancel = threading.Event()

    @property
    def busy(self) -> bool:
        return self._job is not None

    @property
    def job(self) -> Any:
        return self._job

    def start(self, job: Any) -> bool:
        """Start ``job``; returns False (and does nothing) while another job runs."""
        if self.busy:
            return False
        self._ticket += 1
        self._job = job
        self._cancel = threading.Event()
        self._pool.start(_Task(self._ticket, job, self._relay, self._cancel, self._process))
        self.started.emit(job)
        self.busy_changed.emit(True)
        return True

    def cancel(self) -> None:
        """Ask the running job to stop; ``cancelled`` is emitted when it has."""
        if self.busy:
            self._cancel.set()

    def wait(self, msecs: int = -1) -> bool:
        """Block until the worker is idle (tests, shutdown); True when it is."""
        return self._pool.waitForDone(msecs)

    def prewarm(self) -> None:
        """Start the child process now (in the pool) so the first job starts at once."""
        if self._process is not None and not self.busy:
            self._pool.start(self._process.start)

    def shutdown(self) -> None:
        """Cancel any job, wait for the pool and stop the child process."""
        self.cancel()
        self._pool.waitForDone(10_000)
        if self._process is not None:
            self._process.stop()

    def _on_progress(self, ticket: int, fraction: float, message: str) -> None:
        if ticket == self._ticket and self.busy:
            self.progress.emit(fraction, message)

    def _on_done(self, ticket: int, result: Any) -> None:
        if ticket != self._ticket or not self.busy:
            return
        job, was_cancelled = self._finish()
        if was_cancelled:
            self.cancelled.emit(job)
        else:
            self.finished.emit(job, result)

    def _on_failed(self, ticket: int, message: str, details: str) -> None:
        if ticket != self._ticket or not self.busy:
            return
        job, _ = self._finish()
        _log.error("%s failed: %s\n%s", getattr(job, "description", "job"), message, details)
        self.failed.emit(job, message)

    def _finish(self) -> tuple[Any, bool]:
        job, was_cancelled = self._job, self._cancel.is_set()
        self._job = None
        self.busy_changed.emit(False)
        return job, was_cancelled
