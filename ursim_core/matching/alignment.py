"""How well a sketch's free space overlaps the metric map's once turned to an orientation and fitted.

The planar matcher's hypothesis score alone picks the right orientation of a sketch only part of
the time: a turned sketch can find a cheap but wrong matching, because the signatures do not see
orientation and the position term adapts to whatever orientation it is given. The overlap of the
two maps' free space is independent evidence: turned to the right orientation, a sketch can be
stretched and shifted to cover the metric map's free space well; turned wrongly, its corridors and
rooms fall on walls. :func:`fit_alignment` finds that stretch and shift (an axis-aligned scale
per axis, a shift and a small turn on top of the candidate orientation) by a pattern search that
maximises the intersection over union of the two free spaces at a coarse resolution.

On the 18 KTH sketches in their 8 orientations (144 cases; the right orientation read off the
ground-truth cliques), the hypothesis score picked the right orientation in 92 cases, the overlap
alone in 96, and the score divided by the overlap (:func:`ursim_core.matching.pipeline.prepare`)
in 120: the two fail on different sketches.

Everything here is (row, col); a 2 x 3 ``matrix`` maps a sketch pixel ``p`` to
``matrix[:, :2] @ p + matrix[:, 2]`` in the metric map.

The search runs in C where the matcher's C module is built (:mod:`ursim_core.matching.kernels`,
:file:`csrc/overlap.c`): the same points in the same order, with OpenCV's nearest-neighbour warp
done as OpenCV 4 does it and only its counts made; the same overlaps and matrices, bit for bit (a
test compares both). The Python search below stays the reference and the fallback.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ursim_core.matching.kernels import overlap_search_compiled
from ursim_core.matching.orientation import transform_points

__all__ = ["Alignment", "fit_alignment", "fit_alignments", "free_box_corners", "orientation_matrix"]

#: Long side, in pixels, of the metric map's free space when the overlap is measured: coarse
#: enough for a few hundred overlaps per orientation in milliseconds, fine enough for corridors
#: of a KTH-sized map (a 512 px map becomes 96 px: a 12 px corridor is 2 px).
_SIDE = 96
#: First steps of the pattern search: log-scale per axis, shift per axis (fraction of the metric
#: map's extent) and turn (radians, about 6 degrees: the wall angles already agree).
_FIRST_STEPS = (0.2, 0.2, 0.1, 0.1, 0.1)
#: The search stops when every step is below this. Round 18: 0.02 instead of 0.005 took a fit of
#: the 8 orientations of a KTH pair from 15.8 to 10.7 ms median; the overlaps moved by 0.015 at
#: most, the KTH evaluation in the 8 orientations was unchanged and at 15-degree steps 5 of the
#: 432 sketch orientations changed (3 better, 2 worse); the Hungarian and VF2 baselines, which
#: choose their orientation the same way, changed on 6 sketches upright (mean F1 at automatic m
#: -0.001 to +0.028). Chosen for speed, checked on the same 18 sketches.
_SMALLEST_STEP = 0.02
_MAX_ROUNDS = 60


@dataclass(frozen=True)
class Alignment:
    """A sketch fitted onto a metric map in one orientation.

    Attributes
    ----------
    overlap : float
        Intersection over union of the fitted sketch's free space and the metric map's, in [0, 1],
        measured at the coarse resolution of the search.
    matrix : ndarray, shape (2, 3)
        Sketch pixel (row, col) to metric pixel (row, col).
    degrees, mirrored
        The orientation the fit started from (see :mod:`ursim_core.matching.orientation`).
    """

    overlap: float
    matrix: np.ndarray
    degrees: float
    mirrored: bool

    @classmethod
    def unfitted(cls, degrees: float, mirrored: bool) -> Alignment:
        """No fit (a map without free space): overlap 0, the orientation's turn alone."""
        turn = orientation_matrix(degrees=degrees, mirrored=mirrored)
        return cls(0.0, np.hstack([turn, np.zeros((2, 1))]), float(degrees), bool(mirrored))


def orientation_matrix(*, degrees: float, mirrored: bool) -> np.ndarray:
    """The 2 x 2 (row, col) matrix of :func:`~ursim_core.matching.orientation.transform_points`.

    Examples
    --------
    >>> orientation_matrix(degrees=90, mirrored=False).round(6) + 0.0
    array([[ 0., -1.],
           [ 1.,  0.]])
    """
    return transform_points(np.eye(2), degrees=degrees, mirrored=mirrored).T


