"""Planar seed-and-expand graph matching (Mielle et al. 2019, Algorithm 1).

The algorithm follows the released code (``original_code.md`` §1.10 and §1.12) step by step:

1. Every seed pair (sketch region, metric region) becomes a one-pair hypothesis first.
2. Seeds are then taken in order. For a seed ``(s, s')`` the cyclic neighbour lists of ``s`` and
   ``s'`` are aligned by normalised edit distance over rotations of the sketch list
   (:func:`~ursim_core.matching.edit_distance.cyclic_align`; ``rotation_search="first"`` reproduces
   the released integer-truncation bug that always keeps offset 0). Every aligned pair (``n`` *and*
   ``s`` operations) is queued and marked seen; a seed that equals a queued pair is consumed.
3. Queued pairs are popped in FIFO order and appended to the hypothesis. For a popped ``(v, v')``
   the neighbours of ``v`` already matched in the hypothesis to neighbours of ``v'`` are *locks*;
   consecutive locks (in ``v``'s cyclic order) cut both neighbour lists into arcs (elements
   strictly between the two locks, walking forward; with one lock, all the other neighbours after
   it), each pair of arcs is aligned by edit distance, and every aligned pair whose two regions are
   both unseen is queued (consuming the identical seed if there is one). No lock, no expansion.
4. A hypothesis' cost is
   ``(#unmatched in G1 + #unmatched in G2) + (#edges of G1 with an unmatched end + same in G2)
   + |#edges among matched in G1 - #edges among matched in G2|``.
   The best hypothesis is the one with the lowest cost; ties go to the earliest one (the
   one-pair hypotheses in seed order come first, then expansions in seed order).
   Option (``pair_costs``, ``pair_cost_weight`` = w): add ``w * sum of pair_costs[v][v']`` over
   the hypothesis' pairs. With ``pair_costs = (c > m)`` and w = 1 this is the paper's "replace: 1"
   edit cost, which the released code computes but leaves at 0; with ``pair_costs = c`` it is the
   signature-aware score of the recommended configuration (see ``ursim_core.matching.auto_m``).

Neighbour order: the released code sorts a region's neighbours by the angle
``atan2(n - v) - atan2(first - v)`` in [0, 2 pi) of the region centroids in image coordinates
(rows down, so the order is clockwise on screen), where ``first`` is the first boost out-edge
(edge insertion order, which depends on MAORIS internals). Here ``first`` is the neighbour with
the smallest region id, which is deterministic; only the ``rotation_search="first"`` mode depends
on that choice. Ties in angle keep region-id order.

Reflections (``reflections=True``, not in the released code) also try the mirrored sketch list
at the seed; a hypothesis seeded with a mirrored alignment walks every sketch neighbour list
backwards during expansion, so mirror-drawn sketches expand consistently.

Complexity: seeds are all pairs with ``c <= m`` (up to ``n1 * n2``); each expansion costs
O(k * d^2) for a hypothesis of k pairs and degree d, so the worst case is O(n1 n2 k d^2).
Consumed seeds are skipped, which in practice removes most of them on consistent graphs.
:func:`planar_match` takes the seed list from the caller, which may cap it for large graphs
(see ``ursim_core.matching.MatchConfig.max_seeds``).

Speed: the common case (no constraints, no alternatives kept) runs the same loop in C, graphs of
any size (:mod:`ursim_core.matching.kernels`; the same answers, which tests check against this
code, building-sized graphs included). The code here runs the rest (a person's review of a
building's pair is matched here, with its long alignments in numba), and everything where no C
compiler is.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import networkx as nx
import numpy as np

from ursim_core.matching.alignment_memo import seed_alignment
from ursim_core.matching.arcs import expand_locked
from ursim_core.matching.edit_distance import COMPILED_CELLS
from ursim_core.matching.kernels import match_compiled

__all__ = ["PlanarGraph", "PlanarResult", "planar_graph", "cyclic_neighbours", "hypothesis_cost", "planar_match"]


@dataclass(frozen=True, eq=False)
class PlanarGraph:
    """Index form of a region graph for the matcher.

    Attributes
    ----------
    nodes : list
        Region ids; index ``i`` stands for ``nodes[i]``.
    neighbours : list of list of int
        Cyclic neighbour order of each vertex (indices).
    edges : list of (int, int)
        Undirected edges as index pairs, each once.

    Examples
    --------
    >>> g = nx.star_graph([10, 20, 30, 40])  # hall 10 opens onto rooms 20 (left), 30 (below), 40 (right)
    >>> nx.set_node_attributes(g, {10: (5, 5), 20: (5, 0), 30: (10, 5), 40: (5, 10)}, "centroid")
    >>> p = planar_graph(g)
    >>> p.nodes, p.neighbours[0], p.edges  # indices: 0 is region 10; its neighbours in angular order
    ([10, 20, 30, 40], [1, 3, 2], [(0, 1), (0, 2), (0, 3)])
    >>> p.n_vertices, p.branching
    (4, [True, False, False, False])
    """

    nodes: list
    neighbours: list
    edges: list

    @property
    def n_vertices(self) -> int:
        return len(self.nodes)

    # What every planar match derives from the graph, computed once per graph: a sweep matches
    # the same two graphs at 20 values of m, and a turned sketch in several orientations.
    @cached_property
    def neighbour_sets(self) -> list[set]:
        return [set(order) for order in self.neighbours]

    @cached_property
    def positions(self) -> list[dict]:
        """The position of every neighbour in each vertex's cyclic order."""
        return [{vertex: k for k, vertex in enumerate(order)} for order in self.neighbours]

    @cached_property
    def reversed_neighbours(self) -> list[list[int]]:
        return [order[::-1] for order in self.neighbours]

    @cached_property
    def branching(self) -> list[bool]:
        """Vertices with more than one neighbour (the only ones whose arcs can hold pairs)."""
        return [len(order) > 1 for order in self.neighbours]

    @cached_property
    def adjacency_ends(self) -> tuple[np.ndarray, np.ndarray]:
        return _adjacency_ends(self.neighbour_sets)

    @cached_property
    def flat_orders(self) -> tuple[np.ndarray, np.ndarray, int]:
        """The cyclic orders as offsets and one flat int32 array, and the longest order's length
        (what the C loop reads, :mod:`ursim_core.matching.kernels`)."""
        lengths = [len(order) for order in self.neighbours]
        offsets = np.zeros(len(lengths) + 1, dtype=np.int32)
        np.cumsum(lengths, out=offsets[1:])
        flat = np.fromiter((v for order in self.neighbours for v in order), dtype=np.int32, count=int(offsets[-1]))
        return offsets, flat, max(lengths, default=0)


