"""Faulting in memory on a second thread ahead of the step that needs it.

On the virtual machines this was measured on, memory that a process touches for the first time
cost 1-2.5 s per GB: the host backs each page at its first touch, and takes memory the guest
frees back within about two seconds. Memory freed and allocated again at once cost 0.07 s per
GB. At 8000 x 8000 px the zone graph's arrays (600 MB) are the largest fresh memory of a
segmentation, and the step that builds them (``build_adjacency``) spent most of its time on
their page faults: 0.72 s at 8000 px against 0.04 s at 4000 px, whose memory was reused.

:func:`warm_memory` touches a block of about that size on a second thread while the first one
computes the radii and labels the flat zones, and :meth:`Warming.release` frees it just before
the graph is built: the graph's arrays then get pages that are already backed. The block's size is estimated from
the map's border before any zone exists (:func:`warm_bytes`), at most the graph's size plus a
few per cent on the maps measured, so the peak memory stays that of the graph's build; where
memory is cheap to touch (bare metal) the second thread's work is all it costs.
"""

from __future__ import annotations

import mmap
import threading

import numpy as np

__all__ = [
    "CHUNK_BYTES",
    "WARM_MIN_PIXELS",
    "BYTES_PER_ZONE",
    "ZONES_PER_BORDER",
    "BYTES_PER_PIXEL",
    "border_length",
    "warm_bytes",
    "Warming",
    "warm_memory",
]

#: Maps from this many pixels (in their free-space box) warm memory for their zone graph.
#: Below, the graph is small and its memory mostly reused (0.04 s to build at 4000 x 4000 px).
WARM_MIN_PIXELS = 1 << 22

#: Bytes of the zone graph's build per flat zone: a record of 16 bytes, 4.1-4.4 node records of
#: 16 bytes (measured on buildings, sketches and robot maps), and 4 bytes of scratch.
BYTES_PER_ZONE = 88

#: Flat zones per pixel side between free space and obstacle, at most: 0.3-3.2 on the maps
#: measured (generated buildings 2.8-2.9, KTH sketches 1.9-3.1, robot maps 1.6-3.2; enlarged
#: scans, whose walls are smooth, 0.3-1). The number of flat zones is not known before they are
#: labelled, by which time it is too late to warm anything; their borders are counted at once.
ZONES_PER_BORDER = 3

#: Bytes touched between two looks at whether the block is still wanted.
CHUNK_BYTES = 8 << 20

#: The most bytes warmed per pixel: a building's robot map, with 0.1 flat zones per pixel,
#: needs about 8.8 (at 12 per pixel the peak memory grew by 210 MB at 8000 x 8000 px).
BYTES_PER_PIXEL = 8


def border_length(free: np.ndarray, *, rows: int = 512) -> int:
    """Pixel sides between free and obstacle pixels, counted ``rows`` rows at a time (a
    full-size comparison would itself be 64 MB of fresh memory at 8000 x 8000 px).

    Examples
    --------
    >>> free = np.zeros((4, 4), bool); free[1:3, 1:3] = True
    >>> border_length(free)
    8
    """
    total = 0
    for start in range(0, free.shape[0], rows):
        band = free[start : start + rows + 1]  # one more row: the sides with the next band
        total += int(np.count_nonzero(band[:rows, 1:] != band[:rows, :-1]))
        total += int(np.count_nonzero(band[1:] != band[:-1]))
    return total


def warm_bytes(free: np.ndarray) -> int:
    """The bytes to warm for the zone graph of the free-space mask ``free``: its flat zones'
    share (:data:`BYTES_PER_ZONE`) estimated from its border, at most :data:`BYTES_PER_PIXEL`
    per pixel."""
    zones = ZONES_PER_BORDER * border_length(free)
    return min(BYTES_PER_PIXEL * free.size, BYTES_PER_ZONE * zones)


class Warming:
    """A block for the zone graph of ``free`` (:func:`warm_bytes`), touched page by page on a
    daemon thread (the bytes are counted there too).

    A failed allocation (not enough memory) leaves nothing warmed: warming only saves time.

    Examples
    --------
    >>> warming = Warming(np.ones((100, 100), bool))
    >>> warming.release()
    >>> warming.block is None
    True
    """

    def __init__(self, free: np.ndarray):
        self.block: np.ndarray | None = None
        self.touched = 0  # bytes of the block faulted in so far
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._touch, args=(free,), daemon=True)
        self._thread.start()

    def _touch(self, free: np.ndarray) -> None:
        nbytes = warm_bytes(free)
        try:
            self.block = np.empty(max(nbytes, 1), np.uint8)
        except MemoryError:
            return
        # One write per page faults it in (numpy asks for huge pages for a block this large,
        # so most writes land in pages already there); numpy releases the GIL meanwhile. In
        # chunks, so that a release need not wait for the whole block.
        for start in range(0, nbytes, CHUNK_BYTES):
            if self._stop.is_set():
                return
            self.block[start : start + CHUNK_BYTES : mmap.PAGESIZE] = 1
            self.touched = min(start + CHUNK_BYTES, nbytes)

    def release(self) -> None:
        """Stop the touching (after the chunk under way) and free the block: what was not
        touched by then faults in where it is used, as it would have without warming."""
        self._stop.set()
        self._thread.join()
        self.block = None


def warm_memory(free: np.ndarray) -> Warming | None:
    """Start warming memory for the zone graph of the free-space mask ``free``, or None when
    the map is too small for it to pay (:data:`WARM_MIN_PIXELS`).

    Examples
    --------
    >>> warm_memory(np.ones((100, 100), bool)) is None
    True
    """
    if free.size < WARM_MIN_PIXELS:
        return None
    return Warming(free)
