"""Automatic choice of the threshold m per map pair (``MatchConfig(m="auto")``, the default).

The paper names the choice of m as future work: it reports F1 with the best m *per map* (an
oracle that needs the ground truth) and shows that one fixed m for all maps is clearly worse.

Rule ``"score"`` (default)
    Run the matcher at every m of ``config.m_grid`` (0, 0.025, ..., 0.475) and keep the result whose
    hypothesis score, normalised by the size of the problem ``n1 + n2 + e1 + e2``, is the lowest;
    ties go to the smallest m. With the default ``hypothesis_score="signature"`` the score is
    ``structural cost + w * sum of c over the matched pairs`` (w = ``score_weight`` = 4), so the rule
    is: among all hypotheses generated at any m, pick the one that explains most of both graphs
    (structural cost) with the most similar regions (sum of c). m only decides which seeds and
    which alignments are generated. It reads nothing but the two maps.
Rule ``"structure"``
    The same with the structural cost alone (the released code's score). Kept for comparison: it
    always prefers large, structurally complete but wrong hypotheses.

Evidence (18 KTH sketches x 2 annotators, MAORIS "default" preset on maps binarised at > 250,
correct scoring; mean F1 over the sketches as malcolm / vasiliki). Printed from the code as it is
by ``python -m ursim_core.bench_matching --accuracy --sizes --auto-sizes``
(:func:`ursim_core.matching.experiments.accuracy_report`); exploration scripts in
``scratch_matching/``. The MAORIS port was revised while this was measured; both revisions are
shown (A: when beta and w were chosen; B: later, with beta and w left as chosen on A, so B is an
out-of-sample check of the hyper-parameters).

==========================================================  =================  ===================  =================
configuration (segmentation A | B)                          oracle m           best fixed m         auto m
==========================================================  =================  ===================  =================
``MatchConfig.paper()`` (T4, structure + substitutions)     .668/.661|.662/.687 .560/.550|.539/.562  .432/.396|.533/.533
``MatchConfig.released()`` options, this segmentation       .608/.559|.658/.639 .430/.376|.496/.490  --
default but ``hypothesis_score="structure"``                --                 --                   .491/.462|.535/.532
default but ``position_weight=0``                           --                 --                   .519/.465|.587/.550
**default** ``MatchConfig()``                               .667/.707|.702/.757 .602/.621|.662/.708  **.657/.667|.627/.692**
==========================================================  =================  ===================  =================

Medians of the default with auto m: 0.641 / 0.641 (A), 0.615 / 0.833 (B). Both extensions are
needed: each alone gains little with the automatic m; together they reach about the oracle-m
accuracy of the paper's method without knowing the ground truth. Reflections do not help on these
sketches (A: 0.648 / 0.667).

Hyper-parameters: beta = ``position_weight`` = 0.5 and w = ``score_weight`` = 4 were chosen on
segmentation A. Leave-one-sketch-out (choose beta in {0.25, 0.5, 1} and w in {2, 3, 4, 6} on 17
sketches, score the 18th): A 0.653 held-out (0.641 / 0.664) against 0.660 in-sample for (0.5, 4),
which was picked in 16 of 18 folds. On B the in-sample landscape is a flat plateau (0.66-0.69 for
beta 0.25-2, w 3-6, best beta 1, w 3-4) and leave-one-out over beta in {0.25, ..., 3} x w falls to
0.611: on 18 sketches, re-tuning buys nothing reliable, so the A setting was kept (B: 0.659 mean of
the two annotators). Over a much wider family (234 settings incl. other variants and
segmentations, A) leave-one-out falls to 0.558: wide searches overfit this small data set.
With maps binarised as "non-zero = free" the same setting scores 0.619 (A) against 0.46 for the
paper's method with its best fixed m.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["AUTO_RULES", "choose_m", "sweep"]


def sweep(prepared, grid=None) -> list:
    """Match at every m of the grid (``config.m_grid`` by default), in grid order.

    Values of m that select exactly the same pairs as the previous one (same "same" relation)
    reuse its result, with ``m`` updated: the matcher would return the same answer.

    Examples
    --------
    >>> import networkx as nx
    >>> from ursim_core.matching import MatchConfig, prepare
    >>> g = nx.path_graph(3)
    >>> nx.set_node_attributes(g, {0: 50, 1: 10, 2: 12}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    >>> [r.m for r in sweep(prepare(g, g.copy()), [0.0, 0.1])]
    [0.0, 0.1]
    """
    from . import match_prepared

    grid = prepared.config.m_grid if grid is None else grid
    c_matrix = prepared.c_matrix
    results = []
    previous_mask = None
    for m in grid:
        mask = c_matrix <= float(m)
        if previous_mask is not None and np.array_equal(mask, previous_mask) and results:
            results.append(replace(results[-1], m=float(m)))
            continue
        results.append(match_prepared(prepared, float(m)))
        previous_mask = mask
    return results


def _rule_score(prepared, results) -> list[float]:
    """Normalised hypothesis score of each result (1 when nothing was matched)."""
    return [r.normalised_cost for r in results]


def _rule_structure(prepared, results) -> list[float]:
    """Normalised structural cost alone."""
    from .planar import hypothesis_cost

    first, second = prepared.sketch_planar, prepared.metric_planar
    total = max(1, first.n_vertices + second.n_vertices + len(first.edges) + len(second.edges))
    scores = []
    for r in results:
        if not r.pairs:
            scores.append(1.0)
            continue
        sketch_index = {n: i for i, n in enumerate(first.nodes)}
        metric_index = {n: i for i, n in enumerate(second.nodes)}
        index_pairs = [(sketch_index[a], metric_index[b]) for a, b in r.pairs]
        scores.append(hypothesis_cost(first, second, index_pairs) / total)
    return scores


AUTO_RULES = {"score": _rule_score, "structure": _rule_structure}


def choose_m(prepared):
    """Pick m over ``config.m_grid`` with ``config.auto_rule``; return that m's MatchResult.

    The result's ``m_scan`` maps every m of the grid to the rule's statistic (lower is
    better); ties go to the smallest m.

    Examples
    --------
    >>> import networkx as nx
    >>> from ursim_core.matching import MatchConfig, prepare
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> result = choose_m(prepare(g, g.copy()))
    >>> result.m in MatchConfig().m_grid, sorted(result.pairs)
    (True, [(0, 0), (1, 1), (2, 2), (3, 3)])
    """
    results = sweep(prepared)
    scores = AUTO_RULES[prepared.config.auto_rule](prepared, results)
    lowest = min(scores)
    best = next(k for k, value in enumerate(scores) if value <= lowest + 1e-12)
    return replace(results[best], m_scan={float(r.m): float(s) for r, s in zip(results, scores)})
