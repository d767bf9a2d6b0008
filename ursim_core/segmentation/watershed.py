"""Distance-transform watershed with door merging by saddle ratio (robot occupancy maps).

A room is a basin of the clearance (the distance to the nearest obstacle), a door is a
narrow pass between two basins. :func:`watershed_labels`:

1. clearance ``d`` = Euclidean distance transform of the free space;
2. markers = the connected plateaus of local maxima of ``d`` (3x3), and a watershed of
   ``-d`` over the free pixels gives one basin per marker: scikit-image's labels, from
   :mod:`ursim_core.segmentation.flooding` (its heap replayed in a compiled kernel);
3. two touching basins a, b merge when their *saddle ratio* ``s(a, b) / min(peak(a),
   peak(b))`` is at least ``door_ratio``, highest ratio first: ``s`` is the largest
   clearance on their shared boundary (the widest point of the pass), ``peak`` a basin's
   largest clearance. A door is a pass much narrower than the rooms on both sides (a low
   ratio); the ridges of one room or one corridor are passes nearly as wide as the room
   (a ratio near 1). A merged basin keeps the larger peak and the wider pass to each
   neighbour;
4. regions smaller than ``min_size`` px join the neighbour they share the longest
   boundary with (regions without neighbours are dropped).

Regions are numbered 1..N in the raster order of their first pixel; obstacles are 0.

Examples
--------
>>> import numpy as np
>>> free = np.zeros((60, 130), bool)
>>> free[5:55, 5:60] = free[5:55, 70:125] = True   # two rooms
>>> free[27:33, 60:70] = True                      # a door
>>> int(watershed_labels(free).max())
2
"""

from __future__ import annotations

import heapq
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError, SegmentationError

__all__ = [
    "watershed_labels",
    "resolve_watershed_params",
    "merge_small_regions",
    "in_raster_order",
    "WATERSHED_DEFAULTS",
]

#: Default parameters: the best mean F1 of the grid door_ratio 0.7-0.9 x min_size 50-200 on
#: the 15 robot maps of ``maoris_segmentation``. Chosen without each map in turn and scored
#: on it (:func:`ursim_core.segmentation.presets_cv.cross_validate`): F1 .954 (worst map
#: .874), MAORIS ``default`` .927. The grid's range was set after a first grid (0.4-0.8)
#: chose its edge; a grid 0.85-0.96 x 100-400 gives .950 cross-validated.
WATERSHED_DEFAULTS: dict[str, Any] = {"door_ratio": 0.9, "min_size": 100}


def resolve_watershed_params(params: dict[str, Any]) -> dict[str, Any]:
    """The defaults updated by ``params``, validated (:class:`~ursim_core.errors.ParameterError`)."""
    known = set(WATERSHED_DEFAULTS)
    for name in params:
        if name not in known:
            raise ParameterError(f"unknown watershed parameter (known: {', '.join(sorted(known))})", field=str(name))
    values = {**WATERSHED_DEFAULTS, **params}
    ratio, min_size = values["door_ratio"], values["min_size"]
    if isinstance(ratio, bool) or not isinstance(ratio, (int, float)) or not 0.0 <= float(ratio) <= 1.0:
        raise ParameterError(f"must be a number in [0, 1], got {ratio!r}", field="door_ratio")
    if isinstance(min_size, bool) or not isinstance(min_size, (int, np.integer)) or min_size < 0:
        raise ParameterError(f"must be an integer >= 0, got {min_size!r}", field="min_size")
    return {"door_ratio": float(ratio), "min_size": int(min_size)}


def _pairs(labels: np.ndarray, clearance: np.ndarray):
    """4-adjacent pixel pairs of different non-zero labels: (low, high, pass clearance)."""
    lows, highs, passes = [], [], []
    for a, b, da, db in (
        (labels[:, :-1], labels[:, 1:], clearance[:, :-1], clearance[:, 1:]),
        (labels[:-1, :], labels[1:, :], clearance[:-1, :], clearance[1:, :]),
    ):
        touching = (a != b) & (a != 0) & (b != 0)
        first, second = a[touching], b[touching]
        lows.append(np.minimum(first, second))
        highs.append(np.maximum(first, second))
        passes.append(np.minimum(da[touching], db[touching]))
    return np.concatenate(lows), np.concatenate(highs), np.concatenate(passes)