def _shrunk(mask: np.ndarray, factor: float) -> np.ndarray:
    import cv2

    shape = (max(1, round(mask.shape[1] * factor)), max(1, round(mask.shape[0] * factor)))
    return cv2.resize(mask.astype(np.uint8), shape, interpolation=cv2.INTER_AREA)


def free_box_corners(free: np.ndarray) -> np.ndarray | None:
    """The four (row, col) corners of the box around a mask's True pixels; None when it has none.

    Reads each row and column once (no index arrays of every free pixel), so it is cheap on
    building-sized maps.

    Examples
    --------
    >>> free = np.zeros((5, 6), bool); free[1:3, 2:5] = True
    >>> free_box_corners(free).tolist()
    [[1.0, 2.0], [1.0, 4.0], [2.0, 2.0], [2.0, 4.0]]
    """
    rows = np.flatnonzero(free.any(axis=1))
    if not len(rows):
        return None
    cols = np.flatnonzero(free.any(axis=0))
    top, bottom, left, right = float(rows[0]), float(rows[-1]), float(cols[0]), float(cols[-1])
    return np.array([[top, left], [top, right], [bottom, left], [bottom, right]])


class _FreeSpace:
    """What the fits need of one map's free space, computed once for every orientation tried."""

    def __init__(self, free, *, shrink_to: int):
        free = np.asarray(free) != 0
        self.corners = free_box_corners(free)
        self.empty = self.corners is None
        if self.empty:
            return
        self.low, self.high = self.corners[0], self.corners[3]
        self.factor = min(1.0, shrink_to / max(free.shape))
        self.shrunk = _shrunk(free, self.factor)


def fit_alignments(sketch_free, metric_free, orientations) -> list[Alignment]:
    """:func:`fit_alignment` for several ``(degrees, mirrored)`` orientations, the maps read once.

    Examples
    --------
    >>> free = np.zeros((40, 80), bool); free[5:35, 5:30] = True; free[15:25, 30:75] = True
    >>> [round(a.overlap, 1) for a in fit_alignments(free, free, [(0.0, False), (0.0, True)])][0]
    1.0
    """
    metric = _FreeSpace(metric_free, shrink_to=_SIDE)
    # The sketch is shrunk to twice the target's resolution, which keeps its thin strokes.
    sketch = _FreeSpace(sketch_free, shrink_to=2 * _SIDE)
    return [_fit(sketch, metric, float(degrees), bool(mirrored)) for degrees, mirrored in orientations]


def fit_alignment(sketch_free, metric_free, *, degrees: float = 0.0, mirrored: bool = False) -> Alignment:
    """Fit the sketch onto the metric map in one orientation, maximising free-space overlap.

    The fit starts with the sketch's free-space box (turned) stretched onto the metric map's and
    improves the scale of each axis, the shift and a turn of a few degrees by a pattern search.

    Parameters
    ----------
    sketch_free, metric_free : ndarray, shape (rows, cols)
        Free space (bool, or a label image: non-zero is free).
    degrees, mirrored : keyword-only
        The orientation: mirrored left-right first, then turned counter-clockwise.

    Returns
    -------
    Alignment
        ``overlap`` 0 when either map has no free space.

    Examples
    --------
    >>> free = np.zeros((40, 80), bool); free[5:35, 5:30] = True; free[15:25, 30:75] = True
    >>> round(fit_alignment(free, free).overlap, 2) > 0.9
    True
    >>> fit_alignment(free, free, degrees=180).overlap < 0.7
    True
    """
    return fit_alignments(sketch_free, metric_free, [(degrees, mirrored)])[0]


