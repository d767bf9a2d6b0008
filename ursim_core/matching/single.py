"""One run of the configured matcher at one fixed m: seeds, the planar matcher or a baseline, the score.

:func:`match_sweep` gives the runs at many values of m from one call of the planar matcher's C loop,
on two threads for building-sized pairs (:data:`THREADED_REGIONS`).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from ursim_core.matching.baselines import hungarian_match, vf2_match
from ursim_core.matching.config import MatchConfig
from ursim_core.matching.kernels import sweep_compiled
from ursim_core.matching.planar import hypothesis_cost, planar_match
from ursim_core.matching.results import MatchResult, Prepared, new_result

__all__ = [
    "seed_pairs",
    "SeedSelector",
    "seed_cap",
    "pair_cost_matrix",
    "planar_seeds",
    "match_at",
    "match_sweep",
    "THREADED_REGIONS",
]


def seed_pairs(c_matrix: np.ndarray, m: float, *, max_seeds: int | None = None) -> list[tuple[int, int]]:
    """All index pairs with ``c <= m``, sketch outer loop, metric inner loop.

    With ``max_seeds``, only the ``max_seeds`` pairs of lowest c are kept (ties by order),
    still returned in loop order.

    Examples
    --------
    >>> seed_pairs(np.array([[0.0, 0.2], [0.1, 0.5]]), 0.2)
    [(0, 0), (0, 1), (1, 0)]
    >>> seed_pairs(np.array([[0.0, 0.2], [0.1, 0.5]]), 0.2, max_seeds=2)
    [(0, 0), (1, 0)]
    """
    c_matrix = np.asarray(c_matrix)
    rows, cols = np.nonzero(c_matrix <= m)
    if max_seeds is not None and rows.size > max_seeds:
        keep = _lowest_in_order(c_matrix[rows, cols], max_seeds)
        rows, cols = rows[keep], cols[keep]
    return list(zip(rows.tolist(), cols.tolist()))


def _lowest_in_order(values: np.ndarray, count: int) -> np.ndarray:
    """Positions of the ``count`` lowest values, ties by position, in ascending position order.

    The same as ``np.sort(np.argsort(values, kind="stable")[:count])`` in O(n) instead of
    O(n log n): with millions of candidate seeds (thousands of regions, a large m) the sort
    cost seconds per m.
    """
    kth = np.partition(values, count - 1)[count - 1]
    below = np.flatnonzero(values < kth)
    tied = np.flatnonzero(values == kth)[: count - below.size]
    return np.sort(np.concatenate([below, tied]))


class SeedSelector:
    """The capped seeds of :func:`seed_pairs` at any m, from one pass over c.

    When more than ``max_seeds`` pairs have ``c <= m``, the kept ones are the ``max_seeds``
    lowest of the whole matrix (by value, ties by loop order), whatever m is; otherwise they are
    all pairs with ``c <= m``, which are the lowest ones too. So the ``max_seeds + 1`` lowest
    pairs, found once, give the seeds of every m: a sweep over m of a large pair reads its
    n1 x n2 matrix once instead of once per m.

    Examples
    --------
    >>> c = np.array([[0.0, 0.2], [0.1, 0.5]])
    >>> selector = SeedSelector(c, 2)
    >>> selector.at(0.2) == seed_pairs(c, 0.2, max_seeds=2), selector.at(0.05)
    (True, [(0, 0)])
    """

    def __init__(self, c_matrix: np.ndarray, max_seeds: int):
        c_matrix = np.asarray(c_matrix)
        self._c_matrix, self._max_seeds, self._columns = c_matrix, int(max_seeds), c_matrix.shape[1]
        flat = c_matrix.ravel()
        if flat.size <= self._max_seeds + 1:
            positions = np.arange(flat.size)
        else:
            positions = _lowest_in_order(flat, self._max_seeds + 1)
        order = positions[np.argsort(flat[positions], kind="stable")]
        self._order, self._values = order, flat[order]
        # NaN compares false with everything; the ordered shortcut does not hold then.
        self._exact = not np.isnan(self._values).any()
        # A sketch-sized pair's seeds are found at every m of many sweeps: as lists, bisect and a
        # sort of a few dozen ints cost a third of NumPy's calls (the same seeds).
        self._listed = (order.tolist(), self._values.tolist()) if order.size <= _LISTED_SEEDS else None

    @property
    def ordered(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The positions it keeps in the flattened c, sorted by value (ties by position), and
        their values; None when c has NaN (then :meth:`at` reads c itself)."""
        return (self._order, self._values) if self._exact else None

    def selected_counts(self, ms) -> list[int] | None:
        """``np.count_nonzero(c <= m)`` for every m of ``ms``, from the kept values when they are
        all of c (else None)."""
        if not self._exact or self._order.size != self._c_matrix.size:
            return None
        return np.searchsorted(self._values, np.asarray(ms, dtype=np.float64), side="right").tolist()

    def at(self, m: float) -> list[tuple[int, int]]:
        """``seed_pairs(c_matrix, m, max_seeds=max_seeds)``."""
        if not self._exact:
            return seed_pairs(self._c_matrix, m, max_seeds=self._max_seeds)
        if self._listed is not None:
            order, values = self._listed
            count = min(bisect.bisect_right(values, m), self._max_seeds)
            columns = self._columns
            return [divmod(position, columns) for position in sorted(order[:count])]
        count = min(int(np.searchsorted(self._values, m, side="right")), self._max_seeds)
        rows, cols = np.divmod(np.sort(self._order[:count]), self._columns)
        return list(zip(rows.tolist(), cols.tolist()))


