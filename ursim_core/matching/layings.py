"""Where a sketch is laid on the metric map before it is bent: box onto box, in a window, by an answer.

:mod:`ursim_core.matching.elastic` bends the sketch onto the metric map by an optical flow, which
corrects a sketch's local distortions but not a stretch of a third. So the sketch is laid first,
by a scale and a shift per axis (a :class:`Laying`):

- box onto box (:func:`box_laying`): the box around the sketch's regions onto the metric map's,
  right for a sketch of the whole building;
- in the window of the metric map the sketch resembles (:func:`window_laying`, the template search
  of :mod:`ursim_core.matching.template`), for a sketch of part of a building;
- by an answer's pairs (:func:`answer_laying`): the scale and shift that carry the paired sketch
  regions' centroids onto their partners'.

Everything here is on label images in (row, col); the sketch is first turned into the orientation
it is read in (:func:`oriented_labels`). The functions that take an already oriented sketch
(:func:`boxes_laying`, :func:`pairs_laying`, :func:`window_laying`) are what the elastic laying
calls for each reading.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ursim_core.matching import template

__all__ = [
    "Laying",
    "oriented_labels",
    "region_centroids",
    "box_laying",
    "boxes_laying",
    "answer_laying",
    "pairs_laying",
    "window_laying",
]


class Laying(NamedTuple):
    """A scale and a shift per axis that carry the oriented sketch's pixels onto the metric map's:
    ``row' = row_scale * row + row_shift``, ``col' = col_scale * col + col_shift``. ``by`` says
    what it was fitted to: ``"boxes"`` (box onto box) or ``"answer"`` (the answer's pairs)."""

    by: str
    row_scale: float
    row_shift: float
    col_scale: float
    col_shift: float

    def scaled(self, factor: float) -> Laying:
        """The same laying onto the metric map resized by ``factor``."""
        return self._replace(
            row_scale=self.row_scale * factor,
            row_shift=self.row_shift * factor,
            col_scale=self.col_scale * factor,
            col_shift=self.col_shift * factor,
        )

    def matrix(self) -> np.ndarray:
        """OpenCV's 2 x 3 affine matrix of the laying, in (x, y) = (col, row)."""
        return np.array([[self.col_scale, 0.0, self.col_shift], [0.0, self.row_scale, self.row_shift]])


def oriented_labels(labels: np.ndarray, *, degrees: float, mirrored: bool) -> np.ndarray:
    """A label image mirrored left-right (when asked) then turned counter-clockwise by ``degrees``.

    The same transformation as :func:`~ursim_core.matching.orientation.transform_points`, up to a
    shift: quarter turns exactly (``np.rot90``), other angles by nearest-neighbour resampling onto
    a canvas that holds the whole turned image.

    Examples
    --------
    >>> labels = np.array([[1, 2]], np.int32)
    >>> oriented_labels(labels, degrees=90, mirrored=False).tolist()
    [[2], [1]]
    >>> oriented_labels(labels, degrees=0, mirrored=True).tolist()
    [[2, 1]]

    A boolean image (a free-space mask) is turned as one: the mask of the turned labels.

    >>> labels = np.arange(12, dtype=np.int32).reshape(3, 4) % 3
    >>> (oriented_labels(labels > 0, degrees=30, mirrored=True) == (oriented_labels(labels, degrees=30, mirrored=True) > 0)).all()
    np.True_
    """
    import cv2

    labels = np.asarray(labels)
    if mirrored:
        labels = labels[:, ::-1]
    quarter = degrees / 90.0
    if abs(quarter - round(quarter)) < 1e-9:
        return np.ascontiguousarray(np.rot90(labels, int(round(quarter)) % 4))
    from ursim_core.segmentation.canonical import turn_on_canvas

    matrix, (new_rows, new_cols) = turn_on_canvas(labels.shape, degrees)
    # Nearest neighbour keeps the values exactly: ids on float32 (they are far below 2**24), a free
    # space mask on one byte a pixel (OpenCV takes the same source pixels whatever their type;
    # a KTH sketch of 924 x 1870 px turned by 30 degrees: 2.7 against 5.7 ms).
    if labels.dtype == bool:
        source = np.ascontiguousarray(labels).view(np.uint8)
        return cv2.warpAffine(source, matrix, (new_cols, new_rows), flags=cv2.INTER_NEAREST).view(bool)
    turned = cv2.warpAffine(labels.astype(np.float32), matrix, (new_cols, new_rows), flags=cv2.INTER_NEAREST)
    return turned.astype(labels.dtype)


def region_centroids(labels: np.ndarray) -> dict:
    """``{region: (row, col)}``: the mean pixel of every region of a label image (0 = none).

    Examples
    --------
    >>> {region: tuple(map(float, centroid)) for region, centroid in region_centroids(np.array([[0, 1, 1], [2, 2, 2]])).items()}
    {1: (0.0, 1.5), 2: (1.0, 1.0)}
    """
    labels = np.asarray(labels)
    flat = labels.ravel()
    # Over the region pixels only, their rows and columns from their flat indices: the sums are
    # of integers, exact in float64 in any order, so the same centroids as summing every pixel's
    # row and column (a KTH sketch of 924 x 1870 px turned by 30 degrees: 6 against 56 ms).
    where = np.flatnonzero(flat > 0)
    if not where.size:
        return {}
    ids = flat[where].astype(np.intp, copy=False)
    rows, cols = np.divmod(where, labels.shape[1])
    count = np.bincount(ids)
    row_sum = np.bincount(ids, weights=rows)
    col_sum = np.bincount(ids, weights=cols)
    present = np.flatnonzero(count)
    return {int(r): (row_sum[r] / count[r], col_sum[r] / count[r]) for r in present if r > 0}


def box_laying(sketch_labels: np.ndarray, metric_labels: np.ndarray, *, degrees: float = 0.0, mirrored: bool = False):
    """The :class:`Laying` that carries the box around the oriented sketch's regions onto the box
    around the metric map's; None when either map has no region.

    Examples
    --------
    >>> metric = np.zeros((60, 100), np.int32); metric[10:50, 20:80] = 1
    >>> sketch = np.zeros((30, 40), np.int32); sketch[5:25, 10:40] = 1
    >>> box_laying(sketch, metric)
    Laying(by='boxes', row_scale=2.0, row_shift=0.0, col_scale=2.0, col_shift=0.0)
    """
    return boxes_laying(oriented_labels(np.asarray(sketch_labels), degrees=degrees, mirrored=mirrored), metric_labels)


def boxes_laying(sketch: np.ndarray, metric_labels: np.ndarray) -> Laying | None:
    """:func:`box_laying` of a sketch already in its orientation."""
    sketch_box, metric_box = template.free_box(sketch > 0), template.free_box(np.asarray(metric_labels) > 0)
    if sketch_box is None or metric_box is None:
        return None
    (r0, r1, c0, c1), (m0, m1, n0, n1) = sketch_box, metric_box
    row_scale, col_scale = (m1 - m0) / (r1 - r0), (n1 - n0) / (c1 - c0)
    return Laying("boxes", row_scale, m0 - row_scale * r0, col_scale, n0 - col_scale * c0)


def answer_laying(
    sketch_labels: np.ndarray, metric_labels: np.ndarray, pairs, *, degrees: float = 0.0, mirrored: bool = False
):
    """The :class:`Laying` fitted to an answer: per axis, the least-squares scale and shift that
    carry the centroids of the oriented sketch's paired regions onto their partners' centroids.

    No assumption that the sketch covers the metric map's extent, as laying box onto box makes.
    Paired regions in one row (or column) take the other axis' scale across it. None when fewer
    than three pairs have both regions in the label images, when the paired sketch regions spread
    along neither axis, or when a fitted scale is not positive (an answer that lays the sketch
    mirrored or folded is not a laying of it in this orientation).

    Examples
    --------
    >>> metric = np.zeros((60, 100), np.int32)
    >>> metric[10:20, 10:20], metric[10:20, 30:40], metric[30:40, 10:20] = 1, 2, 3
    >>> sketch = metric[5:45, 5:45] * 1
    >>> laying = answer_laying(sketch, metric, [(1, 1), (2, 2), (3, 3)])
    >>> laying.by, [round(value, 6) for value in laying[1:]]
    ('answer', [1.0, 5.0, 1.0, 5.0])
    >>> answer_laying(sketch, metric, [(1, 1), (2, 2)]) is None
    True
    """
    sketch = oriented_labels(np.asarray(sketch_labels), degrees=degrees, mirrored=mirrored)
    metric_labels = np.asarray(metric_labels)
    return pairs_laying(sketch, region_centroids(metric_labels), pairs)


def pairs_laying(sketch: np.ndarray, metric_centroids: dict, pairs) -> Laying | None:
    """:func:`answer_laying` of a sketch already in its orientation, given the metric map's
    :func:`region_centroids` (computed once for many sketches)."""
    sketch_centroids = region_centroids(sketch)
    matched = [
        (sketch_centroids[a], metric_centroids[b]) for a, b in pairs if a in sketch_centroids and b in metric_centroids
    ]
    if len(matched) < 3:
        return None
    source, target = (np.array([points[side] for points in matched], dtype=np.float64) for side in (0, 1))
    spread = [np.ptp(source[:, axis]) >= 1.0 for axis in (0, 1)]
    if not any(spread):
        return None
    fitted = {}
    for axis in (0, 1):
        if spread[axis]:
            design = np.stack([source[:, axis], np.ones(len(source))], axis=1)
            (scale, shift), *_ = np.linalg.lstsq(design, target[:, axis], rcond=None)
            if not (np.isfinite(scale) and np.isfinite(shift) and scale > 0):
                return None
            fitted[axis] = (float(scale), float(shift))
    for axis in (0, 1):
        if not spread[axis]:
            # Regions in one row (or column) fix no scale across it: the other axis' scale, and
            # the shift that carries their mean onto their partners'.
            scale = fitted[1 - axis][0]
            fitted[axis] = (scale, float(target[:, axis].mean() - scale * source[:, axis].mean()))
    fitted = [*fitted[0], *fitted[1]]
    return Laying("answer", *fitted)


def window_laying(sketch: np.ndarray, metric_labels: np.ndarray, *, gain: float | None = None) -> Laying | None:
    """The :class:`Laying` that carries the box around the oriented sketch's regions onto the
    window of the metric map where it correlates best (:func:`~ursim_core.matching.template.best_window`),
    when that window correlates better than the map's whole box by at least ``gain``
    (:data:`~ursim_core.matching.template.WINDOW_GAIN` when None) and at least
    :data:`~ursim_core.matching.template.WINDOW_MIN_CORRELATION` in all; else None.

    Examples
    --------
    >>> plan = np.zeros((300, 600), np.int32)
    >>> plan[20:130, 20:150], plan[20:130, 160:400], plan[20:130, 410:580] = 1, 2, 3
    >>> plan[140:170, 20:580], plan[180:280, 20:260], plan[180:280, 270:580] = 4, 5, 6
    >>> laying = window_laying(plan[:, :320], plan)
    >>> laying.by, 0.9 < laying.col_scale < 1.1
    ('window', True)
    >>> window_laying(plan, plan) is None
    True
    """
    sketch_free, metric_free = np.asarray(sketch) > 0, np.asarray(metric_labels) > 0
    window = template.best_window(sketch_free, metric_free)
    if window is None or window.gain < (template.WINDOW_GAIN if gain is None else gain):
        return None
    if window.correlation < template.WINDOW_MIN_CORRELATION:
        return None
    r0, r1, c0, c1 = template.free_box(sketch_free)
    row_scale, col_scale = window.height / (r1 - r0), window.width / (c1 - c0)
    return Laying("window", row_scale, window.top - row_scale * r0, col_scale, window.left - col_scale * c0)