def _fit(sketch: _FreeSpace, metric: _FreeSpace, degrees: float, mirrored: bool) -> Alignment:
    import cv2

    turn = orientation_matrix(degrees=degrees, mirrored=mirrored)
    if sketch.empty or metric.empty:
        return Alignment.unfitted(degrees, mirrored)
    turned = sketch.corners @ turn.T
    sketch_low, sketch_high = turned.min(axis=0), turned.max(axis=0)
    extent = np.maximum(metric.high - metric.low, 1.0)
    base_scale = extent / np.maximum(sketch_high - sketch_low, 1.0)
    metric_extent = extent.tolist()
    metric_centre = ((metric.low + metric.high) / 2).tolist()
    # The sketch point that the turn sends to the turned box's centre.
    sketch_centre = np.linalg.solve(turn, (sketch_low + sketch_high) / 2)
    # Both shrunk masks hold 0 and 1 only (INTER_AREA of a 0/1 image rounds to 0 or 1, and the
    # nearest-neighbour warp keeps the values), so OpenCV's bitwise and and count are exact here,
    # and cheaper than NumPy's comparisons and counts at ~80 evaluations a fit.
    target = metric.shrunk
    target_area = cv2.countNonZero(target)
    size = (target.shape[1], target.shape[0])
    to_coarse = metric.factor / sketch.factor

    (t00, t01), (t10, t11) = turn.tolist()
    scale_rows, scale_cols = base_scale.tolist()
    centre_rows, centre_cols = sketch_centre.tolist()

    def linear_offset(params) -> tuple[float, ...]:
        # linear = turn(angle) @ diag(scales) @ turn; plain floats: this runs ~80 times a fit.
        log_rows, log_cols, shift_rows, shift_cols, angle = params
        c, s = math.cos(angle), math.sin(angle)
        a, d = scale_rows * math.exp(log_rows), scale_cols * math.exp(log_cols)
        m00, m01, m10, m11 = a * t00, a * t01, d * t10, d * t11
        l00, l01, l10, l11 = c * m00 - s * m10, c * m01 - s * m11, s * m00 + c * m10, s * m01 + c * m11
        # The turned sketch's box centre lands on the metric box centre plus the shift.
        o0 = metric_centre[0] + shift_rows * metric_extent[0] - (l00 * centre_rows + l01 * centre_cols)
        o1 = metric_centre[1] + shift_cols * metric_extent[1] - (l10 * centre_rows + l11 * centre_cols)
        return l00, l01, l10, l11, o0, o1

    def overlap_of(params) -> float:
        l00, l01, l10, l11, o0, o1 = linear_offset(params)
        k, f = to_coarse, metric.factor
        # Pixel centres: index q of a map shrunk by g is the full-size index (q + 0.5) / g - 0.5
        # (cv2.resize), so the offset gains (k - f) * linear @ (0.5, 0.5) + 0.5 * f - 0.5.
        half = 0.5 * (k - f)
        c0 = f * o0 + half * (l00 + l01) + 0.5 * f - 0.5
        c1 = f * o1 + half * (l10 + l11) + 0.5 * f - 0.5
        # OpenCV's matrix is (x, y) = (col, row): rows and columns of the (row, col) one swapped.
        opencv = np.array([[l11 * k, l10 * k, c1], [l01 * k, l00 * k, c0]])
        warped = cv2.warpAffine(sketch.shrunk, opencv, size, flags=cv2.INTER_NEAREST)
        inter = cv2.countNonZero(cv2.bitwise_and(warped, target))
        union = cv2.countNonZero(warped) + target_area - inter
        return inter / union if union else 0.0

    def matrix_of(params) -> np.ndarray:
        l00, l01, l10, l11, o0, o1 = linear_offset(params)
        return np.array([[l00, l01, o0], [l10, l11, o1]])

    # The same search in C (matching.kernels), OpenCV's warp done as OpenCV does it.
    numbers = {
        "turn": (t00, t01, t10, t11),
        "scale": (scale_rows, scale_cols),
        "centre": (centre_rows, centre_cols),
        "metric_centre": metric_centre,
        "metric_extent": metric_extent,
        "to_coarse": to_coarse,
        "factor": metric.factor,
    }
    compiled = overlap_search_compiled(
        sketch.shrunk, target, target_area, numbers,
        first_steps=_FIRST_STEPS, smallest_step=_SMALLEST_STEP, max_rounds=_MAX_ROUNDS,
    )  # fmt: skip
    if compiled is not None:
        best, params = compiled
        return Alignment(float(best), matrix_of(list(params)), degrees, mirrored)

    # A step back after a move lands on a point already scored: look it up, do not warp again.
    seen: dict[tuple, float] = {}

    def scored(params) -> float:
        key = tuple(params)
        if key not in seen:
            seen[key] = overlap_of(params)
        return seen[key]

    params = [0.0] * 5
    best = scored(params)
    steps = list(_FIRST_STEPS)
    for _ in range(_MAX_ROUNDS):
        improved = False
        for axis in range(len(params)):
            for sign in (1.0, -1.0):
                trial = list(params)
                trial[axis] += sign * steps[axis]
                value = scored(trial)
                if value > best + 1e-12:
                    best, params, improved = value, trial, True
        if not improved:
            steps = [step / 2 for step in steps]
            if max(steps) < _SMALLEST_STEP:
                break
    return Alignment(float(best), matrix_of(params), degrees, mirrored)
