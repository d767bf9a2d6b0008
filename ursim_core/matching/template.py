"""Where a sketch of part of a building sits on the metric map: a template search over windows.

Laid box onto box (:func:`~ursim_core.matching.layings.box_laying`), a sketch of part of a building
is stretched over the whole metric map, and the flow that bends it cannot undo a stretch of a
third. :func:`best_window` instead slides the sketch, shrunk to a range of sizes, over the metric
map at a coarse size and keeps the window where the two maps' signed distance images correlate
best (OpenCV's normalised cross-correlation, ``TM_CCOEFF_NORMED``), with how much better that
window correlates than the whole map's box does. :func:`~ursim_core.matching.elastic.lay_sketch`
lays the sketch in that window only when it is clearly better (:data:`WINDOW_GAIN`: a whole
sketch correlates a little better with some part of the map too) and resembles that part
(:data:`WINDOW_MIN_CORRELATION`).

Everything here is on boolean free-space images in (row, col); the sketch is already in the
orientation it is read in.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ursim_core.segmentation.canonical import free_window

__all__ = [
    "COARSE_SIDE",
    "WINDOW_CLIP",
    "WINDOW_SIDES",
    "WINDOW_REFINE",
    "WINDOW_ASPECTS",
    "WINDOW_MIN_AREA",
    "WINDOW_GAIN",
    "WINDOW_MIN_CORRELATION",
    "Window",
    "signed_distance",
    "free_box",
    "best_window",
]

#: The metric map's longer side (pixels) during the search: enough for corridors and rooms to show.
COARSE_SIDE = 128
#: Signed distances are clipped at this many pixels of the coarse size either side of a wall.
WINDOW_CLIP = 12.0
#: The window's size as a share of the largest window of the sketch's shape within the metric
#: map's box (a sketch of the whole building down to half of its width and height), first pass.
WINDOW_SIDES = (1.0, 0.9, 0.8, 0.7, 0.6, 0.5)
#: The second pass: the first pass's best size this much larger and smaller.
WINDOW_REFINE = 0.05
#: The window's width over what the sketch's shape gives. The sketch's own shape only: also 1.1
#: and 1 / 1.1 wide gave told F1 0.965 / 0.958 against 0.964 / 0.955 (round 47, generated seeds
#: 0-31 / 32-63) at 21 % more time per turned KTH pair against 8 % (interleaved).
WINDOW_ASPECTS = (1.0,)
#: The smallest window tried, as a share of the metric map box's area: a sketch of a third of the
#: map or more. Smaller windows correlate well by chance with a room or two (round 47: the windows
#: of generated partial sketches that lost F1 covered 0.19-0.29 of the map's box, the right ones
#: 0.43-0.89; KTH sketches 10 and 18 were laid in windows of 0.18 and 0.16).
WINDOW_MIN_AREA = 0.35
#: How much better (in correlation) the best window must be than the map's whole box for the
#: sketch to be laid in it (round 47, generated seeds 0-63 told their orientation; docs/options.md).
WINDOW_GAIN = 0.15
#: How well the best window must correlate at least for the sketch to be laid in it: a sketch of
#: part of the map resembles that part. (Round 47, generated seeds 0-63 told their orientation, in
#: sample: of the windows used, those under 0.6 lost F1 in three cases and gained in two; a row of
#: equal rooms drawn for a row of unequal ones correlates 0.53 with its best window.)
WINDOW_MIN_CORRELATION = 0.6
#: Coarse pixels the window may reach past the metric map's box (a sketch drawn a little large).
_PAD = 4


class Window(NamedTuple):
    """Where :func:`best_window` puts the sketch's box on the metric map, in the metric map's
    pixels: ``(top, left)`` and ``(height, width)``; ``correlation`` there, and ``gain``, how
    much higher it is than the correlation of the sketch stretched over the map's whole box."""

    top: float
    left: float
    height: float
    width: float
    correlation: float
    gain: float


def signed_distance(free: np.ndarray, *, clip: float) -> np.ndarray:
    """Distance to the nearest wall, positive inside the free space and negative outside, clipped
    at ``clip`` pixels (also the elastic laying's flow image, ``elastic.signed_distance``).

    Examples
    --------
    >>> free = np.zeros((7, 7), bool); free[1:6, 1:6] = True
    >>> signed_distance(free, clip=2)[3].tolist()
    [-1.0, 1.0, 2.0, 2.0, 2.0, 1.0, -1.0]
    """
    import cv2

    free = np.asarray(free, bool)
    inside = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_5)
    outside = cv2.distanceTransform((~free).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_5)
    return np.clip(inside - outside, -clip, clip).astype(np.float32)


def free_box(free: np.ndarray) -> tuple[int, int, int, int] | None:
    """``(first row, end row, first col, end col)`` of the box around the non-zero pixels of
    ``free`` (ends exclusive), or None when there are none.

    Examples
    --------
    >>> free = np.zeros((5, 6), bool); free[1:3, 2:5] = True
    >>> free_box(free), free_box(np.zeros((2, 2), bool))
    ((1, 3, 2, 5), None)
    """
    window = free_window(free)
    if window is None:
        return None
    rows, cols = window
    return rows.start, rows.stop, cols.start, cols.stop


