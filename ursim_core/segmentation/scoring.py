"""Scoring a segmentation against a ground-truth segmentation (MAORIS evaluation).

The MAORIS segmentation data (``maoris_segmentation`` in the shared datasets)
gives ground truth as the map image with thin grey separator lines drawn across
doorways. :func:`gt_labels_from_separator_image` turns such an image into a
label image as the MAORIS evaluator (``segment_Ground_Truth``) does, and
:func:`score_segmentation` gives per-region precision and recall.

Measure (as the MAORIS evaluation): for every ground-truth region g, the
predicted region p with the largest overlap gives precision ``|g & p| / |p|``
and recall ``|g & p| / |g|`` (both 0 when no predicted region overlaps g). The
map's precision and recall are the means over ground-truth regions, and
``f1 = 2 P R / (P + R)`` of those means.

The C++ evaluator's precision is per *predicted* region instead (each
predicted region against the ground-truth region it overlaps most): with it,
the authors' own label images (``sketches/maoris_output``) score P 0.889 /
R 0.901 against ``gt_lex`` and P 0.858 / R 0.911 against ``gt_ezvin``, close
to the figures they reported (90.56 / 90.48 and 86.58 / 91.12 %). It is given
as ``evaluator_precision`` and ``evaluator_f1``; the ground-truth-side
precision (``precision``, ``f1``) penalises a predicted region that covers
several rooms once per room, and is the primary figure here.

Examples
--------
>>> import numpy as np
>>> gt = np.array([[1, 1, 2, 2]])
>>> score = score_segmentation(np.array([[1, 1, 1, 1]]), gt)
>>> score.precision, score.recall
(0.5, 1.0)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ursim_core.errors import SegmentationError
from ursim_core.io.maps import load_map, map_from_array

__all__ = [
    "SegmentationScore",
    "gt_labels_from_separator_image",
    "score_segmentation",
    "load_label_array",
    "relabel_in_raster_order",
]

_KERNEL_3x3 = np.ones((3, 3), np.uint8)


@dataclass(frozen=True)
class SegmentationScore:
    """Precision and recall of a segmentation, per ground-truth region and mean.

    Attributes
    ----------
    precision, recall : float
        Means over ground-truth regions.
    f1 : float
        ``2 P R / (P + R)`` of the means (0 when both are 0).
    evaluator_precision : float
        Mean over *predicted* regions of ``|g & p| / |p|`` with g the
        ground-truth region overlapping p most (0 for a predicted region on no
        ground truth). With ``recall`` this reproduces the figures the MAORIS
        authors published for their sketches (see the module docstring).
    evaluator_f1 : float
        ``2 P R / (P + R)`` of ``evaluator_precision`` and ``recall``.
    gt_regions : tuple of int
        Ground-truth labels, ascending.
    best_match : tuple of int
        For each ground-truth region, the predicted label overlapping it most
        (ties: the smaller label; 0 when none overlaps).
    region_precision, region_recall : tuple of float
        Per ground-truth region, in the order of ``gt_regions``.
    n_predicted : int
        Number of predicted regions.
    """

    precision: float
    recall: float
    f1: float
    evaluator_precision: float
    evaluator_f1: float
    gt_regions: tuple[int, ...]
    best_match: tuple[int, ...]
    region_precision: tuple[float, ...]
    region_recall: tuple[float, ...]
    n_predicted: int

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {
            "precision": self.precision,
            "recall": self.recall,
            "f1": self.f1,
            "evaluator_precision": self.evaluator_precision,
            "evaluator_f1": self.evaluator_f1,
            "n_gt": len(self.gt_regions),
            "n_predicted": self.n_predicted,
        }


def relabel_in_raster_order(labels: np.ndarray) -> np.ndarray:
    """Renumber the non-zero labels 1..N in the raster order of their first pixel.

    Examples
    --------
    >>> relabel_in_raster_order(np.array([[0, 7, 7, 3]])).tolist()
    [[0, 1, 1, 2]]
    """
    labels = np.asarray(labels)
    flat = labels.ravel()
    present, first = np.unique(flat, return_index=True)
    keep = present != 0
    present, first = present[keep], first[keep]
    rank = np.empty(len(present), np.int32)
    rank[np.argsort(first)] = np.arange(1, len(present) + 1, dtype=np.int32)
    out = np.zeros(flat.shape, np.int32)
    nonzero = flat != 0
    out[nonzero] = rank[np.searchsorted(present, flat[nonzero])]
    return out.reshape(labels.shape)


def gt_labels_from_separator_image(path_or_array: str | Path | np.ndarray) -> np.ndarray:
    """Ground-truth labels from a map drawn with grey separator lines.

    As the MAORIS evaluator: free = grey > 250 (transparent pixels are
    obstacle; loaded like :func:`ursim_core.io.maps.load_map`), erode 1 px (3x3),
    ``findContours(RETR_CCOMP)``, fill each top-level contour with its own label
    (holes inside a region are filled too, as ``drawContours(FILLED)`` does),
    then dilate 1 px (3x3; where two labels compete the larger wins). As in
    the C++ the dilation is not restricted to free pixels; after the erosion it
    gives back each region's extent (an opening), so separators and parts
    thinner than 3 px stay unlabelled.

    Parameters
    ----------
    path_or_array : str, Path or ndarray
        An image file, or an array accepted by
        :func:`ursim_core.io.maps.map_from_array` (bool mask, grey, RGB(A) in RGB order).

    Returns
    -------
    ndarray of int32
        Regions 1..N in the raster order of their first pixel.

    Examples
    --------
    >>> image = np.zeros((7, 11), np.uint8)
    >>> image[1:6, 1:10] = 255
    >>> image[1:6, 5] = 120            # a separator line
    >>> labels = gt_labels_from_separator_image(image)
    >>> int(labels.max()), int(labels[3, 2]), int(labels[3, 8])
    (2, 1, 2)
    """
    if isinstance(path_or_array, (str, Path)):
        free = load_map(path_or_array).free
    else:
        free = map_from_array(np.asarray(path_or_array)).free
    eroded = cv2.erode(free.astype(np.uint8), _KERNEL_3x3)
    contours, hierarchy = cv2.findContours(eroded, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    # float32 holds labels exactly and, unlike int32, is accepted by cv2.dilate.
    filled = np.zeros(free.shape, np.float32)
    label = 0
    for index, _contour in enumerate(contours):
        if hierarchy[0][index][3] == -1:  # top level: an outer boundary
            label += 1
            cv2.drawContours(filled, contours, index, float(label), thickness=cv2.FILLED)
    dilated = cv2.dilate(filled, _KERNEL_3x3)
    return relabel_in_raster_order(dilated.astype(np.int32))


def score_segmentation(pred_labels: np.ndarray, gt_labels: np.ndarray) -> SegmentationScore:
    """Per-region precision/recall of ``pred_labels`` against ``gt_labels``.

    Parameters
    ----------
    pred_labels, gt_labels : ndarray of int, same shape
        0 = no region.

    Returns
    -------
    SegmentationScore

    Raises
    ------
    SegmentationError
        Different shapes, or no ground-truth region.

    Examples
    --------
    >>> gt = np.array([[1, 1, 2, 2]])
    >>> score_segmentation(gt * 3, gt).f1
    1.0
    """
    pred = np.asarray(pred_labels)
    gt = np.asarray(gt_labels)
    if pred.shape != gt.shape:
        raise SegmentationError(f"prediction shape {pred.shape} differs from ground truth shape {gt.shape}")
    if pred.ndim != 2:
        raise SegmentationError(f"label images must be 2-D, got shape {pred.shape}")
    pred = pred.astype(np.int64, copy=False).ravel()
    gt = gt.astype(np.int64, copy=False).ravel()
    gt_ids, gt_sizes = np.unique(gt[gt > 0], return_counts=True)
    if len(gt_ids) == 0:
        raise SegmentationError("the ground truth has no region")
    pred_ids, pred_sizes = np.unique(pred[pred > 0], return_counts=True)
    both = (gt > 0) & (pred > 0)
    base = int(pred.max()) + 1
    codes, overlaps = np.unique(gt[both] * base + pred[both], return_counts=True)
    pair_gt, pair_pred = codes // base, codes % base

    best_match, region_precision, region_recall = [], [], []
    for gt_id, gt_size in zip(gt_ids.tolist(), gt_sizes.tolist()):
        rows = np.flatnonzero(pair_gt == gt_id)
        if len(rows) == 0:
            best_match.append(0)
            region_precision.append(0.0)
            region_recall.append(0.0)
            continue
        # Largest overlap; codes are sorted, so argmax picks the smaller label on ties.
        best = rows[np.argmax(overlaps[rows])]
        pred_id, overlap = int(pair_pred[best]), int(overlaps[best])
        pred_size = int(pred_sizes[np.searchsorted(pred_ids, pred_id)])
        best_match.append(pred_id)
        region_precision.append(overlap / pred_size)
        region_recall.append(overlap / gt_size)
    precision = float(np.mean(region_precision))
    recall = float(np.mean(region_recall))
    # Per predicted region: its largest overlap with a ground-truth region.
    best_overlap = np.zeros(base, np.int64)
    np.maximum.at(best_overlap, pair_pred, overlaps)
    evaluator_precision = float(np.mean(best_overlap[pred_ids] / pred_sizes)) if len(pred_ids) else 0.0
    return SegmentationScore(
        precision=precision,
        recall=recall,
        f1=_f1(precision, recall),
        evaluator_precision=evaluator_precision,
        evaluator_f1=_f1(evaluator_precision, recall),
        gt_regions=tuple(gt_ids.tolist()),
        best_match=tuple(best_match),
        region_precision=tuple(region_precision),
        region_recall=tuple(region_recall),
        n_predicted=len(pred_ids),
    )


def _f1(precision: float, recall: float) -> float:
    return 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)


def load_label_array(path: str | Path) -> np.ndarray:
    """Load a label image (8- or 16-bit; e.g. the authors' MAORIS outputs).

    Pixel value 0 is "no region"; every other value is a region. Colour
    images must have equal channels. Regions are renumbered 1..N in the raster
    order of their first pixel (pixels sharing a value stay one region).

    Raises
    ------
    SegmentationError
        Unreadable file, colour image with unequal channels, or unsupported type.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "labels.png"
    ...     _ = cv2.imwrite(str(path), np.array([[0, 9, 4]], np.uint8))
    ...     load_label_array(path).tolist()
    [[0, 1, 2]]
    """
    from ursim_core.segmentation.label_files import read_label_array

    return relabel_in_raster_order(read_label_array(path))
