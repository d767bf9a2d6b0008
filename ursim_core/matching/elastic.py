"""The sketch laid on the metric map elastically, and its regions paired where they overlap.

People draw rooms out of proportion: a hall twice as long as it is, a corridor bent, one wing
squeezed. A similarity or a scale per axis cannot lay such a sketch on the metric map (round 28,
docs/studies.md), so the overlay pairs of a rigid placement were worse than the planar matcher's.
Once the planar matcher has read the sketch's orientation, :func:`elastic_pairs`:

1. turns the sketch's label image into that orientation (:func:`oriented_labels`);
2. lays it on the metric map by a scale and a shift per axis (:mod:`ursim_core.matching.layings`):
   box onto box, or in the window of the map it clearly resembles (a partial sketch laid box onto
   box is stretched over the whole map), and, given the planar answer's pairs, also fitted to
   their regions' centroids;
3. bends it by a dense optical flow between the two maps' signed distance images
   (:func:`elastic_flow`: OpenCV's DIS, Kroeger et al., ECCV 2016), which moves each wall of the
   sketch towards the nearest wall of the metric map it resembles;
4. keeps the laying whose bent sketch lands more on the metric map's free space (the share of its
   free space that does; the boxes on a tie), and pairs every region with the region it overlaps
   most on the other side, both ways, when their intersection over union is at least ``min_iou``
   (:func:`~ursim_core.matching.overlay.overlay_pairs`, as the overlay matcher does for robot
   maps).

The work happens at a fixed working size (the metric map's longer side at :data:`WORKING_SIDE`
pixels, the sketch laid at that size), so the flow's patch sizes and the distance clip mean the
same on maps of any resolution.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

from ursim_core.matching import template

# The layings are layings.py's; Laying, oriented_labels and the public layings stay importable
# from here, where they were until round 49.
from ursim_core.matching.layings import (
    Laying,
    answer_laying,
    box_laying,
    boxes_laying,
    oriented_labels,
    pairs_laying,
    region_centroids,
    window_laying,
)

__all__ = [
    "WORKING_SIDE",
    "DISTANCE_CLIP",
    "Laying",
    "LaidSketch",
    "oriented_labels",
    "signed_distance",
    "elastic_flow",
    "box_laying",
    "answer_laying",
    "window_laying",
    "lay_sketch",
    "elastic_pairs",
    "laid_sketch",
]

#: The metric map's longer side (pixels) while the sketch is laid: the KTH model's own size.
WORKING_SIDE = 512
#: Signed distances are clipped at this many pixels (at the working size) either side of a wall:
#: far enough for a wall to be pulled from the middle of a room, near enough that distant walls
#: do not flatten the gradient. Round 43, the 18 KTH sketches upright in the planar matcher's
#: orientation (in sample; a study script): mean F1 0.74 / 0.80 / 0.82 at 10 / 30 / 60 px.
DISTANCE_CLIP = 60.0
#: With ``window_competes``, any window that correlates better than the whole box (by more than
#: rounding) is bent too: which of the two lands more decides, not a margin of correlation.
_ANY_GAIN = 1e-6


class LaidSketch(NamedTuple):
    """What :func:`lay_sketch` found: the laying used, the share of the bent sketch's free space
    that landed on the metric map's free space (at the working size), and the region pairs with
    their intersections over union (:func:`~ursim_core.matching.overlay.overlay_overlaps`)."""

    laying: Laying
    landed: float
    overlaps: dict

    @property
    def pairs(self) -> list:
        """The region pairs, sorted."""
        return sorted(self.overlaps)


def signed_distance(free: np.ndarray, *, clip: float = DISTANCE_CLIP) -> np.ndarray:
    """Distance to the nearest wall, positive inside the free space and negative outside, clipped
    (:func:`ursim_core.matching.template.signed_distance`, clipped at :data:`DISTANCE_CLIP` unless told)."""
    return template.signed_distance(free, clip=clip)


def elastic_flow(fixed_free: np.ndarray, moving_free: np.ndarray, *, clip: float = DISTANCE_CLIP) -> np.ndarray:
    """The flow that carries ``moving_free`` onto ``fixed_free`` (same shape): DIS optical flow
    (OpenCV's medium preset) between their signed distance images.

    Returns
    -------
    ndarray of float32, shape (rows, cols, 2)
        Per pixel of the fixed image, the (dx, dy) = (col, row) offset at which to read the
        moving image.

    Examples
    --------
    >>> fixed = np.zeros((64, 64), bool); fixed[16:48, 16:48] = True
    >>> moving = np.roll(fixed, 3, axis=1)
    >>> flow = elastic_flow(fixed, moving, clip=8)
    >>> round(float(np.median(flow[20:44, 20:44, 0])))
    3
    """
    return _dis_flow(_flow_image(fixed_free, clip), _flow_image(moving_free, clip))


def _dis_flow(fixed_image: np.ndarray, moving_image: np.ndarray) -> np.ndarray:
    """OpenCV's DIS flow, medium preset (the one setting cross-validated, round 43), of two 8-bit images."""
    import cv2

    return cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM).calc(fixed_image, moving_image, None)


