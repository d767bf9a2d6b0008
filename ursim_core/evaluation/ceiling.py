"""The ceiling of a one-to-one matcher: the best mean F1 any one-to-one answer reaches against the annotators.

A matcher answers one set of pairs per map pair; it is scored against every annotator's cliques
and the scores are averaged. Where the annotators disagree (KTH sketch 07: one read the sketch
turned by a half turn, the other upright), no answer can satisfy both, and where a clique joins
several regions on a side, one-to-one pairs cannot hit all of it. So the best mean F1 any
one-to-one answer can reach, the *ceiling*, can be well below 1, and a matcher's figure means
more beside it: the gap to the ceiling is the matcher's, the gap above it the data's.

:func:`best_one_to_one` finds that answer exactly. Only pairs that lie in some annotator's
clique can be in it: a pair in none is a false positive for everyone and never raises an F1
(correct scoring, :func:`ursim_core.evaluation.scoring.score_matches`). The search goes through
the sketch regions in order, pairing each with one of its candidate partners or with none, and
cuts a branch when even the best case of the regions left (each one more true positive that hits
as many new cliques as any candidate pair can) cannot beat the best answer found.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ursim_core.evaluation.scoring import score_matches

__all__ = ["Ceiling", "best_one_to_one"]

#: Search nodes after which the best answer found so far is returned, marked not exact. The 18 KTH
#: sketches need at most a few thousand; the bound keeps a dataset with huge cliques finite.
NODE_BUDGET = 2_000_000


@dataclass(frozen=True)
class Ceiling:
    """The best one-to-one answer against a set of references.

    Attributes
    ----------
    pairs : tuple of (sketch region, metric region)
        The answer, sorted.
    f1 : tuple of float
        Its F1 against each reference, in the order given.
    exact : bool
        False when the search stopped at :data:`NODE_BUDGET` nodes: ``mean_f1`` is then what the
        best answer found reaches, a lower bound of the ceiling.

    Examples
    --------
    >>> ana = ben = [({1}, {10}), ({2}, {20})]
    >>> cy = [({1}, {10}), ({2}, {21})]  # the third annotator put sketch region 2 elsewhere
    >>> ceiling = best_one_to_one([ana, ben, cy])
    >>> ceiling.pairs, ceiling.f1, round(ceiling.mean_f1, 3), ceiling.exact
    (((1, 10), (2, 20)), (1.0, 1.0, 0.5), 0.833, True)
    """

    pairs: tuple[tuple[int, int], ...]
    f1: tuple[float, ...]
    exact: bool = True

    @property
    def mean_f1(self) -> float:
        return math.fsum(self.f1) / len(self.f1) if self.f1 else math.nan


#: The end of a frame's choices (None is a choice: the region left unpaired).
_DONE = object()


def _f1(tp: int, fp: int, fn: int) -> float:
    if not (tp or fp or fn):
        return 1.0  # nothing to find and nothing wrong: score_matches's perfect empty answer
    return 2 * tp / (2 * tp + fp + fn) if tp else 0.0


def best_one_to_one(references: Sequence, *, node_budget: int = NODE_BUDGET) -> Ceiling:
    """The one-to-one answer with the highest mean F1 (correct scoring) over ``references``.

    Parameters
    ----------
    references : sequence
        One entry per annotator: its cliques, each ``(sketch_regions, metric_regions)`` (as
        :func:`ursim_core.evaluation.scoring.score_matches` takes them; region 0 is no region).
    node_budget : int, keyword-only
        Search nodes before the best answer found so far is returned (``exact=False``).

    Returns
    -------
    Ceiling
        Ties between answers go to the first one the depth-first search reaches (sketch regions
        in increasing order, each paired before it is left unpaired, partners in increasing
        order). Every node counts as an answer, so the first may be the shorter one: with
        annotators A = {1-10, 2-20} and B = A + {3-30}, pairing 3 with 30 too scores the same
        mean F1 (B's recall gained, A's precision lost) and is not returned.

    Examples
    --------
    Two annotators who read a two-room sketch in opposite ways: any answer satisfies one of them.

    >>> upright = [({1}, {10}), ({2}, {20})]
    >>> turned = [({1}, {20}), ({2}, {10})]
    >>> ceiling = best_one_to_one([upright, turned])
    >>> ceiling.pairs, round(ceiling.mean_f1, 3)
    (((1, 10), (2, 20)), 0.5)

    A clique of two metric regions: one-to-one pairs hit it once, which is all F1 asks.

    >>> best_one_to_one([[({1}, {10, 11}), ({2}, {20})]]).f1
    (1.0,)
    """
    cliques = [[(frozenset(s) - {0}, frozenset(m) - {0}) for s, m in _items(reference)] for reference in references]
    if not cliques:
        return Ceiling((), ())
    usable = [[bool(s) and bool(m) for s, m in group] for group in cliques]
    # Per candidate pair and reference: the cliques it lies in.
    candidates: dict[tuple[int, int], tuple[tuple[int, ...], ...]] = {}
    for group in cliques:
        for sketch_set, metric_set in group:
            for a in sketch_set:
                for b in metric_set:
                    candidates.setdefault((a, b), ())
    for pair in candidates:
        candidates[pair] = tuple(
            tuple(k for k, (s, m) in enumerate(group) if pair[0] in s and pair[1] in m) for group in cliques
        )
    partners: dict[int, list[int]] = {}
    for a, b in sorted(candidates):
        partners.setdefault(a, []).append(b)
    sketch_order = sorted(partners)
    n_refs = len(cliques)
    # The most cliques of one reference that a single pair can hit (the bound's step).
    widest = [max((len(hits[r]) for hits in candidates.values()), default=0) for r in range(n_refs)]

    tp = [0] * n_refs
    fp = [0] * n_refs
    hit_counts = [[0] * len(group) for group in cliques]
    missed = [sum(flags) for flags in usable]  # usable cliques not hit yet
    used_metric: set[int] = set()
    chosen: list[tuple[int, int]] = []

    def current() -> float:
        return math.fsum(_f1(tp[r], fp[r], missed[r]) for r in range(n_refs)) / n_refs

    def bound(left: int) -> float:
        total = 0.0
        for r in range(n_refs):
            best_tp = tp[r] + left
            best_fn = max(0, missed[r] - left * widest[r])
            total += _f1(best_tp, fp[r], best_fn)
        return total / n_refs

    best = {"score": current(), "pairs": (), "nodes": 0, "exact": True}

    def add(pair, sign: int) -> None:
        for r, hits in enumerate(candidates[pair]):
            if not hits:
                fp[r] += sign
                continue
            tp[r] += sign
            for k in hits:
                if not usable[r][k]:
                    continue
                before = hit_counts[r][k]
                hit_counts[r][k] += sign
                if sign > 0 and before == 0:
                    missed[r] -= 1
                elif sign < 0 and hit_counts[r][k] == 0:
                    missed[r] += 1

    def visit(position: int) -> bool:
        """Count the node, keep it when best; True when its choices are worth trying."""
        best["nodes"] += 1
        if best["nodes"] > node_budget:
            best["exact"] = False
            return False
        score = current()
        if score > best["score"] + 1e-12:
            best["score"], best["pairs"] = score, tuple(chosen)
        return position < len(sketch_order) and bound(len(sketch_order) - position) > best["score"] + 1e-12

    # Depth first with an explicit stack (a map can have more sketch regions than Python's
    # recursion limit). A frame: its position, its choices left (each partner, then None: the
    # region left unpaired) and the pair it applied for the child being explored.
    stack = [[0, iter([*partners[sketch_order[0]], None]), None]] if visit(0) else []
    while stack and best["exact"]:
        frame = stack[-1]
        position, choices, applied = frame
        if applied is not None:
            add(applied, -1)
            chosen.pop()
            used_metric.discard(applied[1])
            frame[2] = None
        choice = next(choices, _DONE)
        if choice is _DONE:
            stack.pop()
            continue
        if choice is not None:
            if choice in used_metric:
                continue
            pair = (sketch_order[position], choice)
            used_metric.add(choice)
            chosen.append(pair)
            add(pair, 1)
            frame[2] = pair
        if visit(position + 1):
            stack.append([position + 1, iter([*partners[sketch_order[position + 1]], None]), None])
    pairs = tuple(sorted(best["pairs"]))
    f1 = tuple(score_matches(pairs, group).f1 for group in cliques)
    return Ceiling(pairs, f1, exact=best["exact"])


def _items(reference):
    """Cliques as ``(sketch_regions, metric_regions)``, from tuples or Clique-like objects."""
    for item in getattr(reference, "cliques", reference):
        if hasattr(item, "sketch_regions"):
            yield item.sketch_regions, item.metric_regions
        else:
            yield item