def best_window(
    sketch_free: np.ndarray,
    metric_free: np.ndarray,
    *,
    sides=WINDOW_SIDES,
    refine: float = WINDOW_REFINE,
    aspects=WINDOW_ASPECTS,
    min_area: float = WINDOW_MIN_AREA,
    coarse: int = COARSE_SIDE,
    clip: float = WINDOW_CLIP,
) -> Window | None:
    """The window of the metric map where the sketch's free space correlates best with it.

    Parameters
    ----------
    sketch_free, metric_free : ndarray of bool, shape (rows, cols)
        Free space; the sketch in the orientation it is read in.
    sides, refine, aspects : keyword-only
        The windows tried besides the map's whole box: the sketch's box, scaled to the largest
        of its shape that fits in the map's box, times each of :data:`WINDOW_SIDES`; then the best
        of those times ``1 +- refine`` (:data:`WINDOW_REFINE`), and its width (and theirs) times
        each of :data:`WINDOW_ASPECTS`.
    min_area : float, keyword-only
        :data:`WINDOW_MIN_AREA`: smaller windows are not tried.
    coarse, clip : keyword-only
        :data:`COARSE_SIDE` and :data:`WINDOW_CLIP`.

    Returns
    -------
    Window or None
        None when either map has no free space, or the sketch is flat (one value throughout).

    Examples
    --------
    Five rooms along a corridor, and a sketch of the plan's left half:

    >>> plan = np.zeros((300, 600), bool)
    >>> plan[20:130, 20:150] = plan[20:130, 160:400] = plan[20:130, 410:580] = True
    >>> plan[140:170, 20:580] = True
    >>> plan[180:280, 20:260] = plan[180:280, 270:580] = True
    >>> window = best_window(plan[:, :320], plan)
    >>> abs(window.left - 20) < 10, abs(window.width - 300) < 30, window.gain > WINDOW_GAIN
    (True, True, True)
    >>> best_window(plan, plan).gain < WINDOW_GAIN
    True
    """
    import cv2

    sketch_free, metric_free = np.asarray(sketch_free, bool), np.asarray(metric_free, bool)
    sketch_box, metric_box = free_box(sketch_free), free_box(metric_free)
    if sketch_box is None or metric_box is None:
        return None
    factor = coarse / max(metric_free.shape)
    shape = (max(1, round(metric_free.shape[0] * factor)), max(1, round(metric_free.shape[1] * factor)))
    metric = cv2.resize(metric_free.astype(np.uint8), shape[::-1], interpolation=cv2.INTER_AREA) > 0
    metric_image = signed_distance(np.pad(metric, _PAD), clip=clip)
    (r0, r1, c0, c1), (m0, m1, n0, n1) = sketch_box, metric_box
    height, width = (m1 - m0) * factor, (n1 - n0) * factor
    # The sketch kept in proportion: the largest window of its box's shape within the map's box,
    # then smaller; the map's whole box (the box laying, stretched to it) is the reference.
    fit = min(height / (r1 - r0), width / (c1 - c0))
    # Shrunk once to twice the largest window (a turned sketch is a thousand pixels a side), and
    # each window from that: the share of free space in each coarse pixel, free where at least
    # half is (as the map's, whose 0/1 means OpenCV rounds).
    largest = max(height, (r1 - r0) * fit * max(sides)), max(width, (c1 - c0) * fit * max(sides) * max(aspects))
    source_shape = (min(r1 - r0, 2 * round(largest[0]) + 1), min(c1 - c0, 2 * round(largest[1]) + 1))
    source = cv2.resize(sketch_free[r0:r1, c0:c1].astype(np.float32), source_shape[::-1], interpolation=cv2.INTER_AREA)

    def correlation(rows: float, cols: float):
        rows, cols = max(3, round(rows)), max(3, round(cols))
        if rows > metric_image.shape[0] or cols > metric_image.shape[1] or rows * cols < min_area * height * width:
            return None
        shrunk = cv2.resize(source, (cols, rows), interpolation=cv2.INTER_AREA) >= 0.5
        # What lies beyond the sketch's box is unknown: a wall (a whole building's outline) or
        # more rooms (where a partial sketch is cut). Only the pixels whose distance is the same
        # either way are compared (walled in alone, or open alone, the windows found were
        # smaller or larger than the part's: round 47).
        template = signed_distance(shrunk, clip=clip)
        known = np.abs(template - signed_distance(np.pad(shrunk, 1), clip=clip)[1:-1, 1:-1]) < 0.5
        if np.count_nonzero(known) < known.size // 4 or float(template[known].std()) < 1e-6:
            return None
        found = cv2.matchTemplate(metric_image, template, cv2.TM_CCOEFF_NORMED, mask=known.astype(np.float32))
        _, value, _, (x, y) = cv2.minMaxLoc(np.nan_to_num(found, nan=-1.0, posinf=-1.0, neginf=-1.0))
        return value, y, x, rows, cols

    whole = correlation(height, width)
    # Coarse to fine: the sizes in proportion first, then the best of them a step either way (and,
    # with aspects other than 1, a little wider and narrower): about half the correlations of the
    # full grid of sizes, for the same told F1 on the generated pairs (round 47).
    tried = {side: correlation((r1 - r0) * fit * side, (c1 - c0) * fit * side) for side in sides}
    found = {side: value for side, value in tried.items() if value is not None}
    best = max([whole] + list(found.values()), key=lambda value: -2.0 if value is None else value[0])
    if found:
        side = max(found, key=lambda key: found[key][0])
        refined = [(side + step, 1.0) for step in (-refine, refine)]
        refined += [(side + step, aspect) for step in (-refine, 0.0, refine) for aspect in aspects if aspect != 1.0]
        for size, aspect in refined:
            value = correlation((r1 - r0) * fit * size, (c1 - c0) * fit * size * aspect)
            if value is not None and (best is None or value[0] > best[0]):
                best = value
    if best is None:
        return None
    value, y, x, rows, cols = best
    gain = value - whole[0] if whole is not None else 0.0
    return Window((y - _PAD) / factor, (x - _PAD) / factor, rows / factor, cols / factor, float(value), float(gain))
