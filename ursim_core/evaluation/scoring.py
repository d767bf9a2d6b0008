"""Scoring region matches against reference cliques: TP, FP, FN, precision, recall, F1.

The definitions are the paper's (Mielle et al. 2019, "Evaluation"): a returned
correspondence (sketch region, metric region) is a true positive when some
reference clique contains the sketch region on its sketch side and the metric
region on its metric side, else a false positive; a reference clique that no
true positive falls in is a false negative. P = tp / (tp + fp),
R = tp / (tp + fn), F1 = 2PR / (P + R), and F1 = 0 when tp = 0.

Three modes (keyword ``legacy``):

``False`` (default, "correct")
    Each distinct pair counts once, however many cliques contain it. Cliques
    with no region on one side (empty match sets, points that mapped to no
    region) are ignored: nothing can ever hit them.
``True`` (or ``"as-built"``)
    What the released binary printed (``Evaluation.hpp`` / ``MatchMaps.hpp``
    built with -O2): the false-negative test reads an uninitialised flag that
    the compiler drops, so FN is always 0 and recall is 1 whenever one match is
    right. A pair is counted once per clique that contains it.
``"fnfix"``
    The same code with the flag initialised to false: FN = cliques not hit,
    including the empty or unmappable ones that were kept (the trailing empty
    match set of the published .dat files is always an FN). A pair is counted
    once per clique that contains it.

In both legacy modes every given pair is counted, duplicates included, as the
C++ loop did; undefined ratios (0/0) are 0 instead of NaN.

Place accuracy (:func:`place_accuracy`) asks what a robot's user asks, "would it go to the right
place?", and cannot be gamed by a coarse segmentation as pair F1 can (one region per map gives
F1 = 1.0). See its docstring for the definition.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import product
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError

__all__ = [
    "MatchScore",
    "score_matches",
    "score_cliques",
    "SCORING_MODES",
    "PlaceScore",
    "PlaceProblem",
    "place_problem",
    "score_places",
    "place_accuracy",
    "PLACE_REFERENCE_PRESET",
]

SCORING_MODES = ("correct", "as-built", "fnfix")


@dataclass(frozen=True)
class MatchScore:
    """Counts, ratios and per-item labels of one scoring.

    Attributes
    ----------
    tp, fp, fn : int
        True positives, false positives, false negatives (as counted by ``mode``).
    precision, recall, f1 : float
        In [0, 1].
    mode : {"correct", "as-built", "fnfix"}
        The scoring rules used.
    pairs : tuple of (int, int)
        The scored (sketch_region, metric_region) pairs, in input order.
    pair_labels : tuple of {"tp", "fp"}
        One label per entry of ``pairs``.
    pair_cliques : tuple of tuple of int
        For each pair, the indices of the reference cliques that contain it.
    clique_labels : tuple of {"hit", "missed", "ignored"}
        One label per reference clique: "hit" (a true positive falls in it),
        "missed" (none does; an FN, except in the as-built mode whose FN is
        always 0) or "ignored" (a side has no region, so it cannot be hit; only
        the fnfix mode counts such a clique, as "missed").

    Examples
    --------
    >>> score = score_matches([(1, 10), (2, 30)], [({1}, {10}), ({3}, {30})])
    >>> score.pair_labels, score.clique_labels
    (('tp', 'fp'), ('hit', 'missed'))
    """

    tp: int
    fp: int
    fn: int
    precision: float
    recall: float
    f1: float
    mode: str
    pairs: tuple[tuple[int, int], ...]
    pair_labels: tuple[str, ...]
    pair_cliques: tuple[tuple[int, ...], ...]
    clique_labels: tuple[str, ...]


def score_matches(pairs: Iterable[tuple[int, int]], reference: Iterable, *, legacy: bool | str = False) -> MatchScore:
    """Score matched region pairs against reference cliques.

    Parameters
    ----------
    pairs : iterable of (sketch_region, metric_region)
        The returned correspondences, e.g. ``MatchResult.pairs``.
    reference : iterable
        Reference cliques, each a ``(sketch_regions, metric_regions)`` pair of
        collections of region ids, or an object with ``sketch_regions`` and
        ``metric_regions`` attributes (a :class:`~ursim_core.correspondences.Clique`).
        A :class:`~ursim_core.correspondences.Correspondences` is taken as its cliques.
    legacy : {False, True, "as-built", "fnfix"}, keyword-only
        Scoring rules; see the module docstring. False is the correct scoring.

    Returns
    -------
    MatchScore

    Raises
    ------
    ParameterError
        The reference cliques have points but not one region id (e.g. from
        :func:`~ursim_core.correspondences.load_dat`): call
        :func:`~ursim_core.correspondences.assign_regions` first, else every clique is unusable.

    Notes
    -----
    Correct mode: precision is 0 when there are no pairs and recall is 0 when
    there is nothing to find, except that no pairs against no usable reference
    clique is a perfect result (P = R = F1 = 1): nothing was to be found and
    nothing wrong was returned. Duplicate pairs are counted once (every copy
    gets the same label).

    Examples
    --------
    One pair in two overlapping cliques, one wrong pair, one clique missed:

    >>> reference = [({1}, {10}), ({1, 2}, {10, 11}), ({3}, {12})]
    >>> score = score_matches([(1, 10), (4, 13)], reference)
    >>> score.tp, score.fp, score.fn, round(score.f1, 3)
    (1, 1, 1, 0.5)
    >>> score_matches([(1, 10), (4, 13)], reference, legacy="fnfix").tp
    2
    """
    mode = _mode(legacy)
    pairs = tuple((operator.index(sketch), operator.index(metric)) for sketch, metric in pairs)
    items = list(_cliques_of(reference))
    _refuse_unassigned(items, "reference")
    cliques = [_region_sets(item) for item in items]

    pair_cliques = tuple(
        tuple(index for index, (sketch_set, metric_set) in enumerate(cliques) if s in sketch_set and m in metric_set)
        for s, m in pairs
    )
    pair_labels = tuple("tp" if hits else "fp" for hits in pair_cliques)
    hit = [False] * len(cliques)
    for hits in pair_cliques:
        for index in hits:
            hit[index] = True
    usable = [bool(sketch_set) and bool(metric_set) for sketch_set, metric_set in cliques]

    if mode == "correct":
        first_index: dict[tuple[int, int], int] = {}
        for index, pair in enumerate(pairs):
            first_index.setdefault(pair, index)
        tp = sum(1 for index in first_index.values() if pair_cliques[index])
        fp = len(first_index) - tp
        fn = sum(1 for index in range(len(cliques)) if usable[index] and not hit[index])
    else:
        # The C++ loops: one TP per (match, GT set) containing it, one FP per match in none.
        tp = sum(len(hits) for hits in pair_cliques)
        fp = sum(1 for hits in pair_cliques if not hits)
        fn = hit.count(False) if mode == "fnfix" else 0
    # fnfix counts every clique, even one with an empty side; the other modes
    # label such cliques "ignored" (as-built still labels real misses "missed",
    # it just never counted them).
    counted = [True] * len(cliques) if mode == "fnfix" else usable
    clique_labels = tuple(
        "hit" if hit[index] else ("missed" if counted[index] else "ignored") for index in range(len(cliques))
    )

    if mode == "correct" and tp + fp == 0 and not any(usable):
        precision = recall = f1 = 1.0
    else:
        precision = tp / (tp + fp) if tp + fp else 0.0
        recall = tp / (tp + fn) if tp + fn else 0.0
        f1 = 2 * precision * recall / (precision + recall) if tp else 0.0
    return MatchScore(
        tp=tp,
        fp=fp,
        fn=fn,
        precision=precision,
        recall=recall,
        f1=f1,
        mode=mode,
        pairs=pairs,
        pair_labels=pair_labels,
        pair_cliques=pair_cliques,
        clique_labels=clique_labels,
    )


def score_cliques(predicted: Iterable, reference: Iterable, *, legacy: bool | str = False) -> MatchScore:
    """Score one set of cliques against another (e.g. one annotator against another).

    Each predicted clique stands for every pair of its sketch regions and
    metric regions (the Cartesian product); the distinct pairs, in order of
    first appearance, are scored with :func:`score_matches`. A predicted clique
    with no region on a side contributes no pair. The released human-vs-human
    evaluation (``CreateHypFromGT::compare``) is not described in the design
    notes, so this is a choice: it treats a clique exactly as the reference
    side does, as "all these regions correspond to all those".

    Parameters
    ----------
    predicted, reference : iterable
        Cliques as accepted by :func:`score_matches` for ``reference``.
    legacy : {False, True, "as-built", "fnfix"}, keyword-only
        Scoring rules; see the module docstring.

    Returns
    -------
    MatchScore
        ``pairs`` holds the generated pairs.

    Raises
    ------
    ParameterError
        Either side's cliques have points but no region id (see :func:`score_matches`).

    Examples
    --------
    >>> score = score_cliques([({1, 2}, {10})], [({1}, {10}), ({2}, {11})])
    >>> score.pairs, score.pair_labels, score.fn
    (((1, 10), (2, 10)), ('tp', 'fp'), 1)
    """
    pairs: dict[tuple[int, int], None] = {}
    predicted = list(_cliques_of(predicted))
    _refuse_unassigned(predicted, "predicted")
    for item in predicted:
        sketch_regions, metric_regions = _region_lists(item)
        for pair in product(sketch_regions, metric_regions):
            pairs.setdefault(pair, None)
    return score_matches(list(pairs), reference, legacy=legacy)


def _mode(legacy: Any) -> str:
    if legacy is False or legacy is None:
        return "correct"
    if legacy is True or legacy == "as-built":
        return "as-built"
    if legacy == "fnfix":
        return "fnfix"
    if legacy == "correct":
        return "correct"
    raise ParameterError(f"legacy must be False, True, 'as-built' or 'fnfix', got {legacy!r}", field="legacy")


def _cliques_of(items: Any) -> Sequence:
    # A Correspondences is scored through its cliques.
    return getattr(items, "cliques", items)


def _refuse_unassigned(items: Sequence, name: str) -> None:
    # Points and not one region id: never assigned. One id is enough (points off every region get none).
    if any(getattr(item, "sketch_points", ()) or getattr(item, "metric_points", ()) for item in items) and all(
        _region_lists(item) == ([], []) for item in items
    ):
        raise ParameterError(
            f"the {name} cliques have points but no region ids: call ursim_core.correspondences.assign_regions"
            f"({name}, sketch_labels, metric_labels) with the labels the pairs refer to first",
            field=name,
        )


def _region_lists(item: Any) -> tuple[list[int], list[int]]:
    if hasattr(item, "sketch_regions") and hasattr(item, "metric_regions"):
        sketch_regions, metric_regions = item.sketch_regions, item.metric_regions
    else:
        sketch_regions, metric_regions = item
    # Sorted so that sets give a reproducible pair order.
    return (
        sorted({operator.index(region) for region in sketch_regions}),
        sorted({operator.index(region) for region in metric_regions}),
    )


def _region_sets(item: Any) -> tuple[frozenset[int], frozenset[int]]:
    sketch_regions, metric_regions = _region_lists(item)
    return frozenset(sketch_regions), frozenset(metric_regions)


# --------------------------------------------------------------------------- place accuracy

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
    for item in _cliques_of(reference):
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
