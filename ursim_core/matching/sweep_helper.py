"""A helper process that shares the automatic m's sweep of a building-sized pair (``ursim match``).

The sweep (:func:`ursim_core.matching.auto_m.sweep`) runs the planar matcher at every m of the
grid; the values are independent, and at thousands of regions each costs most of a second of
pure Python, which holds the GIL. Within :func:`helping`, a sweep of a pair with at least
:data:`MIN_REGIONS` regions in either map hands every other value of m (whichever side is free
takes the next) to one helper process, so the two cores each run about half of them.

The helper is a fresh interpreter (``subprocess``, not ``fork``): a fork of the matching process
would start with its page tables (over a gigabyte resident after the segmentations) and with
the OpenCV and numba worker threads' locks in an unknown state. It receives the inputs of
:func:`~ursim_core.matching.single.planar_outcome` once per sweep (the two planar graphs, the
configuration and the c matrix as raw float64 bytes) and returns the planar matcher's result
per value of m; the caller builds every :class:`~ursim_core.matching.results.MatchResult` as
:func:`~ursim_core.matching.single.match_at` does. Same inputs, same code: the same answers.
If the helper fails, this process computes what it did not return.

Only ``ursim match`` starts it (:mod:`ursim_core.cli.match`): the batch commands already run one
pair per core, and a library caller gets the single-process sweep unless it asks.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import struct
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np

__all__ = ["MIN_REGIONS", "helping", "active", "Helper", "serve", "keep_freed_memory"]

#: Sweeps share their values of m with the helper from this many regions in either map on. The
#: helper costs about a second of CPU to start and a copy of the c matrix. ``ursim match`` of the
#: 4000 px generated pair (990 and 1076 regions, about 0.1 s per m), interleaved x3: 6.6-7.1 s
#: with it, 7.1-7.6 s without (1.3 s more CPU); 8000 px (4250 regions, 0.5-1 s per m): see
#: ``ursim bench scale``. Sketch-sized pairs never start it.
MIN_REGIONS = 900

_ACTIVE: Helper | None = None
_LENGTH = struct.Struct("<Q")


@contextlib.contextmanager
def helping(enabled: bool = True) -> Iterator[Helper | None]:
    """Within the block, large sweeps share their values of m with one helper process.

    Started on entry (its interpreter and imports overlap whatever the caller does before the
    sweep), stopped on exit. Nothing is started when ``enabled`` is false or a helper is active.
    """
    global _ACTIVE
    if not enabled or _ACTIVE is not None:
        yield None
        return
    helper = Helper()
    _ACTIVE = helper
    try:
        yield helper
    finally:
        _ACTIVE = None
        helper.close()


def active(prepared, grid_length: int) -> Helper | None:
    """The helper a sweep of ``prepared`` over ``grid_length`` values of m should use, if any."""
    helper = _ACTIVE
    if helper is None or not helper.alive or grid_length < 2 or threading.current_thread() is not helper.owner:
        return None
    if prepared.config.matcher != "planar" or prepared.descriptors is None:
        return None
    if prepared.constraints:
        return None  # the helper runs unconstrained matches: a person's review is matched here
    return helper if max(prepared.c_matrix.shape) >= MIN_REGIONS else None


#: glibc's mallopt parameters (malloc.h) and the value :func:`keep_freed_memory` gives them.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _KEEP_BYTES = -1, -3, 1 << 30


def keep_freed_memory() -> None:
    """Let glibc reuse freed memory instead of handing it back and faulting it in again.

    By default, blocks above a threshold (32 MB at most) are mapped and unmapped on every
    allocation, and free memory at the top of the heap is returned to the system: a
    building-sized pair allocates and frees arrays of 10-300 MB over and over (masks of the c
    matrix, the alignment tables, label and distance images), and the kernel zeroes and faults
    their pages in each time. 8000 px pair (``ursim match``, interleaved with main's code x2):
    1.03-1.05 million minor page faults and 8.5-10.5 s of system time for main, 0.72-0.75
    million and 8.0-8.5 s with this (on a loaded machine), the peak resident size within 2 %.
    Memory is still given back after the segmentations
    (:func:`ursim_core.cli.match.load_and_segment` trims explicitly).
    glibc only; elsewhere nothing. ``ursim match`` and its helper process call it.
    """
    import ctypes

    try:
        libc = ctypes.CDLL(None)
        libc.mallopt(_M_MMAP_THRESHOLD, _KEEP_BYTES)
        libc.mallopt(_M_TRIM_THRESHOLD, _KEEP_BYTES)
    except (OSError, AttributeError, TypeError):
        pass


def _send(stream, message) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_LENGTH.pack(len(data)))
    stream.write(data)
    stream.flush()


def _read_exactly(stream, view: memoryview) -> bool:
    """Fill ``view`` from ``stream``; False on end of file."""
    filled = 0
    while filled < len(view):
        count = stream.readinto(view[filled:])
        if not count:
            return False
        filled += count
    return True


def _receive(stream):
    header = bytearray(_LENGTH.size)
    if not _read_exactly(stream, memoryview(header)):
        return None
    data = bytearray(_LENGTH.unpack(header)[0])
    if not _read_exactly(stream, memoryview(data)):
        return None
    return pickle.loads(data)


class Helper:
    """One helper process and the inputs it holds (see the module docstring)."""

    def __init__(self):
        # The helper imports this very package, wherever it was imported from.
        root = str(Path(__file__).resolve().parents[2])
        code = f"import sys; sys.path.insert(0, {root!r}); from ursim_core.matching.sweep_helper import serve; serve()"
        self._inputs: tuple = ()  # the objects last sent (kept, so that their identity is theirs)
        self.owner = threading.current_thread()
        try:
            self._process = subprocess.Popen(
                [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE
            )
        except OSError:  # no interpreter to start: the sweeps run here alone
            self._process = None
        self.alive = self._process is not None

    def _send_inputs(self, prepared) -> None:
        inputs = (prepared.sketch_planar, prepared.metric_planar, prepared.c_matrix, prepared.config)
        if len(self._inputs) == len(inputs) and all(a is b for a, b in zip(self._inputs, inputs)):
            return
        c_matrix = np.ascontiguousarray(prepared.c_matrix)
        stream = self._process.stdin
        _send(stream, ("inputs", c_matrix.shape, c_matrix.dtype.str, *inputs[:2], prepared.config))
        stream.write(memoryview(c_matrix).cast("B"))
        stream.flush()
        self._inputs = inputs

    def _ask(self, m: float, seeds):
        _send(self._process.stdin, ("match", m, seeds))
        reply = _receive(self._process.stdout)
        if reply is None or reply[0] != "ok":
            raise RuntimeError(f"sweep helper: {reply[1] if reply else 'no answer'}")
        return reply[1]

    def share(self, prepared, tasks: list, *, progress=None) -> list:
        """:func:`~ursim_core.matching.single.planar_outcome` of every ``(m, seeds)`` task, in order.

        This thread and the helper each take the next task not yet taken; ``progress(done, m)``
        is called from this thread after each of its own tasks.
        """
        from ursim_core.matching.single import planar_outcome

        outcomes: list = [None] * len(tasks)
        taken = iter(range(len(tasks)))
        lock = threading.Lock()

        def take():
            with lock:
                return next(taken, None)

        def feed() -> None:
            try:
                self._send_inputs(prepared)
                while (index := take()) is not None:
                    outcomes[index] = self._ask(*tasks[index])
            except (OSError, EOFError, RuntimeError, pickle.PickleError, ValueError):
                self.alive = False  # what it did not return is computed below

        feeder = threading.Thread(target=feed, name="ursim-sweep-helper", daemon=True)
        feeder.start()

        def local(index: int) -> None:
            m, seeds = tasks[index]
            outcomes[index] = planar_outcome(
                prepared.sketch_planar, prepared.metric_planar, prepared.c_matrix, prepared.config, m, seeds
            )

        while (index := take()) is not None:
            local(index)
            if progress is not None:
                progress(sum(outcome is not None for outcome in outcomes), tasks[index][0])
        feeder.join()
        for index in range(len(tasks)):
            if outcomes[index] is None:
                local(index)
        return outcomes

    def close(self) -> None:
        """Stop the helper (end of its input) and wait for it; kill it if it does not stop."""
        self.alive = False
        if self._process is None:
            return
        with contextlib.suppress(OSError):
            self._process.stdin.close()
        try:
            self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        with contextlib.suppress(OSError):
            self._process.stdout.close()


def serve() -> None:
    """The helper's loop: read inputs and values of m on stdin, answer on stdout, until end of input."""
    import signal

    # Ctrl-C reaches the whole process group: the caller handles it and closes the input.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # The answers go to a private copy of stdout; anything printed goes to stderr.
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    requests = os.fdopen(os.dup(0), "rb")
    keep_freed_memory()
    import ursim_core.matching.edit_kernel  # noqa: F401 - loads the compiled kernels before the first m
    from ursim_core.matching.single import planar_outcome

    inputs = None
    while (message := _receive(requests)) is not None:
        if message[0] == "inputs":
            _, shape, dtype, first, second, config = message
            c_matrix = np.empty(shape, np.dtype(dtype))
            if not _read_exactly(requests, memoryview(c_matrix).cast("B")):
                return
            inputs = (first, second, c_matrix, config)
        elif message[0] == "match":
            _, m, seeds = message
            try:
                reply = ("ok", planar_outcome(*inputs[:3], inputs[3], m, seeds))
            except Exception as error:  # reported: the caller computes this m itself
                reply = ("error", repr(error))
            _send(answers, reply)