@dataclass(frozen=True)
class PlanarResult:
    """Outcome of :func:`planar_match`.

    Attributes
    ----------
    pairs : list of (int, int)
        Best hypothesis as index pairs (sketch index, metric index), in expansion order.
    cost : float
        Its score (see the module docstring): the structural cost plus the weighted pair
        costs when given; ``inf`` when there was no seed.
    structural_cost : float
        Its structural cost alone (the released code's score).
    hypotheses : int
        Number of hypotheses scored (one-pair ones included).
    seeds_expanded : int
        Seeds that started an expansion (the others were consumed by earlier ones).
    alternatives : list of (cost, pairs)
        Every expanded hypothesis in creation order, when ``keep_alternatives=True``.
    """

    pairs: list
    cost: float
    hypotheses: int
    seeds_expanded: int
    alternatives: list = field(default_factory=list)
    structural_cost: float = math.inf


def cyclic_neighbours(graph: nx.Graph, nodes: Sequence) -> list[list[int]]:
    """Neighbours of every vertex in angular order around its centroid.

    Parameters
    ----------
    graph : networkx.Graph
        Nodes carry ``centroid`` = (row, col).
    nodes : sequence
        Index order of the vertices.

    Returns
    -------
    list of list of int
        For vertex i, indices of its neighbours sorted by the angle relative to the
        neighbour with the smallest region id (see the module docstring).

    Examples
    --------
    >>> g = nx.Graph()
    >>> g.add_node(0, centroid=(0.0, 0.0)); g.add_node(1, centroid=(0.0, 1.0))
    >>> g.add_node(2, centroid=(1.0, 0.0)); g.add_node(3, centroid=(-1.0, 0.0))
    >>> g.add_edges_from([(0, 1), (0, 2), (0, 3)])
    >>> cyclic_neighbours(g, [0, 1, 2, 3])[0]
    [1, 2, 3]
    """
    index = {node: i for i, node in enumerate(nodes)}
    orders = []
    for node in nodes:
        adjacent = sorted((n for n in graph.neighbors(node) if n != node), key=lambda n: index[n])
        if len(adjacent) <= 1:
            orders.append([index[n] for n in adjacent])
            continue
        row, col = graph.nodes[node]["centroid"]

        def direction(other):
            other_row, other_col = graph.nodes[other]["centroid"]
            return math.atan2(other_row - row, other_col - col)

        reference = direction(adjacent[0])
        angles = [(direction(n) - reference) % (2.0 * math.pi) for n in adjacent]
        ordered = sorted(range(len(adjacent)), key=lambda k: angles[k])
        orders.append([index[adjacent[k]] for k in ordered])
    return orders


