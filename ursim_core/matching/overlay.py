"""The overlay matcher (``MatchConfig(matcher="overlay")``): lay one map on the other, pair what overlaps.

Two maps of the same kind (two robot maps of a building, a robot map and a floor plan drawn to
scale) differ by a turn, a shift and perhaps a known scale, and either may cover only part of the
other. Then the surest correspondence is geometric: find the turn and shift that lay the input map's
free space on the metric map's, and pair every region with the region of the other map it overlaps
most (intersection over union at least ``overlay_min_iou``), both ways. This is what metric map
alignment does (Shahbandi and Magnusson's DAM reaches F1 0.78 on Halmstad E5, where the planar
matcher, built for sketches, reaches 0.3).

Search (:func:`fit_overlay`): the orientation candidates are the quarter turns of the wall-angle
difference, as for the planar matcher (:mod:`ursim_core.matching.orientation`). With a known
``scale`` (metric pixels per input pixel: 1 for two maps of the same resolution), every candidate
and every scale within 20 % of it is tried, and for each the shift is found by correlation over all
placements at once (OpenCV's ``matchTemplate``): the input map's free space and the band of wall
around it (+1 and -1), laid on the metric map's free space and wall band, scored by their
normalised cross-correlation, so the input may cover any part of the metric map and neither a
shrunk nor a grown input is favoured. With no known scale it is estimated first
(:func:`estimate_scale`: the same search over 0.5 to 2), then searched within 20 % as a known one.
Round 28 (docs/studies.md): the earlier score, the share of the input's free space and wall band
that agrees, took the smallest scale allowed on the Halmstad E5 pairs it got wrong; with the
correlation, E5 0.69 -> 0.79 mean F1 and cropped copies of generated plans (held-out seeds 32-63)
0.80 -> 0.94 (0.97 with no wall band beyond a cut, :func:`_template`). With the orientation unknown
the matcher also tries each candidate turned by a few degrees (:func:`ranked_overlays`'
``angle_step``, ``MatchConfig.overlay_angle_step``), and its answer keeps every candidate's rank so
that a close call is reported (round 42).

Pairs a person gave (:mod:`ursim_core.matching.constraints`, two fixed pairs or more): the placement
is the similarity (turn, scale, shift) that carries their regions' centroids onto their partners'
(:func:`fit_to_pairs`, least squares), the mirror flag the one whose placement agrees better, as a
georeferencer's control points do; the fixed pairs are then in the answer and the forbidden ones are
not (:func:`constrained_pairs`).

Sketches are drawn out of proportion: for them the planar matcher is better (KTH: F1 0.72 against
0.63). On Halmstad E5 (robot maps of unknown, unequal scales) it gives F1 0.79 held out (README).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.matching.alignment import Alignment, free_box_corners, orientation_matrix
from ursim_core.matching.constraints import allowed_pairs

__all__ = [
    "fit_overlay",
    "ranked_overlays",
    "fit_to_pairs",
    "estimate_scale",
    "overlay_pairs",
    "overlay_overlaps",
    "constrained_pairs",
    "SCALE_SPREAD",
    "SCALE_SEARCH",
    "MAX_EXTENT",
]

#: Relative scales tried around a known scale: a robot map's resolution is known to a few percent.
SCALE_SPREAD = (0.8, 0.85, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2)
#: Scales tried by :func:`estimate_scale` when none is known: 0.5 to 2, in steps of about 7 %.
SCALE_SEARCH = tuple(float(v) for v in np.round(np.exp(np.linspace(np.log(0.5), np.log(2.0), 21)), 4))
#: Long side, in pixels, of the metric map during the search, and the wall band, in those pixels.
_SIDE = 160
_BAND = 2
#: The longest the input map may be laid, in units of the long side of the map it is laid on. The
#: correlation of a placement is at most the square root of the share of the template the other map
#: covers: beyond 4 times its length, at most 1/16 of it, so no placement correlates above 0.25
#: (the example pair at scale 3, 4.2 times: its two best readings tied), and the search grows with
#: the template's area (scale 5: 27 s; 10: 95 s; 100: OpenCV out of memory, or a crash).
MAX_EXTENT = 4.0


def _coarse(free: np.ndarray, factor: float) -> np.ndarray:
    import cv2

    shape = (max(1, round(free.shape[1] * factor)), max(1, round(free.shape[0] * factor)))
    return cv2.resize(free.astype(np.float32), shape, interpolation=cv2.INTER_AREA)


def _template_box(corners: np.ndarray, linear: np.ndarray, limit: float):
    """``(low, (rows, cols))`` of the template of the box ``corners`` under ``linear``; None when a
    side would be longer than ``limit`` pixels (or is not finite): no OpenCV call gets that size."""
    turned = corners @ linear.T
    low = turned.min(axis=0) - _BAND - 1
    extent = turned.max(axis=0) + _BAND + 1 - low
    if not (np.all(np.isfinite(extent)) and extent.max() + 1 <= limit):
        return None
    return low, (int(math.ceil(extent[0])) + 1, int(math.ceil(extent[1])) + 1)


def _template(free: np.ndarray, low: np.ndarray, shape: tuple[int, int], linear: np.ndarray):
    """The input map (float32 free space) under ``linear`` (coarse metric pixels per input pixel),
    in a ``shape`` window whose origin is ``low`` (:func:`_template_box`): free-space and wall-band
    templates, and the offset of their origin."""
    import cv2

    size = (shape[1], shape[0])
    offset = -low
    opencv = np.array([[linear[1, 1], linear[1, 0], offset[1]], [linear[0, 1], linear[0, 0], offset[0]]])
    flags = cv2.INTER_AREA if abs(np.linalg.det(linear)) < 1 else cv2.INTER_LINEAR
    warped = cv2.warpAffine(free, opencv, size, flags=flags).clip(0, 1)
    # A map cut at its image's edge (free space touching it) goes on beyond the edge: no wall is
    # there. The band is drawn around the free space with its edge pixels repeated outward, so a cut
    # adds none (without this, cropped copies of generated plans were laid at the right scale and
    # turn 18 times in 32 as free-space masks, against 32 as label images, whose slivers at the cut
    # MAORIS leaves unlabelled).
    extended = cv2.warpAffine(free, opencv, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)
    return warped, _wall_band((extended > 0.25).astype(np.uint8)), offset


def _wall_band(solid: np.ndarray) -> np.ndarray:
    """The ``_BAND`` pixels of wall around a 0/1 free-space mask (uint8), as float32 0/1."""
    import cv2

    return (cv2.dilate(solid, np.ones((2 * _BAND + 1, 2 * _BAND + 1), np.uint8)) - solid).astype(np.float32)


class _Side:
    """One map as the search reads it: its free space (float32) and box corners at full size, and
    reduced to about ``_SIDE`` pixels (``factor`` of the full size) its free space, its walls
    (everything not free) and its signed image (free space +1, the wall band around it -1, the
    rest 0: what is neither free nor near free space is unknown to a robot's map)."""

    def __init__(self, free: np.ndarray):
        self._free = free
        self.corners = free_box_corners(free)
        self.factor = min(1.0, _SIDE / max(free.shape))
        self.free = _coarse(free, self.factor)
        self.walls = 1.0 - self.free
        self.signed = self.free - _wall_band((self.free > 0.25).astype(np.uint8))

    @functools.cached_property
    def source(self) -> np.ndarray:
        # Only the map laid on the other one is warped at full size: the metric map's float copy
        # (256 MB at 8000 x 8000 px) is never made.
        return self._free.astype(np.float32)


def _best_placement(moving: _Side, fixed: _Side, linear: np.ndarray):
    """``(score, shift, agreement)`` of the best placement of ``moving`` under ``linear`` (coarse
    ``fixed`` pixels per ``moving`` pixel) on ``fixed``, over every placement with any overlap; None
    when the template is too small, or too large to lay on ``fixed`` (:data:`MAX_EXTENT`).

    ``score`` is the normalised cross-correlation of the two signed images (free +1, wall band -1)
    over the template's window: the placements of every scale and turn are ranked by it.
    Normalised by both sides' energy, it favours neither a small template (which fits in any free
    space: the share of the template that agrees, the earlier score, took the smallest scale it was
    allowed) nor a large one (a raw count grows with the template). ``agreement`` is that share
    at the placement found: the fraction of the template's free space and wall band that lands on
    the fixed map's free space and walls.
    """
    import cv2

    # The guard behind _check_scale's refusal, for the estimated scales too: a side of at most
    # MAX_EXTENT times the fixed map's, turned (sqrt 2 < 1.5), rounded and banded.
    box = _template_box(moving.corners, linear, 1.5 * MAX_EXTENT * (max(fixed.free.shape) + 1) + 2 * _BAND + 4)
    if box is None:
        return None
    template, band, offset = _template(moving.source, *box, linear)
    rows, cols = template.shape
    mass = float(template.sum() + band.sum())
    if rows < 3 or cols < 3 or mass == 0:
        return None
    # Every placement with any overlap: the fixed map padded by the template's size.
    padded = cv2.copyMakeBorder(fixed.signed, rows, rows, cols, cols, cv2.BORDER_CONSTANT, value=0)
    score = cv2.matchTemplate(padded, template - band, cv2.TM_CCORR_NORMED)
    # A window with nothing known under it has no correlation (0 / 0).
    score[~np.isfinite(score)] = -1.0
    row, col = np.unravel_index(int(np.argmax(score)), score.shape)
    top, left = row - rows, col - cols
    agreement = _agreement_at(fixed, template, band, top, left) / mass
    return float(score[row, col]), offset + np.array([top, left], float), agreement


def _agreement_at(fixed: _Side, template: np.ndarray, band: np.ndarray, top: int, left: int) -> float:
    """The template's free space on ``fixed``'s free space plus its wall band on ``fixed``'s walls,
    with the template's origin at (top, left) of ``fixed`` (outside the map counts as neither)."""
    rows, cols = template.shape
    r0, c0 = max(top, 0), max(left, 0)
    r1, c1 = min(top + rows, fixed.free.shape[0]), min(left + cols, fixed.free.shape[1])
    if r0 >= r1 or c0 >= c1:
        return 0.0
    inner = (slice(r0 - top, r1 - top), slice(c0 - left, c1 - left))
    return float((fixed.free[r0:r1, c0:c1] * template[inner]).sum() + (fixed.walls[r0:r1, c0:c1] * band[inner]).sum())


def _check_scale(corners: np.ndarray | None, metric_shape: tuple[int, ...], scale: float) -> None:
    """Refuse (ParameterError, field ``scale``) a known ``scale`` that lays the input's free space, box
    ``corners``, at the largest spread searched, over more than :data:`MAX_EXTENT` times the long
    side of the metric map (``metric_shape``)."""
    if corners is None:
        return
    (top, left), (bottom, right) = corners[0], corners[3]
    rows, cols = int(bottom - top) + 1, int(right - left) + 1
    # Python floats: a scale near the largest float makes the length infinite (refused), silently.
    ratio = float(max(rows, cols)) * float(scale) * max(SCALE_SPREAD) / max(metric_shape[:2])
    if ratio <= MAX_EXTENT:
        return
    times = f"{ratio:.3g} times" if math.isfinite(ratio) else "immeasurably many times"
    raise ParameterError(
        f"scale {scale:g} (metric pixels per input pixel: the one given, or the input map's resolution "
        f"over the metric map's) lays the input map's free space ({cols} x {rows} px) {times} as "
        f"long as the metric map ({metric_shape[1]} x {metric_shape[0]} px) it is laid on; at most "
        f"{MAX_EXTENT:g} times can be placed: check the scale or the maps' resolutions",
        field="scale",
    )


def estimate_scale(
    sketch_free, metric_free, *, orientations: Sequence[tuple[float, bool]], scales: Sequence[float] = SCALE_SEARCH
) -> float:
    """Metric pixels per input pixel of two metric maps of unknown resolutions.

    The scale, over ``scales`` and ``orientations``, whose best placement of the input on the metric
    map has the highest normalised cross-correlation of their signed images (free space +1, the
    wall band around it -1; see :func:`fit_overlay`). On Halmstad E5 (20 pairs, the scale read off the
    annotators' clicks by a similarity fit: 0.56-1.31) it came within 15 % on 16 and within 5 % (median)
    overall.

    Examples
    --------
    >>> import cv2
    >>> free = np.zeros((90, 140), np.uint8); free[10:80, 10:60] = 1; free[40:50, 60:130] = 1
    >>> free[20:40, 100:130] = 1; free[50:80, 80:110] = 1
    >>> half = cv2.resize(free, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_NEAREST)
    >>> round(estimate_scale(half, free, orientations=[(0.0, False)]), 1)
    2.0
    """
    sketch, metric = _Side(np.asarray(sketch_free) != 0), _Side(np.asarray(metric_free) != 0)
    return _estimated_scale(sketch, metric, orientations, scales)


def _estimated_scale(sketch: _Side, metric: _Side, orientations, scales) -> float:
    best = (-math.inf, 1.0)
    for degrees, mirrored in orientations:
        turn = orientation_matrix(degrees=degrees, mirrored=mirrored)
        for scale in scales:
            placed = _best_placement(sketch, metric, turn * (scale * metric.factor))
            if placed is not None and placed[0] > best[0]:
                best = (placed[0], float(scale))
    return best[1]


def fit_overlay(
    sketch_free, metric_free, *, orientations: Sequence[tuple[float, bool]], scale: float | None = None
) -> Alignment:
    """The turn, scale and shift that lay the input map best on the metric map.

    Parameters
    ----------
    sketch_free, metric_free : ndarray, shape (rows, cols)
        Free space of the input map and of the metric map (bool, or label images).
    orientations : sequence of (degrees, mirrored), keyword-only
        The orientations to try.
    scale : float or None, keyword-only
        Metric pixels per input pixel, when known (the search tries it within 20 %). None: found
        by :func:`estimate_scale`, then searched within 20 % as a known one.

    Returns
    -------
    Alignment
        ``overlap`` is the agreement of the placement found: the fraction of the input's free space
        and wall band that lands on the metric map's free space and walls.

    Examples
    --------
    >>> free = np.zeros((60, 90), bool); free[10:50, 10:40] = True; free[25:35, 40:85] = True
    >>> part = free[:, 20:]  # the input shows the right-hand part only
    >>> fit = fit_overlay(part, free, orientations=[(0.0, False), (180.0, False)], scale=1.0)
    >>> fit.degrees, np.round(fit.matrix[:, 2]).tolist()
    (0.0, [0.0, 20.0])
    """
    orientations = list(orientations)
    ranked = ranked_overlays(sketch_free, metric_free, orientations=orientations, scale=scale)
    return ranked[0][1] if ranked else Alignment.unfitted(*orientations[0])


def ranked_overlays(
    sketch_free,
    metric_free,
    *,
    orientations: Sequence[tuple[float, bool]],
    scale: float | None = None,
    angle_step: float = 0.0,
) -> list[tuple[float, Alignment]]:
    """Each orientation's best placement (:func:`fit_overlay`'s search), with its correlation.

    Parameters
    ----------
    sketch_free, metric_free, orientations, scale
        As for :func:`fit_overlay`.
    angle_step : float, keyword-only
        When above 0, each orientation is also tried turned by one and two such steps either way
        (degrees), and keeps the turn whose placement correlates best: the candidates come from the
        maps' wall angles, which a robot map's drift bends by a few degrees (Halmstad E5_05 against
        E5_10: candidates at 174.5 and 354.5 degrees, the right placement at 350.5).

    Returns
    -------
    list of (float, Alignment)
        The normalised cross-correlation of the placement's free space and walls with the metric
        map's, and the placement; best first (ties: the earlier orientation), so the first is
        :func:`fit_overlay`'s. Empty when either map has no free space or the input is too small
        (or, at an estimated scale, too large) to place. The runner-up tells how close the call was: a corridor lined with rooms
        correlates nearly as well turned by a half turn (docs/studies.md, round 42).

    Raises
    ------
    ParameterError
        When ``scale`` lays the input over more than :data:`MAX_EXTENT` times the metric map's length.

    Examples
    --------
    >>> free = np.zeros((60, 90), bool); free[10:50, 10:40] = True; free[25:35, 40:85] = True
    >>> ranked = ranked_overlays(free, free, orientations=[(180.0, False), (0.0, False)], scale=1.0)
    >>> [(fit.degrees, round(score, 2)) for score, fit in ranked]
    [(0.0, 1.0), (180.0, 0.79)]
    """
    sketch_free = np.asarray(sketch_free) != 0
    metric_free = np.asarray(metric_free) != 0
    orientations = list(orientations)
    if not sketch_free.any() or not metric_free.any():
        return []
    # Read once, for the scale estimate and for the search.
    sketch, metric = _Side(sketch_free), _Side(metric_free)
    if scale is not None:
        _check_scale(sketch.corners, metric_free.shape, scale)
    else:
        scale = _estimated_scale(sketch, metric, orientations, SCALE_SEARCH)
    # The candidate's own turn first: a tie keeps it.
    turns = (0.0, -angle_step, angle_step, -2 * angle_step, 2 * angle_step) if angle_step > 0 else (0.0,)
    ranked = []
    for index, (degrees, mirrored) in enumerate(orientations):
        best: tuple[float, float, np.ndarray, float] | None = None
        for turned in ((degrees + turn) % 360.0 if turn else degrees for turn in turns):
            orientation = orientation_matrix(degrees=turned, mirrored=mirrored)
            for spread in SCALE_SPREAD:
                linear = orientation * (scale * spread * metric.factor)
                placed = _best_placement(sketch, metric, linear)
                if placed is not None and (best is None or placed[0] > best[0]):
                    matrix = np.hstack([linear / metric.factor, (placed[1] / metric.factor)[:, None]])
                    best = (placed[0], placed[2], matrix, turned)
        if best is not None:
            fit = Alignment(min(best[1], 1.0), best[2], float(best[3]), bool(mirrored))
            ranked.append((-best[0], index, best[0], fit))
    return [(score, fit) for _, _, score, fit in sorted(ranked, key=lambda item: item[:2])]


def overlay_pairs(sketch_labels, metric_labels, matrix: np.ndarray, *, min_iou: float = 0.15) -> list[tuple[int, int]]:
    """Region pairs of two label images laid on each other by ``matrix`` (input -> metric pixels).

    Every input region is paired with the metric region it overlaps most, and every metric region
    with the input region it overlaps most, when their intersection over union is at least
    ``min_iou``; a pair found both ways is listed once.

    Examples
    --------
    >>> labels = np.zeros((20, 30), np.int32); labels[2:18, 2:14] = 1; labels[2:18, 16:28] = 2
    >>> overlay_pairs(labels, labels, np.array([[1.0, 0, 0], [0, 1.0, 0]]))
    [(1, 1), (2, 2)]
    """
    return sorted(overlay_overlaps(sketch_labels, metric_labels, matrix, min_iou=min_iou))


def overlay_overlaps(sketch_labels, metric_labels, matrix: np.ndarray, *, min_iou: float = 0.15) -> dict:
    """:func:`overlay_pairs` with each pair's intersection over union: ``{(input region, metric
    region): iou}``.

    Examples
    --------
    >>> labels = np.zeros((20, 30), np.int32); labels[2:18, 2:14] = 1; labels[2:18, 16:28] = 2
    >>> metric = np.zeros((20, 30), np.int32); metric[2:18, 2:28] = 1
    >>> {pair: round(iou, 2) for pair, iou in overlay_overlaps(labels, metric, np.eye(2, 3)).items()}
    {(1, 1): 0.46, (2, 1): 0.46}
    """
    import cv2

    sketch_labels = np.asarray(sketch_labels)
    metric_labels = np.asarray(metric_labels)
    n_sketch, n_metric = int(sketch_labels.max()) + 1, int(metric_labels.max()) + 1
    if n_sketch < 2 or n_metric < 2:
        return {}
    opencv = np.array([[matrix[1, 1], matrix[1, 0], matrix[1, 2]], [matrix[0, 1], matrix[0, 0], matrix[0, 2]]])
    # Nearest neighbour on float32 keeps the ids exactly (they are far below 2**24).
    warped = cv2.warpAffine(
        sketch_labels.astype(np.float32), opencv, metric_labels.shape[::-1], flags=cv2.INTER_NEAREST
    ).astype(np.int64)
    counts = np.bincount(
        warped.ravel() * n_metric + metric_labels.ravel().astype(np.int64), minlength=n_sketch * n_metric
    )
    counts = counts.reshape(n_sketch, n_metric).astype(np.float64)
    sketch_area = counts.sum(axis=1)[1:]
    metric_area = np.bincount(metric_labels.ravel(), minlength=n_metric).astype(np.float64)[1:]
    inter = counts[1:, 1:]
    iou = inter / np.maximum(sketch_area[:, None] + metric_area[None, :] - inter, 1.0)
    overlaps = {}
    for i in np.flatnonzero(sketch_area > 0):
        j = int(np.argmax(iou[i]))
        if iou[i, j] >= min_iou:
            overlaps[int(i) + 1, j + 1] = float(iou[i, j])
    for j in np.flatnonzero(metric_area > 0):
        i = int(np.argmax(iou[:, j]))
        if iou[i, j] >= min_iou:
            overlaps[i + 1, int(j) + 1] = float(iou[i, j])
    return overlaps


def _similarity(source: np.ndarray, target: np.ndarray, *, mirrored: bool) -> np.ndarray | None:
    """The least-squares similarity (row, col) -> (row, col) with or without a reflection (Umeyama)."""
    source_mean, target_mean = source.mean(axis=0), target.mean(axis=0)
    centred_source, centred_target = source - source_mean, target - target_mean
    spread = float((centred_source**2).sum())
    if spread <= 0:
        return None
    u, values, vt = np.linalg.svd(centred_target.T @ centred_source)
    sign = np.sign(np.linalg.det(u) * np.linalg.det(vt)) or 1.0
    fix = np.diag([1.0, sign * (-1.0 if mirrored else 1.0)])
    rotation = u @ fix @ vt
    scale = float(np.trace(np.diag(values) @ fix)) / spread
    if scale <= 0:
        return None
    linear = scale * rotation
    return np.hstack([linear, (target_mean - linear @ source_mean)[:, None]])


def _agreement(sketch_free: np.ndarray, metric_free: np.ndarray, matrix: np.ndarray) -> float:
    """Intersection over union of the input's free space laid by ``matrix`` and the metric map's."""
    import cv2

    opencv = np.array([[matrix[1, 1], matrix[1, 0], matrix[1, 2]], [matrix[0, 1], matrix[0, 0], matrix[0, 2]]])
    laid = cv2.warpAffine(sketch_free.astype(np.uint8), opencv, metric_free.shape[::-1], flags=cv2.INTER_NEAREST) != 0
    union = int(np.count_nonzero(laid | metric_free))
    return int(np.count_nonzero(laid & metric_free)) / union if union else 0.0


def fit_to_pairs(sketch_free, metric_free, pairs, sketch_graph, metric_graph, *, mirror_flags=(False, True)):
    """The placement that carries the pairs' sketch centroids onto their partners' (two pairs or more).

    Parameters
    ----------
    sketch_free, metric_free : ndarray, shape (rows, cols)
        Free space (or label images) of the two maps, to choose the mirror flag by.
    pairs : sequence of (sketch region, metric region)
    sketch_graph, metric_graph : networkx.Graph
        Region graphs with ``centroid`` (row, col).
    mirror_flags : sequence of bool, keyword-only
        The readings allowed; the one whose placement agrees better with the metric map is kept.

    Returns
    -------
    Alignment or None
        None with fewer than two pairs, or centroids that do not span a placement.

    Examples
    --------
    >>> import networkx as nx
    >>> free = np.zeros((60, 90), bool); free[10:50, 10:40] = True; free[25:35, 40:85] = True
    >>> g = nx.Graph(); g.add_node(1, centroid=(30.0, 25.0)); g.add_node(2, centroid=(30.0, 62.5))
    >>> turned = np.rot90(free, 2)  # the same map turned by 180 degrees
    >>> h = nx.Graph(); h.add_node(1, centroid=(29.0, 64.0)); h.add_node(2, centroid=(29.0, 26.5))
    >>> fit = fit_to_pairs(free, turned, [(1, 1), (2, 2)], g, h)
    >>> round(fit.degrees), fit.mirrored, round(fit.overlap, 2)
    (180, False, 1.0)
    """
    pairs = list(pairs)
    if len(pairs) < 2:
        return None
    sketch_free, metric_free = np.asarray(sketch_free) != 0, np.asarray(metric_free) != 0
    source = np.array([sketch_graph.nodes[a]["centroid"] for a, _ in pairs], float)
    target = np.array([metric_graph.nodes[b]["centroid"] for _, b in pairs], float)
    best = None
    for mirrored in dict.fromkeys(bool(flag) for flag in mirror_flags):
        matrix = _similarity(source, target, mirrored=mirrored)
        if matrix is None:
            continue
        agreement = _agreement(sketch_free, metric_free, matrix)
        if best is None or agreement > best.overlap:
            degrees = math.degrees(math.atan2(matrix[1, 0], matrix[0, 0])) % 360.0
            best = Alignment(agreement, matrix, degrees, mirrored)
    return best


def constrained_pairs(pairs, constraints) -> list[tuple[int, int]]:
    """``pairs`` under ``constraints`` (region ids): the fixed pairs in, nothing else for their regions
    or the excluded ones, no forbidden pair (:func:`~ursim_core.matching.constraints.allowed_pairs`).

    Examples
    --------
    >>> from ursim_core.matching.constraints import MatchConstraints
    >>> constrained_pairs([(1, 1), (2, 2), (3, 3)], MatchConstraints(fixed=[(1, 2)], forbidden=[(3, 3)]))
    [(1, 2)]
    """
    if not constraints:
        return list(pairs)
    return sorted({*allowed_pairs(pairs, constraints), *constraints.fixed})
