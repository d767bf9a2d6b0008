"""The sketch laid on the metric map elastically, and its regions paired where they overlap.

People draw rooms out of proportion: a hall twice as long as it is, a corridor bent, one wing
squeezed. A similarity or a scale per axis cannot lay such a sketch on the metric map (round 28,
docs/studies.md), so the overlay pairs of a rigid placement were worse than the planar matcher's.
Once the planar matcher has read the sketch's orientation, :func:`elastic_pairs`:

1. turns the sketch's label image into that orientation (:func:`oriented_labels`);
2. lays it on the metric map by the bounding boxes of both maps' regions (a scale and a shift
   per axis);
3. bends it by a dense optical flow between the two maps' signed distance images
   (:func:`elastic_flow`: OpenCV's DIS, Kroeger et al., ECCV 2016), which moves each wall of the
   sketch towards the nearest wall of the metric map it resembles;
4. pairs every region with the region it overlaps most on the other side, both ways, when their
   intersection over union is at least ``min_iou``
   (:func:`~ursim_core.matching.overlay.overlay_pairs`, as the overlay matcher does for robot
   maps).

The work happens at a fixed working size (the metric map's longer side at :data:`WORKING_SIDE`
pixels, the sketch laid at that size), so the flow's patch sizes and the distance clip mean the
same on maps of any resolution.
"""

from __future__ import annotations

import weakref

import numpy as np

__all__ = [
    "WORKING_SIDE",
    "DISTANCE_CLIP",
    "oriented_labels",
    "signed_distance",
    "elastic_flow",
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
    # Nearest neighbour on float32 keeps the ids exactly (they are far below 2**24).
    turned = cv2.warpAffine(labels.astype(np.float32), matrix, (new_cols, new_rows), flags=cv2.INTER_NEAREST)
    return turned.astype(labels.dtype)


def signed_distance(free: np.ndarray, *, clip: float = DISTANCE_CLIP) -> np.ndarray:
    """Distance to the nearest wall, positive inside the free space and negative outside, clipped.

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

    key = (id(metric_labels), metric_labels.shape, clip)
    held = _METRIC_MEMO.get("last")
    if held is not None and held[0] == key and held[1]() is metric_labels:
        return held[2], held[3]
    factor = WORKING_SIDE / max(metric_labels.shape)
    shape = (max(1, round(metric_labels.shape[0] * factor)), max(1, round(metric_labels.shape[1] * factor)))
    metric = cv2.resize(metric_labels.astype(np.float32), shape[::-1], interpolation=cv2.INTER_NEAREST)
    metric = metric.astype(np.int64)
    image = _flow_image(metric > 0, clip)
    try:
        _METRIC_MEMO["last"] = (key, weakref.ref(metric_labels), metric, image)
    except TypeError:  # an array-like without weak references: not kept
        pass
    return metric, image


def _box(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if not len(rows):
        return None
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def elastic_pairs(
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    *,
    degrees: float = 0.0,
    mirrored: bool = False,
    min_iou: float = 0.15,
    clip: float = DISTANCE_CLIP,
) -> list[tuple[int, int]]:
    """Region pairs of a sketch laid on a metric map by its boxes, then bent by :func:`elastic_flow`.

    Parameters
    ----------
    sketch_labels, metric_labels : ndarray of int, shape (rows, cols)
        0 = no region.
    degrees, mirrored : keyword-only
        The sketch's orientation (:func:`oriented_labels`), as the planar matcher read it.
    min_iou : float, keyword-only
        Regions are paired when their intersection over union is at least this.
    clip : float, keyword-only
        :data:`DISTANCE_CLIP`.

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
    from ursim_core.matching.overlay import overlay_pairs

    laid = _bent(sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, clip=clip)
    if laid is None:
        return []
    bent, metric = laid
    return overlay_pairs(bent, metric, np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), min_iou=min_iou)


def laid_sketch(
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    *,
    degrees: float = 0.0,
    mirrored: bool = False,
    clip: float = DISTANCE_CLIP,
) -> np.ndarray:
    """The sketch's regions where :func:`elastic_pairs` lays them, on the metric map's pixels.

    For a person to see why regions were paired: the bent sketch drawn over the metric map.

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
    laid = _bent(sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, clip=clip)
    if laid is None:
        return np.zeros(metric_labels.shape, np.int32)
    bent = cv2.resize(laid[0].astype(np.float32), metric_labels.shape[::-1], interpolation=cv2.INTER_NEAREST)
    return bent.astype(np.int32)


def _bent(sketch_labels, metric_labels, *, degrees: float, mirrored: bool, clip: float):
    """``(bent sketch, metric map)`` label images at the working size, or None when either map
    has no region."""
    import cv2

    metric_labels = np.asarray(metric_labels)
    sketch = oriented_labels(np.asarray(sketch_labels), degrees=degrees, mirrored=mirrored)
    sketch_box, metric_box = _box(sketch > 0), _box(metric_labels > 0)
    if sketch_box is None or metric_box is None:
        return None
    metric, metric_image = _metric_at_working_size(metric_labels, clip)
    shape = metric.shape
    factor = WORKING_SIDE / max(metric_labels.shape)
    r0, r1, c0, c1 = sketch_box
    m0, m1, n0, n1 = (value * factor for value in metric_box)
    # Box onto box, then the flow: the laid sketch at the working size, read through the flow.
    row_scale, col_scale = (m1 - m0) / (r1 - r0), (n1 - n0) / (c1 - c0)
    laying = np.array([[col_scale, 0.0, n0 - col_scale * c0], [0.0, row_scale, m0 - row_scale * r0]])
    laid = cv2.warpAffine(sketch.astype(np.float32), laying, shape[::-1], flags=cv2.INTER_NEAREST)
    flow = _dis_flow(metric_image, _flow_image(laid > 0, clip))
    rows, cols = np.indices(shape, dtype=np.float32)
    bent = cv2.remap(laid, cols + flow[..., 0], rows + flow[..., 1], cv2.INTER_NEAREST)
    return bent.astype(np.int64), metric