def planar_graph(graph: nx.Graph, *, nodes: Sequence | None = None) -> PlanarGraph:
    """Build the :class:`PlanarGraph` of a region graph (nodes in ascending id order by default).

    Examples
    --------
    >>> g = nx.path_graph(3); nx.set_node_attributes(g, {0: (0, 0), 1: (0, 5), 2: (0, 9)}, "centroid")
    >>> p = planar_graph(g)
    >>> p.neighbours, p.edges
    ([[1], [0, 2], [1]], [(0, 1), (1, 2)])
    """
    nodes = sorted(graph.nodes) if nodes is None else list(nodes)
    index = {node: i for i, node in enumerate(nodes)}
    edges = sorted({(min(index[a], index[b]), max(index[a], index[b])) for a, b in graph.edges() if a != b})
    return PlanarGraph(nodes=nodes, neighbours=cyclic_neighbours(graph, nodes), edges=edges)


def hypothesis_cost(first: PlanarGraph, second: PlanarGraph, pairs: Sequence[tuple[int, int]]) -> int:
    """Released-code cost of a hypothesis (original_code.md §1.12).

    Examples
    --------
    >>> p = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1], [0, 2], [1]], edges=[(0, 1), (1, 2)])
    >>> hypothesis_cost(p, p, [(0, 0), (1, 1), (2, 2)]), hypothesis_cost(p, p, [(0, 0)])
    (0, 8)
    """
    matched_first = {a for a, _ in pairs}
    matched_second = {b for _, b in pairs}
    inner_first = sum(1 for a, b in first.edges if a in matched_first and b in matched_first)
    inner_second = sum(1 for a, b in second.edges if a in matched_second and b in matched_second)
    return (
        (first.n_vertices - len(matched_first))
        + (second.n_vertices - len(matched_second))
        + (len(first.edges) - inner_first)
        + (len(second.edges) - inner_second)
        + abs(inner_first - inner_second)
    )


def _adjacency_ends(neighbour_sets) -> tuple[np.ndarray, np.ndarray]:
    """Both ends of every (vertex, neighbour) entry of the neighbour sets, as two index arrays."""
    sources = [vertex for vertex, neighbours in enumerate(neighbour_sets) for _ in neighbours]
    targets = [neighbour for neighbours in neighbour_sets for neighbour in neighbours]
    return np.asarray(sources, dtype=np.intp), np.asarray(targets, dtype=np.intp)


