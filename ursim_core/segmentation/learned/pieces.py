"""Candidate pieces: the overlay of two segmentations of the same free space.

A piece is a connected set of free pixels on which MAORIS and the clearance watershed
(:mod:`ursim_core.segmentation.watershed`) both give one label: every boundary of either
segmenter is a boundary between pieces, so merging pieces can reach either segmentation
and any mix of their boundaries. Slivers where the two boundaries nearly coincide join the
neighbour they share the longest boundary with (``min_piece`` px).

Examples
--------
>>> import numpy as np
>>> free = np.zeros((60, 130), bool)
>>> free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True
>>> pieces = candidate_pieces(free)
>>> int(pieces.labels.max()) >= 2, bool(pieces.labels[~free].any())
(True, False)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ursim_core.errors import SegmentationError

__all__ = ["CandidatePieces", "candidate_pieces", "clearance_of"]


@dataclass(frozen=True)
class CandidatePieces:
    """Pieces of a map and what the two segmenters said about them.

    Attributes
    ----------
    labels : ndarray of int32
        0 = obstacle; pieces 1..N.
    maoris, watershed : ndarray of int32
        The two segmentations the pieces overlay (the label of every pixel).
    clearance : ndarray of float32
        Euclidean distance of every free pixel to the nearest obstacle, px.
    """

    labels: np.ndarray
    maoris: np.ndarray
    watershed: np.ndarray
    clearance: np.ndarray


def clearance_of(free: np.ndarray) -> np.ndarray:
    """Distance of every free pixel to the nearest obstacle or the image border (px)."""
    import cv2

    padded = np.pad(free.astype(np.uint8), 1)
    return cv2.distanceTransform(padded, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)[1:-1, 1:-1]


def candidate_pieces(
    free: np.ndarray,
    *,
    maoris_preset: str = "sketch",
    door_ratio: float = 0.95,
    watershed_min_size: int = 100,
    min_piece: int = 30,
) -> CandidatePieces:
    """Overlay MAORIS and the watershed into candidate pieces.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True = free space.
    maoris_preset : str, keyword-only
        MAORIS preset (:data:`ursim_core.segmentation.maoris.PRESETS`).
    door_ratio, watershed_min_size : keyword-only
        The watershed's ``door_ratio`` and ``min_size``.
    min_piece : int, keyword-only
        Pieces smaller than this (px) join a neighbour.
    """
    from skimage.measure import label

    from ursim_core.segmentation.maoris import PRESETS, maoris_labels
    from ursim_core.segmentation.watershed import merge_small_regions, watershed_labels

    free = np.asarray(free)
    if free.ndim != 2 or free.size == 0:
        raise SegmentationError(f"free-space mask must be a non-empty 2-D array, got shape {free.shape}")
    free = free.astype(bool, copy=False)
    maoris = np.asarray(maoris_labels(free, PRESETS[maoris_preset]), np.int32)
    watershed = watershed_labels(free, door_ratio=door_ratio, min_size=watershed_min_size)
    clearance = clearance_of(free)
    # One code per (MAORIS label, watershed label); pieces are its 4-connected components.
    codes = maoris.astype(np.int64) * (int(watershed.max()) + 1) + watershed
    codes[~free | (maoris == 0) | (watershed == 0)] = 0  # MAORIS drops specks; so do the pieces
    labels = label(codes, background=0, connectivity=1).astype(np.int32)
    labels = merge_small_regions(labels, clearance, min_piece)
    return CandidatePieces(labels=_consecutive(labels), maoris=maoris, watershed=watershed, clearance=clearance)


def _consecutive(labels: np.ndarray) -> np.ndarray:
    present = np.unique(labels)
    present = present[present != 0]
    lookup = np.zeros(int(labels.max()) + 1, np.int32)
    lookup[present] = np.arange(1, len(present) + 1, dtype=np.int32)
    return lookup[labels]
