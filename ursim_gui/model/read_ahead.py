"""Map files read ahead on a thread: the next pair of a campaign opens without decoding on the GUI thread.

Decoding a KTH sketch (a 940 x 1823 px PNG) takes 40-90 ms, and *Next pair* did it on the GUI
thread: the longest gap in the app's event loop while walking the KTH campaign was 110-140 ms
(``python -m ursim_gui.bench``, budget 100 ms). The campaign asks for the neighbouring pairs'
maps as soon as a pair opens; :meth:`MapReadAhead.read` then hands over the map already read, or
waits for the read under way (never longer than reading it again), or reads it itself.

A map read ahead is used only when its file has not changed since (the same size and
modification time as before and after the read); a read that failed is done again by
:meth:`~MapReadAhead.read`, so its error reaches the user through the usual path. Qt-free:
a thread of :mod:`concurrent.futures`; the decoders release the GIL.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

__all__ = ["MapReadAhead"]


def _stamp(path: Path) -> tuple[int, int]:
    status = path.stat()
    return status.st_size, status.st_mtime_ns


class MapReadAhead:
    """Map files read on a background thread before they are asked for.

    Parameters
    ----------
    load : callable, optional
        ``load(path) -> Map``; :func:`ursim_core.io.maps.load_map` by default.

    Examples
    --------
    >>> import numpy as np, tempfile, cv2
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = cv2.imwrite(str(folder / "a.png"), np.full((20, 30), 255, np.uint8))
    >>> ahead = MapReadAhead()
    >>> ahead.prefetch([folder / "a.png"])
    >>> ahead.read(folder / "a.png").shape, ahead.pending
    ((20, 30), ())
    >>> ahead.close()
    """

    def __init__(self, load: Callable[[Path], Any] | None = None) -> None:
        self._loader = load
        self._executor: ThreadPoolExecutor | None = None
        self._reads: dict[Path, Future] = {}

    @property
    def pending(self) -> tuple[Path, ...]:
        """The files read ahead (or being read) and not yet taken."""
        return tuple(self._reads)

    def prefetch(self, paths: Iterable[str | os.PathLike]) -> None:
        """Read these files ahead, in order; reads of other files not yet taken are dropped."""
        wanted = list(dict.fromkeys(Path(path).absolute() for path in paths))
        for path in [path for path in self._reads if path not in wanted]:
            self._reads.pop(path).cancel()
        for path in wanted:
            if path not in self._reads:
                if self._executor is None:
                    self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ursim-read-ahead")
                self._reads[path] = self._executor.submit(self._read, path)

    def read(self, path: str | os.PathLike) -> Any:
        """The map of ``path``: the one read ahead when its file is unchanged, else read now."""
        path = Path(path).absolute()
        future = self._reads.pop(path, None)
        if future is not None and not future.cancel():
            try:
                stamp, map_ = future.result()
                if stamp == _stamp(path):
                    return map_
            except Exception:  # read again below, where the error reaches the user
                pass
        return self._load(path)

    def close(self) -> None:
        """Drop every read ahead and let the thread end."""
        for future in self._reads.values():
            future.cancel()
        self._reads.clear()
        if self._executor is not None:
            self._executor.shutdown(wait=False, cancel_futures=True)
            self._executor = None

    def _load(self, path: Path) -> Any:
        if self._loader is None:
            from ursim_core.io.maps import load_map  # when first needed: the session is made at start-up

            self._loader = load_map
        return self._loader(path)

    def _read(self, path: Path) -> tuple[tuple[int, int], Any]:
        before = _stamp(path)
        map_ = self._load(path)
        if _stamp(path) != before:
            raise OSError(f"{path}: changed while it was read ahead")
        return before, map_