#: :class:`SeedSelector` keeps the order of at most this many lowest pairs as Python lists.
_LISTED_SEEDS = 512


def seed_cap(max_seeds, n_sketch: int, n_metric: int) -> int | None:
    """Resolve ``MatchConfig.max_seeds`` for graphs of the given sizes.

    Examples
    --------
    >>> seed_cap("auto", 15, 8), seed_cap("auto", 1000, 1000), seed_cap(None, 5, 5)
    (6666, 100, None)
    """
    if max_seeds == "auto":
        return max(64, 100_000 // max(1, n_sketch, n_metric))
    return max_seeds


def pair_cost_matrix(config: MatchConfig, c_matrix: np.ndarray, m: float) -> np.ndarray | None:
    """Per-pair term of the hypothesis score for ``config.hypothesis_score`` (None for 'structure').

    Examples
    --------
    >>> pair_cost_matrix(MatchConfig(hypothesis_score="substitutions"), np.array([[0.1, 0.3]]), 0.2).tolist()
    [[0.0, 1.0]]
    """
    if config.hypothesis_score == "structure" or config.score_weight == 0:
        return None
    if config.hypothesis_score == "substitutions":
        return (np.asarray(c_matrix) > m).astype(np.float64)
    return np.asarray(c_matrix, dtype=np.float64)


def _constrained_costs(c_matrix: np.ndarray, m: float, constraints) -> np.ndarray:
    """``c`` for the Hungarian baseline under ``constraints``: a fixed pair costs less than
    anything (and nothing else in its row and column can be kept); forbidden pairs and excluded
    regions cost more than any m, so they are never kept."""
    if constraints is None:
        return c_matrix
    costs = np.array(c_matrix, dtype=np.float64)
    above = max(float(m), float(np.nanmax(costs, initial=0.0))) + 1.0
    for a, b in constraints.forbidden:
        costs[a, b] = above
    costs[list(constraints.excluded_first), :] = above
    costs[:, list(constraints.excluded_second)] = above
    for a, b in constraints.fixed:
        costs[a, :] = above
        costs[:, b] = above
        costs[a, b] = min(0.0, float(m))
    return costs


def _cost_of(prepared: Prepared, index_pairs, pair_costs, scored=None) -> tuple[float, float]:
    """The hypothesis score of ``index_pairs`` and its normalised value; ``scored``: that score as
    the planar matcher computed it (the same sums in the same order), not computed again."""
    first, second = prepared.sketch_planar, prepared.metric_planar
    total = first.n_vertices + second.n_vertices + len(first.edges) + len(second.edges)
    if not index_pairs:
        return math.inf, 1.0
    if scored is not None:
        cost = float(scored)
    else:
        cost = float(hypothesis_cost(first, second, index_pairs))
        if pair_costs is not None:
            cost += prepared.config.score_weight * float(sum(pair_costs[i, j] for i, j in index_pairs))
    return cost, (cost / total if total else 0.0)


def planar_seeds(prepared: Prepared, m: float, seed_selector: SeedSelector | None = None) -> list[tuple[int, int]]:
    """The planar matcher's seeds at m: :func:`seed_pairs` with the configured cap.

    ``seed_selector`` (see :func:`match_at`) gives the same seeds faster when its cap is the
    configured one.
    """
    c_matrix = prepared.c_matrix
    cap = seed_cap(prepared.config.max_seeds, *c_matrix.shape)
    if seed_selector is not None and cap is not None and seed_selector._max_seeds == cap:
        return seed_selector.at(m)
    return seed_pairs(c_matrix, m, max_seeds=cap)


def match_at(prepared: Prepared, m: float, *, seed_selector: SeedSelector | None = None) -> MatchResult:
    """Run the configured matcher at one fixed m.

    ``seed_selector``: a :class:`SeedSelector` of ``prepared.c_matrix`` and the configured
    seed cap, shared by the calls of a sweep over m (the same seeds, found faster).

    Examples
    --------
    >>> import networkx as nx
    >>> from ursim_core.matching.pipeline import prepare
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> sorted(match_at(prepare(g, g.copy()), 0.01).pairs)
    [(0, 0), (1, 1), (2, 2), (3, 3)]
    """
    config = prepared.config
    m = float(m)
    descriptors = prepared.descriptors
    c_matrix = prepared.c_matrix
    reasons = _notes_of(prepared)
    index_pairs: list = []
    scored = None
    seeds_count = 0
    hypotheses = 0
    pair_costs = pair_cost_matrix(config, c_matrix, m) if descriptors is not None else None
    constraints = prepared.index_constraints
    if descriptors is not None:
        if config.matcher == "planar":
            seeds = planar_seeds(prepared, m, seed_selector)
            seeds_count = len(seeds)
            if not seeds and not (constraints and constraints.fixed):
                reasons.append(f"no seeds: no pair of regions has c <= m = {m:g}")
            else:
                # Arrays, not nested lists: converting an n1 x n2 matrix costs seconds for
                # thousands of regions, and the planar matcher reads only a few of its cells.
                outcome = planar_match(
                    prepared.sketch_planar,
                    prepared.metric_planar,
                    np.asarray(c_matrix) <= m,
                    seeds=seeds,
                    rotation_search=config.rotation_search,
                    reflections=config.reflections,
                    pair_costs=pair_costs,
                    pair_cost_weight=config.score_weight,
                    constraints=constraints,
                )
                index_pairs = outcome.pairs
                hypotheses = outcome.hypotheses
                if constraints is None and math.isfinite(outcome.cost):
                    # The planar score is the hypothesis score with these pair costs and weight.
                    scored = outcome.cost
        elif config.matcher == "hungarian":
            index_pairs = hungarian_match(_constrained_costs(c_matrix, m, constraints), m)
            if not index_pairs:
                reasons.append(f"no assigned pair has c <= m = {m:g}")
        else:  # VF2: prepare() refuses constraints for it
            sketch_nodes, metric_nodes = prepared.sketch_planar.nodes, prepared.metric_planar.nodes
            found = vf2_match(prepared.sketch_graph, prepared.metric_graph, c_matrix, m, timeout=config.vf2_timeout)
            sketch_index = {n: i for i, n in enumerate(sketch_nodes)}
            metric_index = {n: i for i, n in enumerate(metric_nodes)}
            index_pairs = [(sketch_index[a], metric_index[b]) for a, b in found.pairs]
            if found.gave_up:
                reasons.append(found.gave_up)
            elif not index_pairs:
                reasons.append(f"no subgraph isomorphism with c <= m = {m:g}")
    cost, normalised = _cost_of(prepared, index_pairs, pair_costs, scored)
    return _result(prepared, m, index_pairs, cost, normalised, seeds_count, hypotheses, reasons)


def _notes_of(prepared: Prepared) -> list[str]:
    """The reasons every answer of ``prepared`` carries: its notes, and a missing anchor."""
    reasons = list(prepared.notes)
    descriptors = prepared.descriptors
    if prepared.config.variant in ("T2", "T4") and descriptors is not None and not descriptors.anchors:
        reasons.append("no anchors: anchor signatures are all zero, matching is structural only")
    return reasons


def _result(prepared: Prepared, m, index_pairs, cost, normalised, seeds_count, hypotheses, reasons) -> MatchResult:
    """The :class:`MatchResult` of index pairs found at m, in region ids, with the pair's anchors,
    unique regions and signatures (``prepared.answer_fields``, made once per preparation)."""
    sketch_nodes, metric_nodes = prepared.sketch_planar.nodes, prepared.metric_planar.nodes
    shared = prepared.answer_fields
    # new_result skips the frozen dataclass's __init__: a turned KTH sketch makes about 600 of
    # these (round 41). Each result gets lists and an m_scan of its own, as the constructor gave.
    return new_result(
        {
            **shared,
            "pairs": [(sketch_nodes[i], metric_nodes[j]) for i, j in index_pairs],
            "anchors": list(shared["anchors"]),
            "unique_sketch": list(shared["unique_sketch"]),
            "unique_metric": list(shared["unique_metric"]),
            "m": m,
            "cost": cost,
            "normalised_cost": normalised,
            "seeds_count": seeds_count,
            "hypotheses": hypotheses,
            "reason": "; ".join(dict.fromkeys(reasons)),
            "m_scan": {},
        }
    )


#: Sweeps of pairs with at least this many regions in either map share their values of m between
#: two threads of the C loop (:func:`~ursim_core.matching.kernels.sweep_compiled`; each thread
#: takes the next m, the same results). A value of m costs about 0.13 s at 8000 px (4250 regions),
#: a sketch-sized one microseconds. The 8000 px pair's sweep (19 distinct m) in C took 2.6 s on one
#: thread and 1.5 s on two (12.3 s in Python); ``ursim match`` of the pair, interleaved x3 on a
#: shared machine: 21.8 / 25.2 / 24.8 s on two threads, 23.0 / 30.0 / 28.2 s on one, and 26.3 /
#: 23.5 / 24.1 s with the helper process that shared the values of m before (each side calling C).
THREADED_REGIONS = 900


def match_sweep(prepared: Prepared, ms, seed_selector: SeedSelector | None) -> list[MatchResult] | None:
    """``[match_at(prepared, m, seed_selector=seed_selector) for m in ms]`` from one call of the
    planar matcher's C loop (:func:`~ursim_core.matching.kernels.sweep_compiled`), or None when
    it does not take the case: another matcher, constraints, no selector with the configured
    cap, NaN in c, or no C module.

    The same results, field by field: a test compares them. A sweep of a sketch-sized pair spent
    more time in the Python around each m's C call than in the calls; a building-sized one runs on
    two threads (:data:`THREADED_REGIONS`).
    """
    config, descriptors = prepared.config, prepared.descriptors
    if config.matcher != "planar" or descriptors is None or seed_selector is None or not ms:
        return None
    c_matrix = prepared.c_matrix
    ordered = seed_selector.ordered
    cap = seed_cap(config.max_seeds, *c_matrix.shape)
    if ordered is None or cap != seed_selector._max_seeds or prepared.index_constraints is not None:
        return None
    weighted = config.hypothesis_score != "structure" and config.score_weight != 0
    outcomes = sweep_compiled(
        prepared.sketch_planar, prepared.metric_planar, c_matrix, *ordered, cap, ms,
        score=config.hypothesis_score, weight=config.score_weight if weighted else 0.0,
        rotation_search=config.rotation_search, reflections=config.reflections, threads=_sweep_threads(c_matrix),
    )  # fmt: skip
    if outcomes is None:
        return None
    notes = _notes_of(prepared)
    results = []
    for m, (index_pairs, scored, _, hypotheses, _, seeds_count) in zip(ms, outcomes):
        m = float(m)
        reasons = notes if seeds_count else [*notes, f"no seeds: no pair of regions has c <= m = {m:g}"]
        cost, normalised = _cost_of(prepared, index_pairs, None, scored)
        results.append(_result(prepared, m, index_pairs, cost, normalised, seeds_count, hypotheses, reasons))
    return results


def _sweep_threads(c_matrix: np.ndarray) -> int:
    """Threads of the C loop for a sweep of a pair with this c matrix (see :data:`THREADED_REGIONS`):
    two at most, and no more than this process may use (:func:`ursim_core.cpus.usable_cpus`: a
    worker of ``ursim evaluate``'s or ``match-batch``'s pool is told its share)."""
    from ursim_core.cpus import usable_cpus

    return min(2, usable_cpus()) if max(c_matrix.shape) >= THREADED_REGIONS else 1