def _boundaries(labels: np.ndarray, clearance: np.ndarray, count: int):
    """``{(a, b): [saddle, boundary length]}`` for touching regions a < b."""
    low, high, passes = _pairs(labels, clearance)
    if low.size == 0:
        return {}
    keys = low.astype(np.int64) * count + high
    unique, inverse, lengths = np.unique(keys, return_inverse=True, return_counts=True)
    saddles = np.zeros(len(unique), np.float64)
    np.maximum.at(saddles, inverse, passes)
    return {(int(k // count), int(k % count)): [float(s), int(n)] for k, s, n in zip(unique.tolist(), saddles, lengths)}


def _merge_doorless(peaks: np.ndarray, boundaries: dict, door_ratio: float, parent: np.ndarray) -> None:
    """Merge touching basins by decreasing saddle ratio while it is >= ``door_ratio``."""
    neighbours: dict[int, dict[int, float]] = {}
    for (a, b), (saddle, _) in boundaries.items():
        neighbours.setdefault(a, {})[b] = saddle
        neighbours.setdefault(b, {})[a] = saddle
    peak = peaks.astype(np.float64).copy()

    def ratio(a: int, b: int, saddle: float) -> float:
        smaller = min(peak[a], peak[b])
        return saddle / smaller if smaller > 0 else 0.0

    heap = [(-ratio(a, b, s), a, b) for (a, b), (s, _) in boundaries.items()]
    heapq.heapify(heap)
    while heap:
        negative, a, b = heapq.heappop(heap)
        if -negative < door_ratio:
            break
        if parent[a] != a or parent[b] != b or b not in neighbours.get(a, {}):
            continue
        current = ratio(a, b, neighbours[a][b])
        if current != -negative:  # stale entry: the pair changed since it was pushed
            heapq.heappush(heap, (-current, a, b))
            continue
        # Fuse the basin with fewer neighbours into the other one.
        keep, gone = (a, b) if len(neighbours[a]) >= len(neighbours[b]) else (b, a)
        parent[gone] = keep
        peak[keep] = max(peak[keep], peak[gone])
        del neighbours[keep][gone]
        for other, saddle in neighbours.pop(gone).items():
            if other == keep:
                continue
            del neighbours[other][gone]
            widest = max(saddle, neighbours[keep].get(other, 0.0))
            neighbours[keep][other] = neighbours[other][keep] = widest
        for other, saddle in neighbours[keep].items():
            heapq.heappush(heap, (-ratio(keep, other, saddle), min(keep, other), max(keep, other)))


def _roots(parent: np.ndarray) -> np.ndarray:
    while True:
        jumped = parent[parent]
        if np.array_equal(jumped, parent):
            return parent
        parent = jumped


def _merge_small(labels: np.ndarray, clearance: np.ndarray, min_size: int) -> np.ndarray:
    """Join regions under ``min_size`` px to the neighbour with the longest shared boundary,
    smallest region first; regions without neighbours are dropped."""
    count = int(labels.max()) + 1
    sizes = np.bincount(labels.ravel(), minlength=count).astype(np.int64)
    if min_size <= 0 or not (sizes[1:] < min_size).any():
        return labels
    lengths = {pair: length for pair, (_, length) in _boundaries(labels, clearance, count).items()}
    return _roots(_small_merge_parents(sizes, lengths, min_size))[labels]


def _small_merge_parents(sizes: np.ndarray, lengths: dict, min_size: int) -> np.ndarray:
    """The parent of each region after :func:`_merge_small`'s joins (0 = dropped), from the
    region sizes and the boundary length of each touching pair ``(a, b)``, a < b."""
    count = len(sizes)
    sizes = sizes.copy()
    contacts: dict[int, dict[int, int]] = {}
    for (a, b), length in lengths.items():
        contacts.setdefault(a, {})[b] = length
        contacts.setdefault(b, {})[a] = length
    parent = np.arange(count)
    heap = [(int(sizes[r]), r) for r in range(1, count) if 0 < sizes[r] < min_size]
    heapq.heapify(heap)
    while heap:
        size, region = heapq.heappop(heap)
        if parent[region] != region or size != sizes[region] or size >= min_size:
            continue
        touching = contacts.pop(region, {})
        if not touching:
            parent[region] = 0
            continue
        into = max(touching, key=lambda other: (touching[other], -other))
        parent[region] = into
        sizes[into] += sizes[region]
        for other, length in touching.items():
            del contacts[other][region]
            if other != into:
                contacts[into][other] = contacts[other][into] = contacts[into].get(other, 0) + length
        if sizes[into] < min_size:
            heapq.heappush(heap, (int(sizes[into]), into))
    return parent


def watershed_labels(free: np.ndarray, **params: Any) -> np.ndarray:
    """Segment a free-space mask into rooms: clearance watershed, doors by saddle ratio.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True = free space.
    door_ratio : float, keyword-only
        Touching basins merge while the widest point of their pass is at least this
        fraction of the smaller basin's largest clearance (0..1; higher keeps more doors).
    min_size : int, keyword-only
        Regions smaller than this (px) join a neighbour.

    Returns
    -------
    ndarray of int32
        0 = obstacle; regions 1..N in the raster order of their first pixel.

    Examples
    --------
    >>> free = np.zeros((60, 130), bool)
    >>> free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True  # two rooms, a door
    >>> labels = watershed_labels(free)
    >>> labels.dtype, int(labels[0, 0]), int(labels[30, 30]), int(labels[30, 100])  # wall, rooms
    (dtype('int32'), 0, 1, 2)
    >>> int(watershed_labels(free, door_ratio=0.0).max())  # every pass counts as wide: one region
    1
    """
    import cv2
    from scipy import ndimage

    from ursim_core.segmentation.flooding import clearance_levels, flood_levels

    options = resolve_watershed_params(params)
    free = np.asarray(free)
    if free.ndim != 2 or free.size == 0:
        raise SegmentationError(f"free-space mask must be a non-empty 2-D array, got shape {free.shape}")
    free = free.astype(bool, copy=False)
    if not free.any():
        return np.zeros(free.shape, np.int32)
    # Contiguous: every step below reads it whole (a strided view is copied each time).
    clearance = np.ascontiguousarray(
        cv2.distanceTransform(np.pad(free, 1).view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)[1:-1, 1:-1]
    )
    # The 3x3 maximum; cv2 ignores the pixels beyond the border as ndimage's "reflect"
    # does for a 3x3 window (it reflects the border pixel itself), 7 times faster.
    peaks = free & (clearance >= cv2.dilate(clearance, np.ones((3, 3), np.uint8)))
    markers, _ = ndimage.label(peaks, structure=np.ones((3, 3), bool))
    basins = flood_levels(clearance_levels(clearance, free), markers, free, fallback=-clearance)
    count = int(basins.max()) + 1
    # Each basin's largest clearance. ndimage.maximum sorts every pixel by label (2.4 s at
    # 4000 px); an unbuffered maximum gives the same values in 0.15 s, in float32 (the
    # maximum of the float64 copies is the float64 copy of the maximum).
    peak_of = np.zeros(count, np.float32)
    np.maximum.at(peak_of, basins.ravel(), clearance.ravel())
    peak_of = peak_of.astype(np.float64)
    peak_of[0] = 0.0
    parent = np.arange(count)
    boundaries = _boundaries(basins, clearance, count)
    _merge_doorless(peak_of, boundaries, options["door_ratio"], parent)
    doorless = _roots(parent)
    # Step 4 on the basin tables rather than on a merged image (the same sizes and
    # boundary lengths, summed per merged region), and one lookup of the basins at the
    # end: each relabelling of the image costs a pass over every pixel.
    merged_sizes = np.bincount(
        doorless, weights=np.bincount(basins.ravel(), minlength=count), minlength=int(doorless.max()) + 1
    ).astype(np.int64)
    lengths: dict[tuple[int, int], int] = {}
    for (a, b), (_, length) in boundaries.items():
        a, b = int(doorless[a]), int(doorless[b])
        if a != b:
            pair = (a, b) if a < b else (b, a)
            lengths[pair] = lengths.get(pair, 0) + length
    final = doorless
    if options["min_size"] > 0:
        final = _roots(_small_merge_parents(merged_sizes, lengths, options["min_size"]))[doorless]
    return _raster_lookup(basins, final)[basins]


def _first_pixels(labels: np.ndarray, count: int) -> np.ndarray:
    """Flat index of each label's first pixel in raster order (``labels.size`` if absent),
    from the runs of equal labels along rows rather than every pixel."""
    starts = np.ones(labels.shape, bool)
    starts[:, 1:] = labels[:, 1:] != labels[:, :-1]
    flat_starts = np.flatnonzero(starts)
    first = np.full(count, labels.size, np.int64)
    np.minimum.at(first, labels.ravel()[flat_starts], flat_starts)
    return first


def _raster_lookup(basins: np.ndarray, final: np.ndarray) -> np.ndarray:
    """``lookup[basin]`` = the label of ``_in_raster_order(final[basins])``: a region's
    first pixel is the first of its basins' first pixels."""
    first = np.full(int(final.max()) + 1, basins.size, np.int64)
    np.minimum.at(first, final, _first_pixels(basins, len(final)))
    present = np.flatnonzero(first[1:] < basins.size) + 1
    rank = np.zeros(len(first), np.int32)
    rank[present[np.argsort(first[present], kind="stable")]] = np.arange(1, len(present) + 1, dtype=np.int32)
    return rank[final]


def _in_raster_order(labels: np.ndarray) -> np.ndarray:
    """Labels renumbered 1..N by the raster order of their first pixel (0 stays 0); as
    :func:`~ursim_core.segmentation.scoring.relabel_in_raster_order`, on the runs of
    equal labels along rows instead of a sort of every pixel."""
    return _raster_lookup(labels, np.arange(int(labels.max()) + 1))[labels]


def merge_small_regions(labels: np.ndarray, clearance: np.ndarray, min_size: int) -> np.ndarray:
    """Regions under ``min_size`` px joined to the neighbour they share the longest boundary
    with, smallest first; regions without neighbours become 0 (step 4 of
    :func:`watershed_labels`, for any label image). Labels are not renumbered."""
    return _merge_small(np.asarray(labels), clearance, int(min_size))


def in_raster_order(labels: np.ndarray) -> np.ndarray:
    """Labels renumbered 1..N by the raster order of their first pixel (0 stays 0)."""
    return _in_raster_order(np.asarray(labels))
