"""Edits of a label image (0 = no region): merge two regions, split one by a line, paint or erase a wall.

Pure functions on arrays, (row, col) points; each returns a new label image and leaves
the input alone. Region ids that survive an edit keep their number (so the points of
a correspondence file keep meaning the same regions); a new region gets the next
unused id.

Examples
--------
>>> import numpy as np
>>> labels = np.zeros((5, 9), np.int32); labels[1:4, 1:8] = 1
>>> split = split_region(labels, 1, (0, 4), (4, 4))
>>> sorted(np.unique(split).tolist())
[0, 1, 2]
>>> merge_regions(split, 1, 2)[2, 2] == merge_regions(split, 1, 2)[2, 6]
np.True_
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from scipy import ndimage

__all__ = ["merge_regions", "split_region", "paint_wall", "erase_wall", "stroke_mask"]


def stroke_mask(shape: tuple[int, int], points: Sequence[tuple[int, int]], width: int = 1) -> np.ndarray:
    """Boolean mask of a polyline through ``points`` (row, col), ``width`` pixels wide."""
    mask = np.zeros(shape, np.uint8)
    if not points:
        return mask.astype(bool)
    xy = np.array([(int(col), int(row)) for row, col in points], np.int32)
    if len(xy) == 1:
        cv2.circle(mask, tuple(int(v) for v in xy[0]), max(0, width // 2), 1, -1)
    else:
        cv2.polylines(mask, [xy.reshape(-1, 1, 2)], False, 1, thickness=max(1, int(width)))
    return mask.astype(bool)


def merge_regions(labels: np.ndarray, keep: int, merged: int) -> np.ndarray:
    """Region ``merged`` becomes part of ``keep`` (the wall pixels between them stay walls)."""
    if keep == merged:
        return labels.copy()
    out = labels.copy()
    out[labels == merged] = keep
    return out


def _relabel_pieces(labels: np.ndarray, region: int, cut: np.ndarray) -> np.ndarray:
    """Region minus ``cut``: its largest piece keeps the id, the others get new ids."""
    out = labels.copy()
    inside = labels == region
    out[inside & cut] = 0
    pieces, count = ndimage.label(inside & ~cut)
    if count <= 1:
        return out
    sizes = ndimage.sum_labels(np.ones_like(pieces), pieces, index=np.arange(1, count + 1))
    order = np.argsort(-sizes, kind="stable") + 1
    next_id = int(labels.max()) + 1
    for piece in order[1:]:
        out[pieces == piece] = next_id
        next_id += 1
    return out


def split_region(
    labels: np.ndarray, region: int, start: tuple[int, int], end: tuple[int, int], *, width: int = 1
) -> np.ndarray:
    """Cut ``region`` along the line ``start`` -> ``end``; the line's pixels become walls.

    A line that does not cross the region from side to side leaves it in one piece
    (only the line's pixels are taken out of it).
    """
    cut = stroke_mask(labels.shape, [start, end], width)
    return _relabel_pieces(labels, int(region), cut)


def paint_wall(labels: np.ndarray, points: Sequence[tuple[int, int]], *, width: int = 3) -> np.ndarray:
    """Paint a wall stroke: its pixels leave their regions; a region cut in two becomes two."""
    cut = stroke_mask(labels.shape, points, width)
    out = labels.copy()
    for region in np.unique(labels[cut]):
        if region != 0:
            out = _relabel_pieces(out, int(region), cut)
    out[cut] = 0
    return out


def erase_wall(labels: np.ndarray, points: Sequence[tuple[int, int]], *, width: int = 3) -> np.ndarray:
    """Erase a wall stroke: its wall pixels join the region most of the stroke's other pixels are in.

    A stroke that touches no region changes nothing.
    """
    brush = stroke_mask(labels.shape, points, width)
    touched = labels[brush & (labels != 0)]
    if touched.size == 0:
        # The stroke may lie in a wall only: take the regions right around it.
        ring = ndimage.binary_dilation(brush, iterations=2) & (labels != 0)
        touched = labels[ring]
    if touched.size == 0:
        return labels.copy()
    values, counts = np.unique(touched, return_counts=True)
    out = labels.copy()
    out[brush & (labels == 0)] = int(values[np.argmax(counts)])
    return out
