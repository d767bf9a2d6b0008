"""Automatic choice of the threshold m per map pair (``MatchConfig(m="auto")``, the default).

The paper names the choice of m as future work: it reports F1 with the best m *per map* (an
oracle that needs the ground truth) and shows that one fixed m for all maps is clearly worse.

Rule ``"score"`` (default)
    Run the matcher at every m of ``config.m_grid`` (0, 0.025, ..., 0.475) and keep the result whose
    hypothesis score, normalised by the size of the problem ``n1 + n2 + e1 + e2``, is the lowest;
    ties go to the smallest m. With the default ``hypothesis_score="signature"`` the score is
    ``structural cost + w * sum of c over the matched pairs`` (w = ``score_weight`` = 8), so the rule
    is: among all hypotheses generated at any m, pick the one that explains most of both graphs
    (structural cost) with the most similar regions (sum of c). m only decides which seeds and
    which alignments are generated. It reads nothing but the two maps.
Rule ``"structure"``
    The same with the structural cost alone (the released code's score). Kept for comparison: it
    always prefers large, structurally complete but wrong hypotheses.

Evidence (18 KTH sketches x 2 annotators, MAORIS "default" preset for both maps, maps binarised
at > 250, correct scoring; mean F1 as malcolm / vasiliki; ``ursim evaluate`` on
``ursim_kth_sketches`` with the options named):

====================================================  ===========  ===========  ===========
configuration                                         oracle m     best fixed m auto m
====================================================  ===========  ===========  ===========
``--paper`` (T4, structure + substitutions)           .68 pooled   .58 pooled   .52 pooled
``--released --legacy-scoring fnfix`` (faithfulness)  .53 / .54    .47 / .46    --
**default** ``MatchConfig()``                         .67 / .73    .63 / .70    **.65 / .71**
====================================================  ===========  ===========  ===========

The released C++ measured on the same data: oracle .568 / .562, best fixed m .487 / .475
(released_code_results.md); human vs human on our segmentation: .79 / .76.

Hyper-parameters: beta = ``position_weight`` = 2 and w = ``score_weight`` = 8 were chosen on
data the KTH figures do not contain: generated pairs with exactly known ground truth
(``ursim_core.synth.make_pair``, seeds 0-11). With the generator as it was then, (2, 8) scored mean
F1 .897 against .801 for the earlier (0.5, 4) and .967 for (2, 16); with the current generator
(bends, crossings, dropped dead ends) .996 against .951 and .996. On KTH the three lie on a flat
plateau (.677, .659 and .629 mean of the two annotators), so (2, 8) was kept as the setting good on
both; an earlier leave-one-sketch-out study on KTH alone (beta in .25..3, w in 2..6) found held-out
F1 between .61 and .65: 18 sketches are too few to tune more than a couple of numbers on.
"""

from __future__ import annotations

import numpy as np

from ursim_core.matching.config import AUTO_RULE_NAMES
from ursim_core.matching.results import replaced

__all__ = ["AUTO_RULES", "choose_m", "chosen_of", "matched_sweep", "sweep"]


def sweep(prepared, grid=None, *, progress=None, known=None) -> list:
    """Match at every m of the grid (``config.m_grid`` by default), in grid order.

    ``progress(fraction, message)``, when given, is called after each m (for progress bars).

    Values of m that select exactly the same pairs as the previous one (same "same" relation)
    reuse its result, with ``m`` updated: the matcher would return the same answer.

    ``known`` maps values of m to results already matched at them for this preparation (the
    ``matched`` of :func:`matched_sweep` over another grid): an m the sweep would match is taken
    from it instead. The orientations of a sketch are screened on every second m; the few kept
    are then swept over the whole grid, and half of it is already known.

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
    return matched_sweep(prepared, grid, progress=progress, known=known)[0]


def matched_sweep(prepared, grid=None, *, progress=None, known=None) -> tuple[list, dict]:
    """:func:`sweep`, and the results it matched (not reused from the previous m), by m.

    The planar matcher's values of m are matched in one call of its C loop when it takes them
    (:func:`~ursim_core.matching.single.match_sweep`, on two threads for building-sized pairs),
    else one by one (:func:`~ursim_core.matching.single.match_at`).
    """
    from ursim_core.matching.single import SeedSelector, match_at, match_sweep, seed_cap

    grid = prepared.config.m_grid if grid is None else grid
    known = known or {}
    matched: dict[float, object] = {}
    c_matrix = prepared.c_matrix
    selector = None
    cap = seed_cap(prepared.config.max_seeds, *c_matrix.shape)
    if prepared.config.matcher == "planar" and prepared.descriptors is not None and cap is not None and len(grid) > 1:
        selector = SeedSelector(c_matrix, cap)
    # Two values of m select the same pairs when as many values of c are <= each (the pairs with
    # c <= m grow with m): counted, not compared mask by mask; the later one reuses the result.
    selected = selector.selected_counts(grid) if selector is not None else None
    if selected is None:
        selected = [np.count_nonzero(c_matrix <= float(m)) for m in grid]
    fresh = [index == 0 or selected[index] != selected[index - 1] for index in range(len(grid))]
    # match_at reads no option of the grid: a result found at m under another grid is this
    # sweep's, but for the options it records.
    to_match = [float(m) for m, new in zip(grid, fresh) if new and known.get(float(m)) is None]
    swept = match_sweep(prepared, to_match, selector) if len(to_match) > 1 else None
    found = dict(zip(to_match, swept)) if swept is not None else {}
    results = []
    for index, m in enumerate(grid, start=1):
        m = float(m)
        if not fresh[index - 1]:
            results.append(replaced(results[-1], m=m))
        else:
            earlier = known.get(m)
            if earlier is not None:
                result = replaced(earlier, config=prepared.config)
            else:
                result = found.get(m) or match_at(prepared, m, seed_selector=selector)
            matched[m] = result
            results.append(result)
        if progress is not None:
            progress(index / len(grid), f"matching at m = {m:.3f}")
    return results, matched


def _rule_score(prepared, results) -> list[float]:
    """Normalised hypothesis score of each result (1 when nothing was matched)."""
    return [r.normalised_cost for r in results]


def _rule_structure(prepared, results) -> list[float]:
    """Normalised structural cost alone."""
    from ursim_core.matching.planar import hypothesis_cost

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
assert tuple(AUTO_RULES) == AUTO_RULE_NAMES, "config.AUTO_RULE_NAMES must list the rules defined here"


def choose_m(prepared, *, progress=None, known=None):
    """Pick m over ``config.m_grid`` with ``config.auto_rule``; return that m's MatchResult.

    ``progress(fraction, message)`` and ``known`` are passed to :func:`sweep`.

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
    return chosen_of(prepared, sweep(prepared, progress=progress, known=known))


def chosen_of(prepared, results):
    """The result of a sweep that ``config.auto_rule`` picks, with ``m_scan`` (see :func:`choose_m`)."""
    scores = AUTO_RULES[prepared.config.auto_rule](prepared, results)
    lowest = min(scores)
    best = next(k for k, value in enumerate(scores) if value <= lowest + 1e-12)
    return replaced(results[best], m_scan={float(r.m): float(s) for r, s in zip(results, scores)})
