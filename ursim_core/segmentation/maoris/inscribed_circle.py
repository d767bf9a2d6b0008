"""MAORIS steps 1-2: the value image.

Step 1 (:func:`inscribed_circle_radii`, :func:`inscribed_circle_image`): every free pixel gets the
radius of the largest inscribed disc containing it (``FuzzyOpening.cpp``), min-max normalised to
0..255. Step 2 (:func:`quantize`): normalise again and round up to multiples of 5
(``ZoneReducer.hpp``). The discs are painted by compiled code (:mod:`.kernels.discs`).
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.segmentation.canonical import free_window
from ursim_core.segmentation.maoris.compiled import kernels

__all__ = ["inscribed_circle_radii", "inscribed_circle_image", "quantize"]


def _as_free_mask(free: Any) -> np.ndarray:
    array = np.asarray(free)
    if array.ndim != 2 or array.shape[0] == 0 or array.shape[1] == 0:
        raise SegmentationError(f"free-space mask must be a non-empty 2-D array, got shape {array.shape}")
    return array.astype(bool, copy=False) if array.dtype != bool else array


def inscribed_circle_radii(free: np.ndarray, *, max_radius: int = 500) -> np.ndarray:
    """Radius of the largest (shifted) inscribed disc containing each free pixel.

    Exactly the C++ ``fuzzyOpening(src, out, max_radius)`` before normalisation:
    ``out(p) = max r(q)`` over free pixels q with ``|p - (q - (1, 1))| <= r(q) - 1``,
    where ``r(q) = min(int(dist(q)), max_radius)`` and dist is the exact
    Euclidean distance to the nearest obstacle pixel. Obstacle pixels get 0, and
    so do the free pixels no disc reaches (the row/column just above/left of a
    wall, an effect of the C++'s one-pixel shift).

    Instead of painting a disc per pixel, only the *non-dominated* centres are
    painted: q is dominated when a neighbour q2's disc contains q's disc
    (``r(q2) - r(q) >= |q2 - q|``), which removes ~95 % of them. The rest are
    painted row span by row span in compiled code (:mod:`.kernels.discs`), each
    pixel keeping the largest radius: equal-radius rectangles of centres
    (ridges) as one shape, and lone centres only where no disc of a larger
    radius beside them covers theirs.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True for free space.
    max_radius : int, keyword-only
        Cap on the disc radius (the C++ hard-codes 500).

    Returns
    -------
    ndarray of int32, shape (rows, cols)

    Examples
    --------
    >>> free = np.zeros((9, 9), bool); free[1:8, 1:8] = True
    >>> inscribed_circle_radii(free)[4]
    array([0, 4, 4, 4, 4, 4, 3, 0, 0], dtype=int32)
    """
    free = _as_free_mask(free)
    if int(max_radius) < 1:
        raise ParameterError(f"must be >= 1, got {max_radius!r}", field="max_radius")
    window = free_window(free, 1)
    if window is None:
        return np.zeros(free.shape, np.int32)
    inner = _inscribed_radii_in_window(free[window], int(max_radius))
    if inner.shape == free.shape:  # the window is the whole image (maoris_labels crops to it first)
        return inner
    out = np.zeros(free.shape, np.int32)
    out[window] = inner
    return out


def _inscribed_radii_in_window(free: np.ndarray, max_radius: int) -> np.ndarray:
    return _radii_in_storage(free, max_radius, padding=0)[0]


def _radii_in_storage(
    free: np.ndarray, max_radius: int, *, padding: int, size: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """The radii of :func:`inscribed_circle_radii` for a ``free`` window (its bounding box
    plus margin), and the int32 storage they are the first pixels of, with room for the
    image padded by ``padding`` on every side (:class:`~.zone_graph.ZoneGraph` pads its
    labels in it: at 8000 px each fresh 256 MB image costs 0.15-0.6 s of page faults), and
    at least ``size`` pixels (the segmentation makes its output there too)."""
    # Cropping to the free pixels' bounding box plus a 1-pixel obstacle margin
    # leaves the distance transform unchanged (the margin is obstacle, and the
    # image border is kept where the box touches it).
    rows, cols = free.shape
    storage = np.empty(max((rows + 2 * padding) * (cols + 2 * padding), size), np.float32)
    dist = storage[: rows * cols].reshape(rows, cols)
    # The exact distances along rows (:mod:`.kernels.distance`): cv2.distanceTransform's
    # (DIST_MASK_PRECISE) column pass grew x4.8 from 4000 to 8000 px; the floors are the same.
    kernels().distance_transform(free.view(np.uint8), dist)
    # Radii are int32 (as the output); a larger cap only matters without any obstacle.
    shapes = kernels().centre_rectangles(dist, min(max_radius, np.iinfo(np.int32).max))
    # The radii are painted over the distances, which the shapes replace: a fresh image cost
    # more in page faults than the painting, and the one image also stays in cache.
    out = dist.view(np.int32)
    out.fill(0)
    kernels().paint_discs(shapes, free.view(np.uint8), out)
    return out, storage.view(np.int32)


def _normalise_to_uint8(values: np.ndarray) -> np.ndarray:
    return _by_lookup(values, _normalise_exactly)


def _normalise_exactly(values: np.ndarray) -> np.ndarray:
    # cv::normalize(NORM_MINMAX, CV_8U) on a float image, as the C++ does.
    return cv2.normalize(np.asarray(values, np.float32), None, 0, 255, cv2.NORM_MINMAX, cv2.CV_8U)


def _by_lookup(values: np.ndarray, function) -> np.ndarray:
    """``function(values)`` for a ``function`` that maps each element by the
    element and the array's minimum and maximum only (a min-max normalisation).

    An integer image is mapped through a table: ``function`` of the range
    lo..hi of its values, which has the same minimum and maximum. At 4000 px
    that is one pass over the image instead of several float passes.
    """
    values = np.asarray(values)
    lookup = _lookup_table(values, function)
    if lookup is None:
        return function(values)
    lo, table = lookup
    hi = lo + len(table) - 1
    if values.dtype == np.int32 and table.dtype == np.uint8 and values.flags.c_contiguous:
        # The radii: one compiled pass, in parts on threads for large images, into a fresh image
        # (the offsets, the 8-bit indices and the table's result were three passes and a fresh
        # image on one thread: 0.22-0.25 s at 8000 x 8000 px).
        out = np.empty(values.shape, np.uint8)
        kernels().lookup_bytes(values, lo, np.ascontiguousarray(table), out)
        return out
    offsets = values - lo if lo else values
    if hi - lo <= 255:  # cv2.LUT takes 8-bit indices, and is several times faster than numpy
        indices = offsets.astype(np.uint8, copy=False)
        lut = np.pad(table, (0, 255 - (hi - lo)))
        if np.shares_memory(indices, values):  # the caller's image: the result is a new one
            return cv2.LUT(indices, lut)
        # Our own temporary takes the result: one fresh image fewer (64 MB at 8000 px).
        return cv2.LUT(indices, lut, dst=indices)
    return table[offsets]


def _lookup_table(values: np.ndarray, function, *, most: int = 1 << 16) -> tuple[int, np.ndarray] | None:
    """``(lo, table)`` with ``function(values) == table[values - lo]`` for a ``function`` of
    :func:`_by_lookup`'s kind, or None when ``values`` is not a 2-D integer image or its range
    is over ``most`` values."""
    if values.dtype.kind not in "iu" or values.ndim != 2 or values.size == 0:
        return None
    lo, hi = int(values.min()), int(values.max())
    if hi - lo > most:
        return None
    return lo, function(np.arange(lo, hi + 1, dtype=values.dtype)[None, :])[0]


def inscribed_circle_image(free: np.ndarray, *, max_radius: int = 500) -> np.ndarray:
    """Largest-inscribed-circle image, min-max normalised to 0..255 (uint8).

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
    max_radius : int, keyword-only

    Returns
    -------
    ndarray of uint8
        0 on obstacles; the largest radius maps to 255.

    Examples
    --------
    >>> free = np.zeros((9, 9), bool); free[1:8, 1:8] = True
    >>> int(inscribed_circle_image(free).max())
    255
    """
    return _normalise_to_uint8(inscribed_circle_radii(free, max_radius=max_radius))


# ---------------------------------------------------------------------------
# Step 2: quantisation


def _quantization_table(radii: np.ndarray, quantum: int) -> tuple[int, np.ndarray]:
    """``(lo, table)`` with ``table[radii - lo] == quantize(_normalise_to_uint8(radii),
    quantum=quantum)`` (uint8) for a non-empty 2-D integer image of radii.

    Both steps map each pixel by its value and the image's minimum and maximum only, and the
    normalisation keeps the order of values, so the normalised image's minimum and maximum are
    the normalised minimum and maximum: composing the two tables over the range of values gives
    the same image, without the two intermediate uint8 images (64 MB each at 8000 px). The
    segmentation reads the table while it labels the flat zones, so no value image is made at all.
    The radii of a map are below its diagonal (under 2**21 px: the distance transform refuses
    sides of 2**20 px), so the table is at most 2 MB.
    """
    lookup = _lookup_table(radii, lambda values: quantize(_normalise_exactly(values), quantum=quantum), most=1 << 22)
    if lookup is None:
        raise SegmentationError(
            f"radii must be a non-empty 2-D integer image of a range under 2**22, got {radii.shape}"
        )
    return lookup[0], np.ascontiguousarray(lookup[1], np.uint8)


def quantize(values: np.ndarray, *, quantum: int = 5) -> np.ndarray:
    """Min-max normalise to 0..255, then round up to multiples of ``quantum``.

    0 stays 0 (walls); results above 255 are clipped to 255.

    Parameters
    ----------
    values : ndarray
    quantum : int, keyword-only

    Returns
    -------
    ndarray of uint8

    Examples
    --------
    >>> quantize(np.array([[0, 1, 5, 6, 254, 255]], np.uint8)).tolist()
    [[0, 5, 5, 10, 255, 255]]
    """
    quantum = int(quantum)
    if not 1 <= quantum <= 255:
        raise ParameterError(f"must be in 1..255, got {quantum!r}", field="quantum")

    def exactly(values: np.ndarray) -> np.ndarray:
        normalised = _normalise_exactly(values).astype(np.int32)
        return np.minimum(-(-normalised // quantum) * quantum, 255).astype(np.uint8)

    return _by_lookup(values, exactly)
