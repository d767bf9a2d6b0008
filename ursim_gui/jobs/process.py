"""A child process that runs jobs, so long computations never hold the GUI's interpreter lock.

Segmentation spends long stretches in C code that keeps Python's GIL (a single
``scipy.ndimage`` call can take a second on a big map), so a worker *thread* still
freezes the window. A worker *process* cannot, and it can be stopped at once, which
makes Cancel real. Qt-free: :mod:`ursim_gui.jobs.runner` calls :meth:`JobProcess.run` from
a worker thread and turns the outcome into Qt signals.

Protocol over a pipe: the parent sends a job (any picklable object with
``run(progress, cancelled)``) or ``None`` to stop; the child answers with
``("progress", fraction, message)`` messages then ``("done", result)`` or
``("failed", message, traceback)``.
"""

from __future__ import annotations

import multiprocessing
import traceback
from typing import Any

from ursim_gui.model.jobs import JobCancelled

__all__ = ["JobProcess", "JobFailed", "serve"]

_POLL_S = 0.05


class JobFailed(Exception):
    """The job raised in the child; ``details`` holds the child's traceback."""

    def __init__(self, message: str, details: str = ""):
        super().__init__(message)
        self.details = details


def serve(connection) -> None:
    """Child main loop: run each job received, answer with its outcome."""
    # Pay the heavy imports while the user is still looking at the maps.
    import ursim_core.matching
    import ursim_core.segmentation  # noqa: F401

    def progress(fraction: float, message: str = "") -> None:
        connection.send(("progress", float(fraction), str(message)))

    while True:
        try:
            job = connection.recv()
        except EOFError:
            return
        except Exception as error:  # a job that cannot be unpickled here
            connection.send(("failed", f"cannot start the job: {error}", traceback.format_exc()))
            continue
        if job is None:
            return
        try:
            result = job.run(progress, lambda: False)
            connection.send(("done", result))
        except Exception as error:
            connection.send(("failed", str(error) or type(error).__name__, traceback.format_exc()))


class JobProcess:
    """One reusable child process; :meth:`run` is called from one thread at a time."""

    def __init__(self) -> None:
        self._context = multiprocessing.get_context("spawn")  # fork is unsafe with Qt threads
        self._process = None
        self._connection = None

    @property
    def alive(self) -> bool:
        return self._process is not None and self._process.is_alive()

    def start(self) -> None:
        """Start the child if it is not running (blocks for the spawn, not for its imports)."""
        if self.alive:
            return
        parent, child = self._context.Pipe()
        self._process = self._context.Process(target=serve, args=(child,), name="ursim-gui-jobs", daemon=True)
        self._process.start()
        child.close()
        self._connection = parent

    def run(self, job: Any, progress, cancelled) -> Any:
        """Run ``job`` in the child; returns its result.

        Raises
        ------
        JobCancelled
            ``cancelled()`` became true; the child was stopped at once.
        JobFailed
            The job raised, or the child died.
        """
        self.start()
        self._connection.send(job)
        while True:
            if cancelled():
                self.stop(kill=True)
                raise JobCancelled("cancelled")
            if not self._connection.poll(_POLL_S):
                if not self._process.is_alive():
                    code = self._process.exitcode
                    self.stop(kill=True)
                    raise JobFailed(f"the worker process ended unexpectedly (exit code {code})")
                continue
            try:
                kind, *payload = self._connection.recv()
            except EOFError:
                self.stop(kill=True)
                raise JobFailed("the worker process ended unexpectedly") from None
            if kind == "progress":
                progress(*payload)
            elif kind == "done":
                return payload[0]
            else:
                raise JobFailed(*payload)

    def stop(self, *, kill: bool = False) -> None:
        """Stop the child: politely (finish the current job first) or at once."""
        process, connection = self._process, self._connection
        self._process = self._connection = None
        if process is None:
            return
        if not kill and process.is_alive():
            try:
                connection.send(None)
            except OSError:
                pass
            process.join(2.0)
        if process.is_alive():
            process.terminate()
            process.join(2.0)
        connection.close()
