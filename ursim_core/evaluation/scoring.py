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

Place accuracy (:mod:`ursim_core.evaluation.place`) asks what a robot's user asks, "would it go
to the right place?", and cannot be gamed by a coarse segmentation as pair F1 can (one region per
map gives F1 = 1.0).
"""

from __future__ import annotations

import operator
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from itertools import product
from typing import Any

from ursim_core.errors import ParameterError

__all__ = [
    "MatchScore",
    "score_matches",
    "score_cliques",
    "SCORING_MODES",
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
