"""Region types and positions: the "old method" types and the position term of ``c``.

Positions are region centroids normalised to each map's extent (:func:`region_positions`); the
matcher blends their distances into the signature comparison (:func:`blend_positions`) after
turning the sketch to the orientation tried (:mod:`ursim_core.matching.orientation`).
"""

from __future__ import annotations

from collections.abc import Sequence

import networkx as nx
import numpy as np

__all__ = [
    "region_types",
    "region_positions",
    "position_distance",
    "blend_positions",
    "blend_position_arrays",
    "metric_positions_of",
]


def region_types(graph: nx.Graph, *, nodes: Sequence | None = None) -> np.ndarray:
    """The "old method" region type: 1 for a crossing (degree > 1), 0 for a dead end.

    Examples
    --------
    >>> region_types(nx.path_graph(3)).tolist()
    [0, 1, 0]
    """
    nodes = sorted(graph.nodes) if nodes is None else list(nodes)
    return np.array([1 if graph.degree(node) > 1 else 0 for node in nodes], dtype=np.int64)


def region_positions(graph: nx.Graph, *, nodes: Sequence | None = None) -> np.ndarray:
    """Region centroids normalised to the map's extent, in [0, 1] x [0, 1].

    The extent is the union of the regions' bounding boxes (``bbox`` node attribute;
    the centroids' own range when absent), so the positions do not depend on the
    image's margins or scale. A zero extent on an axis gives 0.5 on that axis.

    Returns
    -------
    ndarray, shape (n, 2)
        (row, col) per region in ``nodes`` order.

    Examples
    --------
    >>> g = nx.Graph()
    >>> g.add_node(1, centroid=(5.0, 10.0), bbox=(0, 0, 10, 20))
    >>> g.add_node(2, centroid=(15.0, 30.0), bbox=(10, 20, 20, 40))
    >>> region_positions(g).tolist()
    [[0.25, 0.25], [0.75, 0.75]]
    """
    nodes = sorted(graph.nodes) if nodes is None else list(nodes)
    if not nodes:
        return np.zeros((0, 2))
    centroids = np.array([graph.nodes[node]["centroid"] for node in nodes], dtype=np.float64).reshape(-1, 2)
    if all("bbox" in graph.nodes[node] for node in nodes):
        boxes = np.array([graph.nodes[node]["bbox"] for node in nodes], dtype=np.float64).reshape(-1, 4)
        low = boxes[:, :2].min(axis=0)
        high = boxes[:, 2:].max(axis=0)
    else:
        low, high = centroids.min(axis=0), centroids.max(axis=0)
    extent = high - low
    safe = np.where(extent > 0, extent, 1.0)
    return np.where(extent > 0, (centroids - low) / safe, 0.5)


def position_distance(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Euclidean distances between every pair of normalised positions.

    Examples
    --------
    >>> position_distance(np.array([[0.0, 0.0]]), np.array([[0.6, 0.8], [0.0, 0.5]])).tolist()
    [[1.0, 0.5]]
    """
    first = np.asarray(first, dtype=np.float64).reshape(-1, 2)
    second = np.asarray(second, dtype=np.float64).reshape(-1, 2)
    out = np.empty((len(first), len(second)))
    # In blocks of rows, per axis: the temporaries of a block stay in cache, and the only large
    # array is the result (4249 x 4256 regions: 145 MB; full-size temporaries doubled the fresh
    # memory, 0.1 s of each of the 16 calls of a building-sized match). Same sums, same order.
    step = max(1, _BLOCK_ELEMENTS // max(1, len(second)))
    for start in range(0, len(first), step):
        block = out[start : start + step]
        np.subtract.outer(first[start : start + step, 0], second[:, 0], out=block)
        block *= block
        cols = np.subtract.outer(first[start : start + step, 1], second[:, 1])
        cols *= cols
        block += cols
        np.sqrt(block, out=block)
    return out


#: Elements of a block of :func:`position_distance` (256 KiB of float64: within a core's cache).
_BLOCK_ELEMENTS = 1 << 15


def blend_positions(c_matrix, sketch_graph, sketch_nodes, metric_graph, metric_nodes, position_weight):
    """``(c + beta * d_position) / (1 + beta)`` with beta = ``position_weight`` (c itself when 0)."""
    if not position_weight:
        return c_matrix
    return blend_position_arrays(
        c_matrix,
        region_positions(sketch_graph, nodes=sketch_nodes),
        region_positions(metric_graph, nodes=metric_nodes),
        position_weight,
    )


def blend_position_arrays(c_matrix, sketch_positions, metric_positions, position_weight):
    """:func:`blend_positions` of positions already normalised (:func:`region_positions`).

    Examples
    --------
    >>> blend_position_arrays(np.zeros((1, 1)), np.array([[0.0, 0.0]]), np.array([[0.6, 0.8]]), 1.0).tolist()
    [[0.5]]
    """
    if not position_weight:
        return c_matrix
    distances = position_distance(sketch_positions, metric_positions)
    # In place, in the order of ``(c + w * d) / (1 + w)``: the same values without two temporaries.
    distances *= position_weight
    distances += c_matrix
    distances /= 1.0 + position_weight
    return distances


def metric_positions_of(descriptors, metric_graph: nx.Graph) -> np.ndarray:
    """The metric map's region positions of a pair's
    :class:`~ursim_core.matching.descriptors.PairDescriptors`: those it kept
    (``metric_positions``), else :func:`region_positions` in its ``metric_nodes`` order."""
    if descriptors.metric_positions is not None:
        return descriptors.metric_positions
    return region_positions(metric_graph, nodes=descriptors.metric_nodes)
