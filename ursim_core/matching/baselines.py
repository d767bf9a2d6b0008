"""Baseline matchers of the paper's Table 1: Hungarian on signatures and VF2 subgraph isomorphism.

Both work on the same ``c`` matrix as the planar matcher (``c(v, v')`` = mean absolute signature
difference), so every descriptor variant (T1-T4, baseline types) can be paired with every matcher.

- :func:`hungarian_match`: ``scipy.optimize.linear_sum_assignment`` on ``c`` (rectangular: every
  vertex of the smaller graph is assigned), then only pairs with ``c <= m`` are kept.
- :func:`vf2_match`: ``networkx`` VF2 (``GraphMatcher``) node-induced subgraph isomorphism of the
  graph with fewer vertices into the other one, vertices compatible when ``c <= m``; the first
  isomorphism found is returned. VF2 is exponential in the worst case, so the search is guarded by
  a wall-clock budget (``timeout`` seconds, checked at every vertex-compatibility test) and by
  ``max_vertices``; when it gives up, the result is empty and ``gave_up`` says why.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import networkx as nx
import numpy as np

__all__ = ["hungarian_match", "vf2_match", "Vf2Result"]


def hungarian_match(c_matrix: np.ndarray, m: float) -> list[tuple[int, int]]:
    """Minimum-cost assignment on ``c``, keeping the pairs with ``c <= m``.

    Parameters
    ----------
    c_matrix : ndarray, shape (n_sketch, n_metric)
    m : float

    Returns
    -------
    list of (row, col)
        Index pairs sorted by row.

    Examples
    --------
    >>> c = np.array([[0.0, 0.5], [0.4, 0.3], [0.1, 0.9]])
    >>> hungarian_match(c, 0.35)
    [(0, 0), (1, 1)]
    >>> hungarian_match(c, 0.2)
    [(0, 0)]
    """
    c_matrix = np.asarray(c_matrix, dtype=np.float64)
    if c_matrix.size == 0:
        return []
    from ursim_core.matching.lsap import linear_sum_assignment

    rows, cols = linear_sum_assignment(c_matrix)
    return [(int(r), int(k)) for r, k in zip(rows, cols) if c_matrix[r, k] <= m]


class _OutOfTime(Exception):
    pass


@dataclass(frozen=True)
class Vf2Result:
    """Outcome of :func:`vf2_match`.

    Attributes
    ----------
    pairs : list of (sketch_region, metric_region)
        Empty when no isomorphism exists or the search gave up.
    gave_up : str
        Empty, or why the search stopped (time budget, size cap).
    """

    pairs: list
    gave_up: str = ""


def vf2_match(
    sketch_graph: nx.Graph,
    metric_graph: nx.Graph,
    c_matrix: np.ndarray,
    m: float,
    *,
    sketch_nodes=None,
    metric_nodes=None,
    timeout: float = 2.0,
    max_vertices: int = 200,
) -> Vf2Result:
    """VF2 node-induced subgraph isomorphism with vertex compatibility ``c <= m``.

    The graph with fewer vertices (the sketch on ties) is searched for inside the
    other one; the first isomorphism networkx finds is returned.

    Parameters
    ----------
    sketch_graph, metric_graph : networkx.Graph
    c_matrix : ndarray, shape (n_sketch, n_metric)
        Rows and columns in ``sketch_nodes`` / ``metric_nodes`` order (default: ascending ids).
    m : float
    timeout : float
        Wall-clock budget in seconds.
    max_vertices : int
        Larger graphs are not searched at all.

    Examples
    --------
    >>> g = nx.path_graph(3)
    >>> c = np.array([[0.0, 1, 1], [1, 0.0, 1], [1, 1, 0.0]])
    >>> vf2_match(g, g.copy(), c, 0.1).pairs
    [(0, 0), (1, 1), (2, 2)]
    """
    sketch_nodes = sorted(sketch_graph.nodes) if sketch_nodes is None else list(sketch_nodes)
    metric_nodes = sorted(metric_graph.nodes) if metric_nodes is None else list(metric_nodes)
    if not sketch_nodes or not metric_nodes:
        return Vf2Result([], "")
    if max(len(sketch_nodes), len(metric_nodes)) > max_vertices:
        return Vf2Result([], f"graphs larger than max_vertices={max_vertices}: VF2 not run")
    compatible = np.asarray(c_matrix) <= m
    # Nodes are renamed to integers: sketch node i of ``sketch_nodes`` is i, metric node j is
    # n_sketch + j. GraphMatcher iterates sets of nodes, so nodes whose hash depends on the
    # interpreter's string-hash seed (tuples with a tag string, as before) made the first
    # isomorphism found, and so the answer, differ from one process to the next.
    n_sketch = len(sketch_nodes)
    sketch_tagged = nx.relabel_nodes(sketch_graph, {n: i for i, n in enumerate(sketch_nodes)})
    metric_tagged = nx.relabel_nodes(metric_graph, {n: n_sketch + j for j, n in enumerate(metric_nodes)})
    for graph in (sketch_tagged, metric_tagged):
        for node in graph.nodes:
            graph.nodes[node].clear()
            graph.nodes[node]["key"] = node
    sketch_is_pattern = len(sketch_nodes) <= len(metric_nodes)
    big, small = (metric_tagged, sketch_tagged) if sketch_is_pattern else (sketch_tagged, metric_tagged)
    deadline = time.perf_counter() + timeout

    def node_match(big_attributes, small_attributes):
        if time.perf_counter() > deadline:
            raise _OutOfTime
        a, b = big_attributes["key"], small_attributes["key"]
        sketch_node, metric_node = (b, a) if sketch_is_pattern else (a, b)
        return bool(compatible[sketch_node, metric_node - n_sketch])

    from networkx.algorithms import isomorphism

    matcher = isomorphism.GraphMatcher(big, small, node_match=node_match)
    try:
        mapping = next(matcher.subgraph_isomorphisms_iter(), None)
    except _OutOfTime:
        return Vf2Result([], f"VF2 gave up after {timeout:g} s")
    if mapping is None:
        return Vf2Result([], "")
    pairs = []
    for big_node, small_node in mapping.items():
        sketch_node, metric_node = (small_node, big_node) if sketch_is_pattern else (big_node, small_node)
        pairs.append((sketch_node, metric_node - n_sketch))
    return Vf2Result([(sketch_nodes[i], metric_nodes[j]) for i, j in sorted(pairs)], "")