def _flow_image(free: np.ndarray, clip: float) -> np.ndarray:
    """The signed distance image as the flow reads it: 8 bits, the wall at 127."""
    return np.round((signed_distance(free, clip=clip) + clip) * (127.0 / clip)).astype(np.uint8)


#: The metric map at the working size and its flow image, for the last label image seen: an
#: evaluation or a campaign matches many sketches against one map (a weak reference, so a new
#: array at a freed address is never mistaken for it). Label images are not changed in place: the
#: app's edits and every segmenter make new arrays.
_METRIC_MEMO: dict = {}


def _metric_at_working_size(metric_labels: np.ndarray, clip: float) -> tuple[np.ndarray, np.ndarray]:
    import cv2

    def make() -> tuple[np.ndarray, np.ndarray]:
        factor = WORKING_SIDE / max(metric_labels.shape)
        shape = (max(1, round(metric_labels.shape[0] * factor)), max(1, round(metric_labels.shape[1] * factor)))
        metric = cv2.resize(metric_labels.astype(np.float32), shape[::-1], interpolation=cv2.INTER_NEAREST)
        metric = metric.astype(np.int64)
        return metric, _flow_image(metric > 0, clip)

    return _memoised("working", metric_labels, clip, make)


def _memoised(name: str, metric_labels: np.ndarray, extra, make):
    """``make()`` of the metric map, kept in :data:`_METRIC_MEMO` under ``name`` for the last map seen."""
    key = (id(metric_labels), metric_labels.shape, extra)
    held = _METRIC_MEMO.get(name)
    if held is not None and held[0] == key and held[1]() is metric_labels:
        return held[2]
    value = make()
    try:
        _METRIC_MEMO[name] = (key, weakref.ref(metric_labels), value)
    except TypeError:  # an array-like without weak references: not kept
        pass
    return value


def _metric_centroids(metric_labels: np.ndarray) -> dict:
    """:func:`~ursim_core.matching.layings.region_centroids` of the metric map, kept for the last
    map seen (many sketches, one map)."""
    return _memoised("centroids", metric_labels, None, lambda: region_centroids(metric_labels))


def lay_sketch(
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    *,
    degrees: float = 0.0,
    mirrored: bool = False,
    answer=None,
    laying: Laying | None = None,
    window: bool = False,
    window_competes: bool = False,
    min_iou: float = 0.15,
    clip: float = DISTANCE_CLIP,
) -> LaidSketch | None:
    """The sketch laid on the metric map, bent by :func:`elastic_flow`, and its regions paired.

    Parameters
    ----------
    sketch_labels, metric_labels : ndarray of int, shape (rows, cols)
        0 = no region.
    degrees, mirrored : keyword-only
        The sketch's orientation (:func:`oriented_labels`), as the planar matcher read it.
    answer : list of (sketch region, metric region), keyword-only
        An answer's pairs: the sketch is also laid by :func:`answer_laying`, and the laying whose
        bent sketch lands more on the metric map's free space is kept (the boxes on a tie). Not
        the intersection over union: a partial sketch stretched box onto box over the whole map
        covers more of it, but less of it lands on free space.
    laying : Laying, keyword-only
        Lay the sketch so and no other way (``answer`` and ``window`` are then not read).
    window : bool, keyword-only
        Lay the sketch in the window of the metric map where it correlates clearly better than
        over the map's whole box (:func:`window_laying`), instead of box onto box: a sketch of
        part of a building.
    window_competes : bool, keyword-only
        With ``window``: bend the sketch laid in the window, whenever one correlates better than the
        whole box, and laid box onto box, and keep the one that lands more on the metric map's free
        space, instead of the window only when it correlates clearly better.
    min_iou : float, keyword-only
        Regions are paired when their intersection over union is at least this.
    clip : float, keyword-only
        :data:`DISTANCE_CLIP`.

    Returns
    -------
    LaidSketch or None
        None when either map has no region.

    Examples
    --------
    >>> metric = np.zeros((60, 100), np.int32); metric[5:55, 5:45] = 1; metric[5:55, 50:95] = 2
    >>> sketch = np.zeros((40, 40), np.int32); sketch[2:38, 2:14] = 1; sketch[2:38, 16:38] = 2
    >>> laid = lay_sketch(sketch, metric)
    >>> laid.pairs, laid.laying.by, round(laid.landed, 2)
    ([(1, 1), (2, 2)], 'boxes', 1.0)
    """
    from ursim_core.matching.overlay import overlay_overlaps

    found = _laid(
        sketch_labels,
        metric_labels,
        degrees=degrees,
        mirrored=mirrored,
        clip=clip,
        answer=answer,
        laying=laying,
        window=window,
        window_competes=window_competes,
    )
    if found is None:
        return None
    bent, metric, chosen, landed = found
    overlaps = overlay_overlaps(bent, metric, np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), min_iou=min_iou)
    return LaidSketch(chosen, landed, overlaps)


