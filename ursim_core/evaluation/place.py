"""Place accuracy: would a robot sent to a sketched place arrive in the right place?

Pair F1 (:mod:`ursim_core.evaluation.scoring`) can be gamed: with one region per map the single
pair hits every clique and F1 is 1.0. Place accuracy sends the robot where the match says
(:func:`ursim_core.navigation.goal.interior_target`, the rule ``ursim goal`` follows) and asks
whether it arrives in the clique's place, read in a fixed reference segmentation of the metric map
(:data:`PLACE_REFERENCE_PRESET`); one region per map scores about 0.2. :func:`place_accuracy`
gives the definition.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["PLACE_REFERENCE_PRESET", "PlaceScore", "PlaceProblem", "place_problem", "score_places", "place_accuracy"]


#: MAORIS preset of the fixed reference segmentation of a metric map for place accuracy: the one
#: the KTH annotators clicked on.
PLACE_REFERENCE_PRESET = "default"


@dataclass(frozen=True)
class PlaceScore:
    """Place accuracy of one set of matched pairs against reference cliques.

    Attributes
    ----------
    accuracy : float
        Mean over the scored cliques of the fraction of their sketch points sent to the right
        place; NaN when no clique could be scored.
    per_clique : tuple of float
        The fraction of each scored clique (in reference order, unscored cliques left out).
    clique_indices : tuple of int
        Index in the reference of each scored clique.
    successes, n_points : int
        Sketch points sent to the right place, and sketch points scored.
    n_cliques : int
        Cliques scored: with points on both sides and a non-empty place.

    Examples
    --------
    Three rooms in a row, the same in both maps; the second clique has no metric point:

    >>> labels = np.array([[1, 1, 1, 2, 2, 2, 3, 3, 3]])
    >>> reference = [([(0, 1)], [(0, 1)]), ([(0, 4)], []), ([(0, 7), (0, 8)], [(0, 7)])]
    >>> score = place_accuracy([(1, 1), (3, 2)], reference, labels, labels, labels)
    >>> score.accuracy, score.per_clique, score.clique_indices, (score.successes, score.n_points)
    (0.5, (1.0, 0.0), (0, 2), (1, 3))
    """

    accuracy: float
    per_clique: tuple[float, ...]
    clique_indices: tuple[int, ...]
    successes: int
    n_points: int

    @property
    def n_cliques(self) -> int:
        return len(self.per_clique)


@dataclass(frozen=True)
class PlaceProblem:
    """What place accuracy needs of the reference, independent of the pairs (computed once).

    Attributes
    ----------
    clique_indices : tuple of int
        The scored cliques' indices in the reference.
    sketch_regions : tuple of tuple of int
        Per scored clique, the region of each sketch point in the matcher's sketch segmentation
        (0 for a point more than ``tolerance`` px from any region).
    places : tuple of frozenset of int
        Per scored clique, its place: the regions of the reference metric segmentation under its
        metric points.
    reference_metric_labels : ndarray
        The fixed reference segmentation of the metric map.
    """

    clique_indices: tuple[int, ...]
    sketch_regions: tuple[tuple[int, ...], ...]
    places: tuple[frozenset[int], ...]
    reference_metric_labels: np.ndarray


def _point_cliques(reference: Any) -> list[tuple[tuple, tuple]]:
    items = []
    for item in getattr(reference, "cliques", reference):
        if hasattr(item, "sketch_points") and hasattr(item, "metric_points"):
            items.append((tuple(item.sketch_points), tuple(item.metric_points)))
        else:
            sketch_points, metric_points = item
            items.append((tuple(sketch_points), tuple(metric_points)))
    return items


def place_problem(
    reference: Any, sketch_labels: np.ndarray, reference_metric_labels: np.ndarray, *, tolerance: float = 10
) -> PlaceProblem:
    """The pair-independent part of :func:`place_accuracy`: sketch regions of the points, places.

    Parameters
    ----------
    reference : iterable or Correspondences
        Cliques with points: objects with ``sketch_points`` and ``metric_points`` or
        ``(sketch_points, metric_points)`` pairs of ``(row, col)`` lists.
    sketch_labels : ndarray
        The matcher's sketch segmentation.
    reference_metric_labels : ndarray
        The fixed reference segmentation of the metric map.
    tolerance : float, keyword-only
        Largest distance of a point to its region (the released code's 10 px rule).
    """
    from ursim_core.correspondences import regions_at_points

    indices, sketch_regions, places = [], [], []
    for index, (sketch_points, metric_points) in enumerate(_point_cliques(reference)):
        if not sketch_points or not metric_points:
            continue
        place = frozenset(regions_at_points(reference_metric_labels, metric_points, tolerance=tolerance)) - {0}
        if not place:
            # Every metric point is far from any region: no target can be right, nothing to ask.
            continue
        indices.append(index)
        sketch_regions.append(tuple(regions_at_points(sketch_labels, sketch_points, tolerance=tolerance)))
        places.append(place)
    return PlaceProblem(tuple(indices), tuple(sketch_regions), tuple(places), np.asarray(reference_metric_labels))


def score_places(pairs: Iterable[tuple[int, int]], problem: PlaceProblem, metric_graph: Any) -> PlaceScore:
    """Place accuracy of ``pairs`` on a prepared :class:`PlaceProblem` (see :func:`place_accuracy`).

    ``metric_graph`` is the region graph of the matcher's metric segmentation: node attributes
    ``size`` (pixels) and ``interior`` (a ``(row, col)`` pixel inside the region).
    """
    matched: dict[int, list[int]] = {}
    for sketch, metric in pairs:
        matched.setdefault(operator.index(sketch), []).append(operator.index(metric))
    labels = problem.reference_metric_labels
    target_label: dict[int, int] = {}
    from ursim_core.navigation.goal import interior_target

    for sketch, metrics in matched.items():
        # Where the robot is sent (the rule of ``ursim goal``), then the reference region under it.
        _, (row, col) = interior_target(metric_graph, metrics)
        target_label[sketch] = int(labels[row, col]) if 0 <= row < labels.shape[0] and 0 <= col < labels.shape[1] else 0

    per_clique, successes, n_points = [], 0, 0
    for regions, place in zip(problem.sketch_regions, problem.places):
        hits = sum(1 for region in regions if region and target_label.get(region, 0) in place)
        per_clique.append(hits / len(regions))
        successes += hits
        n_points += len(regions)
    accuracy = float(np.mean(per_clique)) if per_clique else math.nan
    return PlaceScore(
        accuracy=accuracy,
        per_clique=tuple(per_clique),
        clique_indices=problem.clique_indices,
        successes=successes,
        n_points=n_points,
    )


def place_accuracy(
    pairs: Iterable[tuple[int, int]],
    reference: Any,
    sketch_labels: np.ndarray,
    metric_labels: np.ndarray,
    reference_metric_labels: np.ndarray,
    metric_graph: Any = None,
    *,
    tolerance: float = 10,
) -> PlaceScore:
    """Place accuracy: how often a robot sent to a sketched place would arrive in the right place.

    Definition. For every reference clique with points on both sides, and every sketch point p
    of it: take the region s of p in the matcher's sketch segmentation (``sketch_labels``; a
    point more than ``tolerance`` px from any region has none); send the robot to the interior
    point of the largest metric region matched to s (in ``metric_labels``, by pixel count;
    smallest id on ties); it is a success when that point lies in the clique's *place*: the
    union of the regions, in a fixed reference segmentation of the metric map
    (``reference_metric_labels``; for KTH the MAORIS ``default`` preset, the one the annotators
    clicked on), under the clique's metric points (same tolerance). A point with no region or
    an unmatched region is a failure. Average over the clique's sketch points, then over the
    cliques. Cliques whose metric points all lie far from every reference region are not scored.

    Unlike pair F1, a coarse segmentation gains nothing: with one region per map the robot goes
    to the same point whatever is asked, and only the cliques whose place holds it succeed.

    Parameters
    ----------
    pairs : iterable of (sketch_region, metric_region)
        The matches, in the ids of ``sketch_labels`` and ``metric_labels``.
    reference : iterable or Correspondences
        Ground-truth cliques with points (see :func:`place_problem`).
    sketch_labels, metric_labels : ndarray
        The matcher's segmentations of the sketch and of the metric map.
    reference_metric_labels : ndarray
        The fixed reference segmentation of the metric map (same shape as ``metric_labels``).
    metric_graph : networkx.Graph, optional
        Region graph of ``metric_labels`` (``size``, ``interior``); computed when not given.
    tolerance : float, keyword-only
        Point-to-region distance of the 10 px rule.

    Returns
    -------
    PlaceScore

    Examples
    --------
    A 1 x 9 corridor in three rooms, cut the same way in the sketch and in the metric map; three
    cliques, one point on each side, one per room. The matcher swaps rooms 2 and 3:

    >>> import numpy as np
    >>> labels = np.array([[1, 1, 1, 2, 2, 2, 3, 3, 3]])
    >>> reference = [([(0, 1)], [(0, 1)]), ([(0, 4)], [(0, 4)]), ([(0, 7)], [(0, 7)])]
    >>> score = place_accuracy([(1, 1), (2, 3), (3, 2)], reference, labels, labels, labels)
    >>> round(score.accuracy, 3), score.successes, score.n_points
    (0.333, 1, 3)

    The right pairs send the robot into each room: all succeed (pair F1 is 1.0 too).

    >>> place_accuracy([(1, 1), (2, 2), (3, 3)], reference, labels, labels, labels).accuracy
    1.0

    One region per map: its single pair hits every clique, so pair F1 is 1.0, but the robot is
    sent to the same point whatever is asked, the right place for one clique of the three:

    >>> one = np.ones_like(labels)
    >>> round(place_accuracy([(1, 1)], reference, one, one, labels).accuracy, 3)
    0.333
    """
    if metric_graph is None:
        from ursim_core.segmentation.graph import region_graph

        metric_graph = region_graph(np.asarray(metric_labels))
    problem = place_problem(reference, sketch_labels, reference_metric_labels, tolerance=tolerance)
    return score_places(pairs, problem, metric_graph)
