"""From clicked points to region ids: the assignment of points to the regions of a segmentation.

Points are authoritative; region ids are derived from them (:func:`regions_at_points`) and can
be recomputed after re-segmenting (:func:`assign_regions`). :func:`from_pairs` makes cliques
from a matcher's region pairs.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import warnings
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from ursim_core.correspondences.values import Clique, Correspondences
from ursim_core.errors import RegionsRecomputedWarning, SegmentationError

__all__ = ["regions_at_points", "assign_regions", "from_pairs"]


def regions_at_points(labels: np.ndarray, points: Iterable, *, tolerance: float = 10) -> list[int]:
    """The region id under each ``(row, col)`` point, with the released code's tolerance.

    A point on a region pixel gets that region. A point on 0 (a wall, outside
    the segmentation) or outside the image gets the region of the nearest
    non-zero pixel when that pixel is at most ``tolerance`` pixels away
    (Euclidean), else 0, meaning "dropped" (``GraphLaplacian::getVertex``).
    When several regions are equally near, any one of them may be returned.

    Parameters
    ----------
    labels : (rows, cols) integer array
        Label image, 0 = no region.
    points : iterable of (row, col)
        Pixel coordinates; non-integers are rounded to the nearest pixel.
    tolerance : float, keyword-only
        Largest distance in pixels to a region pixel, 10 by default.

    Returns
    -------
    list of int
        One id per point, 0 where no region is near enough.

    Examples
    --------
    >>> labels = np.zeros((5, 20), dtype=np.int32)
    >>> labels[:, :4] = 1
    >>> labels[:, 10:] = 2
    >>> regions_at_points(labels, [(2, 1), (2, 5), (2, 8), (2, 25)], tolerance=3)
    [1, 1, 2, 0]
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"labels must be a 2-D array, got shape {labels.shape}")
    coordinates = np.asarray(list(points) if not isinstance(points, np.ndarray) else points, dtype=float)
    if coordinates.size == 0:
        return []
    if coordinates.ndim != 2 or coordinates.shape[1] != 2:
        raise ValueError(f"points must be (row, col) pairs, got an array of shape {coordinates.shape}")
    if not np.all(np.isfinite(coordinates)):
        raise ValueError("points must be finite numbers")
    coordinates = np.rint(coordinates).astype(np.int64)
    rows, cols = labels.shape
    result = np.zeros(len(coordinates), dtype=np.int64)
    inside = (
        (coordinates[:, 0] >= 0) & (coordinates[:, 0] < rows) & (coordinates[:, 1] >= 0) & (coordinates[:, 1] < cols)
    )
    result[inside] = labels[coordinates[inside, 0], coordinates[inside, 1]]
    misses = np.flatnonzero(result == 0)
    if len(misses) == 0 or tolerance < 0 or not labels.any():
        return [int(value) for value in result]

    reach = int(math.floor(tolerance))
    window_area = (2 * reach + 1) ** 2
    remaining = misses
    # Measured costs: a window search is ~80 us per point plus ~0.02 us per
    # window pixel; the distance transform with indices ~0.3 us per image pixel.
    if len(misses) * (window_area + 4000) > 15 * labels.size:
        # Many misses or a large tolerance: one distance transform answers all
        # points inside the image at once.
        from scipy import ndimage  # 0.4 s to import: only when a point is off every region

        distance, (nearest_row, nearest_col) = ndimage.distance_transform_edt(labels == 0, return_indices=True)
        inside_misses = misses[inside[misses]]
        miss_rows, miss_cols = coordinates[inside_misses, 0], coordinates[inside_misses, 1]
        near = distance[miss_rows, miss_cols] <= tolerance
        result[inside_misses[near]] = labels[
            nearest_row[miss_rows[near], miss_cols[near]], nearest_col[miss_rows[near], miss_cols[near]]
        ]
        remaining = misses[~inside[misses]]
    for index in remaining:
        row, col = coordinates[index]
        result[index] = _nearest_label_in_window(labels, row, col, tolerance, reach)
    return [int(value) for value in result]


def _nearest_label_in_window(labels: np.ndarray, row: int, col: int, tolerance: float, reach: int) -> int:
    top, bottom = max(row - reach, 0), min(row + reach + 1, labels.shape[0])
    left, right = max(col - reach, 0), min(col + reach + 1, labels.shape[1])
    if top >= bottom or left >= right:
        return 0
    window = labels[top:bottom, left:right]
    found_rows, found_cols = np.nonzero(window)
    if len(found_rows) == 0:
        return 0
    squared = (found_rows + top - row) ** 2 + (found_cols + left - col) ** 2
    best = int(np.argmin(squared))
    if squared[best] > tolerance * tolerance:
        return 0
    return int(window[found_rows[best], found_cols[best]])