def elastic_pairs(
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    *,
    degrees: float = 0.0,
    mirrored: bool = False,
    answer=None,
    min_iou: float = 0.15,
    clip: float = DISTANCE_CLIP,
) -> list[tuple[int, int]]:
    """Region pairs of a sketch laid on a metric map and bent by :func:`elastic_flow`
    (:func:`lay_sketch`'s pairs; [] when either map has no region).

    Returns
    -------
    list of (sketch region, metric region)
        Sorted; one region may be paired on both sides (a sketch that draws two rooms as one).

    Examples
    --------
    >>> metric = np.zeros((60, 100), np.int32); metric[5:55, 5:45] = 1; metric[5:55, 50:95] = 2
    >>> sketch = np.zeros((40, 40), np.int32); sketch[2:38, 2:14] = 1; sketch[2:38, 16:38] = 2
    >>> elastic_pairs(sketch, metric)
    [(1, 1), (2, 2)]
    """
    laid = lay_sketch(
        sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, answer=answer, min_iou=min_iou, clip=clip
    )
    return [] if laid is None else laid.pairs


def laid_sketch(
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    *,
    degrees: float = 0.0,
    mirrored: bool = False,
    laying: Laying | None = None,
    clip: float = DISTANCE_CLIP,
) -> np.ndarray:
    """The sketch's regions where :func:`lay_sketch` lays them, on the metric map's pixels.

    For a person to see why regions were paired: the bent sketch drawn over the metric map.
    ``laying``: the one a match used (``MatchResult.laying``); box onto box when None.

    Returns
    -------
    ndarray of int32, shape of ``metric_labels``
        Sketch region ids, 0 where no sketch region lands (resampled from the working size).

    Examples
    --------
    >>> metric = np.zeros((60, 100), np.int32); metric[5:55, 5:45] = 1; metric[5:55, 50:95] = 2
    >>> sketch = np.zeros((40, 40), np.int32); sketch[2:38, 2:14] = 1; sketch[2:38, 16:38] = 2
    >>> laid = laid_sketch(sketch, metric)
    >>> laid.shape, int(laid[30, 20]), int(laid[30, 80])
    ((60, 100), 1, 2)
    """
    import cv2

    metric_labels = np.asarray(metric_labels)
    found = _laid(sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, clip=clip, laying=laying)
    if found is None:
        return np.zeros(metric_labels.shape, np.int32)
    bent = cv2.resize(found[0].astype(np.float32), metric_labels.shape[::-1], interpolation=cv2.INTER_NEAREST)
    return bent.astype(np.int32)


def _laid(
    sketch_labels,
    metric_labels,
    *,
    degrees: float,
    mirrored: bool,
    clip: float,
    answer=None,
    laying=None,
    window: bool = False,
    window_competes: bool = False,
):
    """``(bent sketch, metric map, laying, landed)``, the images at the working size, of the
    laying given, or else of the best of box onto box (or the window, with ``window``, when it
    is clearly better; with ``window_competes`` too, any window better than the whole box) and the
    answer's; None when either map has no region."""
    metric_labels = np.asarray(metric_labels)
    sketch = oriented_labels(np.asarray(sketch_labels), degrees=degrees, mirrored=mirrored)
    boxes = boxes_laying(sketch, metric_labels)  # None when either map has no region
    if boxes is None:
        return None
    layings = [boxes if laying is None else laying]
    if laying is None and window:
        found = window_laying(sketch, metric_labels, gain=_ANY_GAIN if window_competes else None)
        if found is not None:
            layings = [boxes, found] if window_competes else [found]
    if laying is None and answer:
        fitted = pairs_laying(sketch, _metric_centroids(metric_labels), answer)
        if fitted is not None:
            layings.append(fitted)
    metric, metric_image = _metric_at_working_size(metric_labels, clip)
    factor = WORKING_SIDE / max(metric_labels.shape)
    best = None
    for tried in layings:
        bent, landed = _bent(sketch, metric, metric_image, tried.scaled(factor), clip)
        if best is None or landed > best[3]:
            best = (bent, metric, tried, landed)
    return best


def _bent(sketch: np.ndarray, metric: np.ndarray, metric_image: np.ndarray, laying: Laying, clip: float):
    """The oriented sketch laid at the working size and read through the flow onto the metric
    map, and the share of its free space that lands on the metric map's free space."""
    import cv2

    shape = metric.shape
    laid = cv2.warpAffine(sketch.astype(np.float32), laying.matrix(), shape[::-1], flags=cv2.INTER_NEAREST)
    flow = _dis_flow(metric_image, _flow_image(laid > 0, clip))
    rows, cols = np.indices(shape, dtype=np.float32)
    bent = cv2.remap(laid, cols + flow[..., 0], rows + flow[..., 1], cv2.INTER_NEAREST).astype(np.int64)
    sketch_free = bent > 0
    laid_area = np.count_nonzero(sketch_free)
    return bent, float(np.count_nonzero(sketch_free & (metric > 0)) / laid_area) if laid_area else 0.0