#: Graphs with at most this many (vertex, neighbour) entries count the edges of a hypothesis in
#: Python (:func:`_inner_edges`): for a sketch-sized graph NumPy's call overhead costs more than
#: the count.
_LISTED_ENTRIES = 256


def _inner_edges(ends, n_vertices: int, vertices, neighbour_sets) -> int:
    """Edges between two of ``vertices``: entries with both ends in them, each edge seen twice.

    The count of ``sum(1 for v in vertices for n in neighbours[v] if n in vertices) // 2``:
    computed so for small graphs, and for larger ones by one pass of NumPy over the entries
    (``ends``) instead of Python over thousands of matched regions.
    """
    sources, targets = ends
    if sources.size <= _LISTED_ENTRIES:
        inside = set(vertices)
        return sum(1 for vertex in inside for neighbour in neighbour_sets[vertex] if neighbour in inside) // 2
    inside = np.zeros(n_vertices, dtype=np.bool_)
    inside[np.fromiter(vertices, dtype=np.intp)] = True
    return int(np.count_nonzero(inside[sources] & inside[targets])) // 2


#: Pair-cost and "same" matrices of at most this many cells are read as nested lists by
#: :func:`planar_match` (a KTH pair has about a hundred); larger ones are indexed as arrays (no
#: n1 x n2 lists).
_LISTED_COSTS = 4096


#: The pairs the fixed pairs imply when there are none (shared: never written).
_NOTHING: frozenset = frozenset()