def assign_regions(
    corr: Correspondences, sketch_labels: np.ndarray, metric_labels: np.ndarray, *, tolerance: float = 10
) -> Correspondences:
    """Fill every clique's region ids from its points.

    Each side's regions become the ids under its points (see
    :func:`regions_at_points`), without duplicates, in point order, with
    dropped points (0) left out. Points are not changed.

    Parameters
    ----------
    corr : Correspondences
        Cliques with points.
    sketch_labels, metric_labels : (rows, cols) integer arrays
        Label images of the two maps.
    tolerance : float, keyword-only
        As in :func:`regions_at_points`.

    Returns
    -------
    Correspondences
        A copy with ``sketch_regions`` and ``metric_regions`` replaced.

    Raises
    ------
    SegmentationError
        A label image's shape differs from the size recorded for its map.

    Warns
    -----
    RegionsRecomputedWarning
        Some cliques carried region ids that their points contradict (e.g. labels of
        another segmentation); the ids of the points replace them.

    Examples
    --------
    >>> labels = np.array([[1, 1, 0, 2, 2]], dtype=np.int32)
    >>> corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(0, 0), (0, 1), (0, 4)],
    ...                                        metric_points=[(0, 3)]),))
    >>> done = assign_regions(corr, labels, labels)
    >>> done.cliques[0].sketch_regions, done.cliques[0].metric_regions
    ((1, 2), (2,))
    """
    for side, ref, labels in (("sketch", corr.sketch, sketch_labels), ("metric", corr.metric, metric_labels)):
        shape = np.shape(labels)
        if ref.size is not None and tuple(shape) != tuple(ref.size):
            raise SegmentationError(
                f"the {side} label image is {shape[0]}x{shape[1]} but the {side} map is "
                f"{ref.size[0]}x{ref.size[1]}: labels of another image?",
                path=ref.labels_path or ref.path,
            )
    sketch_regions = _regions_per_clique(sketch_labels, [c.sketch_points for c in corr.cliques], tolerance)
    metric_regions = _regions_per_clique(metric_labels, [c.metric_points for c in corr.cliques], tolerance)
    # Cliques that carried region ids (not a fresh .dat file) whose ids the points contradict.
    changed = [
        clique.id
        for clique, sketch, metric in zip(corr.cliques, sketch_regions, metric_regions)
        if (clique.sketch_regions or clique.metric_regions)
        and (set(clique.sketch_regions) != set(sketch) or set(clique.metric_regions) != set(metric))
    ]
    if changed:
        listed = ", ".join(str(clique_id) for clique_id in changed[:10]) + (", ..." if len(changed) > 10 else "")
        noun = "clique" if len(changed) == 1 else "cliques"
        warnings.warn(
            RegionsRecomputedWarning(
                f"the region ids of {len(changed)} {noun} ({noun} {listed}) disagreed with their points "
                "and were recomputed from the points"
            ),
            stacklevel=2,
        )
    return corr.with_cliques(
        dataclasses.replace(clique, sketch_regions=sketch, metric_regions=metric)
        for clique, sketch, metric in zip(corr.cliques, sketch_regions, metric_regions)
    )


def _regions_per_clique(labels: np.ndarray, point_lists: Sequence[Sequence], tolerance: float) -> list[tuple]:
    # One call for all points, so the distance transform (if needed) is computed once.
    flat = [point for points in point_lists for point in points]
    found = iter(regions_at_points(labels, flat, tolerance=tolerance))
    result = []
    for points in point_lists:
        ids = [next(found) for _ in points]
        result.append(tuple(dict.fromkeys(region for region in ids if region != 0)))
    return result


def from_pairs(
    pairs: Iterable[tuple[int, int]],
    *,
    sketch_points_of: Callable[[int], tuple[int, int]],
    metric_points_of: Callable[[int], tuple[int, int]],
    source: str = "auto",
    scores: Sequence[float | None] | None = None,
    first_id: int = 1,
) -> tuple[Clique, ...]:
    """One clique per matched region pair, anchored at a representative point of each region.

    Parameters
    ----------
    pairs : iterable of (sketch_region, metric_region)
        E.g. ``MatchResult.pairs``.
    sketch_points_of, metric_points_of : callable, keyword-only
        Region id -> ``(row, col)`` interior point, e.g.
        ``lambda region: graph.nodes[region]["interior"]``.
    source : {"auto", "manual"}, keyword-only
        Source recorded on every clique.
    scores : sequence of float or None, keyword-only
        One score per pair.
    first_id : int, keyword-only
        Id of the first clique (e.g. ``corr.next_clique_id()`` to append).

    Returns
    -------
    tuple of Clique

    Examples
    --------
    >>> centres = {1: (5, 5), 2: (5, 30), 7: (40, 12)}
    >>> cliques = from_pairs([(1, 7), (2, 7)], sketch_points_of=centres.get, metric_points_of=centres.get)
    >>> [(c.id, c.sketch_points, c.metric_regions, c.effective_status) for c in cliques]
    [(1, ((5, 5),), (7,), 'pending'), (2, ((5, 30),), (7,), 'pending')]
    """
    pairs = [(operator.index(sketch), operator.index(metric)) for sketch, metric in pairs]
    if scores is not None and len(scores) != len(pairs):
        raise ValueError(f"{len(scores)} scores for {len(pairs)} pairs")
    return tuple(
        Clique(
            id=first_id + index,
            sketch_points=(sketch_points_of(sketch),),
            metric_points=(metric_points_of(metric),),
            sketch_regions=(sketch,),
            metric_regions=(metric,),
            source=source,
            score=None if scores is None else scores[index],
        )
        for index, (sketch, metric) in enumerate(pairs)
    )