def planar_match(
    first: PlanarGraph,
    second: PlanarGraph,
    same: Sequence[Sequence[bool]] | np.ndarray,
    *,
    seeds: Sequence[tuple[int, int]] | None = None,
    rotation_search: str = "min",
    reflections: bool = False,
    keep_alternatives: bool = False,
    pair_costs: Sequence[Sequence[float]] | None = None,
    pair_cost_weight: float = 0.0,
    constraints=None,
) -> PlanarResult:
    """Algorithm 1: seed-and-expand planar matching of two region graphs.

    Parameters
    ----------
    first, second : PlanarGraph
        Sketch and metric graphs (index form, see :func:`planar_graph`).
    same : 2-D sequence of bool or NumPy bool array
        ``same[i][j]`` is True when sketch vertex i and metric vertex j compare equal
        (``c <= m``). An array (what :func:`~ursim_core.matching.single.match_at` passes)
        lets long neighbour lists be aligned by the compiled kernel.
    seeds : sequence of (int, int), optional
        Seed pairs in processing order. Default: every pair with ``same[i][j]``,
        sketch index outer loop, metric index inner loop (as the released code).
    rotation_search : {'min', 'first'}
        See :func:`~ursim_core.matching.edit_distance.cyclic_align`.
    reflections : bool
        Also try mirrored neighbour orders at the seed.
    keep_alternatives : bool
        Also return every expanded hypothesis (for inspection and for rules that
        re-rank them).
    pair_costs : 2-D sequence of float or NumPy array, optional
        Cost of matching sketch vertex i to metric vertex j, added to the score with
        weight ``pair_cost_weight`` (see the module docstring).
    pair_cost_weight : float
    constraints : IndexConstraints, optional
        :class:`~ursim_core.matching.constraints.IndexConstraints`: fixed pairs are in every
        hypothesis from the start, as locks, and are expanded from after the seed's own pairs
        (the one-pair hypotheses are not scored); with no seed left, the first fixed pair is the
        seed. Forbidden pairs and excluded vertices are never paired.

    Returns
    -------
    PlanarResult

    Examples
    --------
    >>> p = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1], [0, 2], [1]], edges=[(0, 1), (1, 2)])
    >>> same = [[True, False, True], [False, True, False], [True, False, True]]
    >>> result = planar_match(p, p, same)
    >>> sorted(result.pairs), result.cost
    ([(0, 0), (1, 1), (2, 2)], 0)
    """
    if seeds is None and isinstance(same, np.ndarray):
        seeds = list(zip(*(axis.tolist() for axis in np.nonzero(same))))
    elif seeds is None:
        seeds = [(i, j) for i in range(first.n_vertices) for j in range(second.n_vertices) if same[i][j]]
    else:
        seeds = list(seeds)
    fixed: tuple = ()
    forbidden: frozenset = frozenset()
    if constraints is not None:
        fixed, forbidden = tuple(constraints.fixed), constraints.forbidden
        # Vertices no seed or expansion may pair: the excluded ones and those of the fixed pairs.
        closed_first = constraints.excluded_first | {a for a, _ in fixed}
        closed_second = constraints.excluded_second | {b for _, b in fixed}
        seeds = [
            seed
            for seed in seeds
            if seed[0] not in closed_first and seed[1] not in closed_second and seed not in forbidden
        ]
        if fixed and not seeds:
            seeds = [fixed[0]]  # the fixed pairs and what they imply, with no seed of their own
    if not seeds:
        return PlanarResult(pairs=[], cost=math.inf, hypotheses=0, seeds_expanded=0)
    if constraints is None and not keep_alternatives and rotation_search in ("min", "first"):
        # The same loop in C (matching.kernels), when it is built and takes graphs of this size.
        compiled = match_compiled(
            first, second, same, seeds, rotation_search=rotation_search, reflections=reflections,
            pair_costs=pair_costs, pair_cost_weight=pair_cost_weight,
        )  # fmt: skip
        if compiled is not None:
            pairs, cost, structure, hypotheses, expanded = compiled
            return PlanarResult(pairs, cost, hypotheses, expanded, structural_cost=structure)
    n_first, n_second = first.n_vertices, second.n_vertices
    edges_first, edges_second = len(first.edges), len(second.edges)
    weighted = pair_costs is not None and pair_cost_weight != 0

    if weighted and isinstance(pair_costs, np.ndarray) and pair_costs.size > _LISTED_COSTS:
        cost_array = pair_costs

        def pair_costs_of(pairs):
            # The same values in the same order as the nested-list form: the same float sum.
            return cost_array[[a for a, _ in pairs], [b for _, b in pairs]].tolist()

    else:
        if weighted and isinstance(pair_costs, np.ndarray):
            # A sketch-sized matrix read as lists: every seed and hypothesis is scored, and
            # indexing lists costs a fraction of NumPy's per-call overhead (the same floats).
            pair_costs = pair_costs.tolist()

        def pair_costs_of(pairs):
            return [pair_costs[a][b] for a, b in pairs]

    def pair_term(pairs):
        return pair_cost_weight * sum(pair_costs_of(pairs)) if weighted else 0

    if isinstance(same, np.ndarray) and same.size <= _LISTED_COSTS:
        longest_first = max(map(len, first.neighbours), default=0)
        longest_second = max(map(len, second.neighbours), default=0)
        if longest_first * longest_second < COMPILED_CELLS:
            # A sketch-sized "same" read as lists: every alignment reads a block of it, and
            # indexing lists costs less than a NumPy block per call. No alignment is long
            # enough for the compiled kernel (which needs the array), so the answers are the same.
            same = same.tolist()

    # Every one-pair hypothesis has the same structural cost; they come first, so the first seed
    # wins among them (the first of the lowest pair cost when pair costs are used).
    single_structure = (n_first - 1) + (n_second - 1) + edges_first + edges_second
    best_seed = min(seeds, key=lambda seed: pair_term([seed])) if weighted else seeds[0]
    best_pairs = [best_seed]
    best_structure = single_structure
    best_cost = single_structure + pair_term(best_pairs)
    hypotheses = len(seeds)
    if fixed:
        # No hypothesis goes without the fixed pairs: the one-pair hypotheses are not scored,
        # every seed's expansion (the first fixed pair's own included) is.
        best_pairs, best_cost, best_structure, hypotheses = list(fixed), math.inf, math.inf, 0
    consumed = set()
    seeds_expanded = 0
    first_sets, second_sets = first.neighbour_sets, second.neighbour_sets
    second_positions = second.positions
    first_ends, second_ends = first.adjacency_ends, second.adjacency_ends
    reversed_first = first.reversed_neighbours
    second_neighbours = second.neighbours
    branching_first, branching_second = first.branching, second.branching
    arc_cache: dict = {}
    packed: dict = {}
    alternatives: list = []
    for seed in seeds:
        if seed in consumed:
            continue
        consumed.add(seed)
        seeds_expanded += 1
        seed_first, seed_second = seed
        reflected, seed_pairs = seed_alignment(
            first.neighbours[seed_first],
            second.neighbours[seed_second],
            same,
            rotation_search=rotation_search,
            reflections=reflections,
        )
        first_orders = reversed_first if reflected else first.neighbours
        seen_first = {seed_first}
        seen_second = {seed_second}
        queue = deque()
        matched = {seed_first: seed_second}
        pairs = [seed]
        if constraints is not None:
            seen_first |= closed_first
            seen_second |= closed_second
            if fixed:
                # The fixed pairs are locks from the start, and are in the hypothesis already.
                matched.update(fixed)
                pairs = list(fixed) + ([] if seed in fixed else [seed])
        for pair in seed_pairs:
            if pair[0] in seen_first or pair[1] in seen_second or pair in forbidden:
                continue
            queue.append(pair)
            seen_first.add(pair[0])
            seen_second.add(pair[1])
            consumed.add(pair)
        # The other fixed pairs are expanded from (between their locks, as any pair of the
        # hypothesis) after the seed's own pairs; they are not aligned as seeds, which would put
        # every unlocked rotation of their neighbour lists in every hypothesis.
        # What the fixed pairs imply is in every hypothesis, so it consumes no seed: a seed that
        # one hypothesis reached only through them still starts a hypothesis of its own.
        implied = _NOTHING
        if fixed:
            queue.extend(pair for pair in fixed if pair != seed)
            implied = set(fixed)
        # The loop below runs for every pair of every hypothesis (hundreds of thousands per m
        # on a building map): bound methods and the pair tuples are reused, not looked up or
        # rebuilt each time.
        pop, push, keep = queue.popleft, queue.append, pairs.append
        see_first, see_second, consume = seen_first.add, seen_second.add, consumed.add
        while queue:
            pair = pop()
            vertex, partner = pair
            if vertex not in matched:  # a fixed pair is in the hypothesis from the start
                keep(pair)
                matched[vertex] = partner
            if not branching_first[vertex] or not branching_second[partner]:
                continue  # one neighbour on either side: every arc between locks is empty
            from_fixed = implied and pair in implied
            for candidate in expand_locked(
                first_orders[vertex],
                second_neighbours[partner],
                matched,
                second_positions[partner],
                same,
                arc_cache,
                packed,
                (vertex, partner, reflected),
            ):
                a, b = candidate
                if a not in seen_first and b not in seen_second and not (forbidden and candidate in forbidden):
                    push(candidate)
                    see_first(a)
                    see_second(b)
                    if from_fixed:
                        implied.add(candidate)
                    else:
                        consume(candidate)
        hypotheses += 1
        inner_first = _inner_edges(first_ends, n_first, matched.keys(), first_sets)
        inner_second = _inner_edges(second_ends, n_second, matched.values(), second_sets)
        structure = (
            (n_first - len(pairs))
            + (n_second - len(pairs))
            + (edges_first - inner_first)
            + (edges_second - inner_second)
            + abs(inner_first - inner_second)
        )
        cost = structure + pair_term(pairs)
        if keep_alternatives:
            alternatives.append((cost, pairs))
        # A small tolerance so that float sums of pair costs do not break the earliest-wins tie rule.
        if cost < best_cost - 1e-12:
            best_cost, best_pairs, best_structure = cost, pairs, structure
    return PlanarResult(
        pairs=best_pairs,
        cost=best_cost,
        hypotheses=hypotheses,
        seeds_expanded=seeds_expanded,
        alternatives=alternatives,
        structural_cost=best_structure,
    )
