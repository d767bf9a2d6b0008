"""Region descriptors for URSIM: attributes, uniqueness, anchors, weights and heat-kernel signatures.

Everything here works on region adjacency graphs (:func:`ursim_core.segmentation.graph.region_graph`) and
plain arrays.  A graph's regions are always taken in ascending region-id order; the arrays
returned are indexed in that order (``nodes[i]`` is the region id of row ``i``).

Steps (Mielle et al. 2019, §3-4; departures of the released code in ``original_code.md`` §1.2-1.8):

1. :func:`region_attributes`: size (pixels) and PCA shape (``1 - lambda_min / lambda_max``).
2. :func:`attribute_statistics` / :func:`standardise`: z-scores with the sample sd (n - 1).
   The paper standardises each map with its own statistics; the released code standardised the
   sketch with the metric map's statistics (``standardise="model"`` in :func:`pair_descriptors`).
   An attribute with zero variance (or a map with one region) gets z = 0 everywhere, so it never
   makes a region unique.
3. :func:`unique_mask`: a region is unique when ``|z| >= k`` on any attribute (k = 1).
4. :func:`anchor_pairs`: Hungarian assignment between the unique regions of the two maps on the
   disparity (paper: mean ``|dz|`` over attributes; released: ``min(1, (|dz_size| +
   |dpca_raw|) / 2)`` truncated to integer percent).  Returns ``min(#unique, #unique')`` pairs.
5. :func:`vertex_weights`: ``"size"`` (paper: standardised size made non-negative,
   ``z - min z + floor``), ``"uniqueness"`` (released code: ``1 - (phi(z_pca) + phi(z_size)) / 2``)
   or ``"equal"`` (1 everywhere: variants T1, T2).  Why the floor: with ``z - min z`` the smallest
   region gets weight 0, and a zero weight removes every off-diagonal entry of its Laplacian row
   (``-sqrt(w_u w_v) = 0``): no heat can enter or leave it, so its anchor signature is 0 at every
   time whatever its position.  The default floor 0.1 (``SIZE_WEIGHT_FLOOR``, one tenth of a
   standard deviation) keeps it connected while keeping the weight ratios of the other regions.
6. :func:`weighted_laplacian`: Chung-Langlands vertex-weighted Laplacian
   ``L(u,u) = sum_{v~u} w_v``, ``L(u,v) = -sqrt(w_u w_v)``; symmetric PSD with ``L sqrt(w) = 0``.
7. :func:`heat_kernel_signatures`: anchor signature ``s_u(t) = sum_a H_t(u, a)`` or the plain
   HKS ``H_t(u, u)``, with ``H_t = exp(-t L)``, t = 0, 0.2, ..., 2.8.  Dense eigendecomposition
   for graphs up to ``DENSE_LIMIT`` regions; above it ``scipy.sparse.linalg.expm_multiply`` applies
   ``exp(-tL)`` to indicator vectors, which is exact and needs no full eigendecomposition.
   Measured on the project's 2-core machine (busy): anchor signature of a 200-region graph
   0.59 s with ``eigh`` vs 0.034 s with ``expm_multiply``; 1000 regions 12.7 s vs 0.032 s. Hence
   the low limit (100): sketch-sized graphs (< 20 regions) still take the exact dense path.
8. :func:`signature_distance`: ``c(v, v') = mean_t |s_v(t) - s_v'(t)|`` for all pairs.
9. Beyond the paper (option ``position_weight`` = beta of :func:`pair_descriptors`, 0 = paper):
   ``c = (c_signature + beta * d_position) / (1 + beta)`` where ``d_position`` is the Euclidean
   distance between region centroids normalised to each map's extent (:func:`region_positions`,
   :func:`position_distance`). It uses the coarse layout a sketch keeps ("fairly accurate at key
   places") and assumes the sketch is drawn in the metric map's orientation (not rotated or
   mirrored); set it to 0 when that does not hold. Evidence in ``ursim_core.matching.auto_m``.

:func:`pair_descriptors` runs the whole chain for a sketch graph and a metric graph according to
a variant: T1 (plain HKS, equal weights), T2 (anchors, equal weights), T3 (plain HKS, size
weights), T4 = URSIM (anchors and weights), or ``"baseline"`` (the "old method": a region is a
crossing when its degree is > 1, else a dead end; c is 0 for the same type and 1 otherwise).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from ursim_core.matching.config import SIZE_WEIGHT_FLOOR, VARIANTS
from ursim_core.matching.positions import (
    blend_position_arrays,
    blend_positions,
    position_distance,
    region_positions,
    region_types,
)
from ursim_core.matching.signatures import (
    DEFAULT_TIMES,
    DENSE_LIMIT,
    heat_kernel_signatures,
    signature_distance,
    weighted_laplacian,
)

# scipy.sparse and scipy.optimize are imported where they are used: together they cost about
# 0.4 s at start-up, and sketch-sized graphs need neither the sparse path nor (often) anchors.

__all__ = [
    "ATTRIBUTES",
    "DEFAULT_TIMES",
    "DENSE_LIMIT",
    "SIZE_WEIGHT_FLOOR",
    "VARIANTS",
    "PairDescriptors",
    "region_attributes",
    "attribute_statistics",
    "standardise",
    "unique_mask",
    "uniqueness_score",
    "disparity_matrix",
    "anchor_pairs",
    "vertex_weights",
    "weighted_laplacian",
    "heat_kernel_signatures",
    "signature_distance",
    "region_types",
    "region_positions",
    "position_distance",
    "pair_descriptors",
    "blend_positions",
]

ATTRIBUTES = ("size", "pca_shape")


def region_attributes(graph: nx.Graph, *, attributes: Sequence[str] = ATTRIBUTES) -> tuple[list, np.ndarray]:
    """Node order and attribute matrix of a region graph.

    Parameters
    ----------
    graph : networkx.Graph
        Region graph; every node carries the named attributes.
    attributes : sequence of str
        Node attribute names, one column each.

    Returns
    -------
    nodes : list
        Region ids in ascending order (the row order).
    values : ndarray of float, shape (n_regions, n_attributes)

    Examples
    --------
    >>> g = nx.Graph(); g.add_node(2, size=10, pca_shape=0.5); g.add_node(1, size=4, pca_shape=0.1)
    >>> nodes, values = region_attributes(g)
    >>> nodes, values.tolist()
    ([1, 2], [[4.0, 0.1], [10.0, 0.5]])
    """
    nodes = sorted(graph.nodes)
    values = np.array(
        [[float(graph.nodes[node][name]) for name in attributes] for node in nodes], dtype=np.float64
    ).reshape(len(nodes), len(attributes))
    return nodes, values


def attribute_statistics(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Column means and sample standard deviations (n - 1), as the released code.

    With fewer than two rows the sd is reported as 0.

    Examples
    --------
    >>> mean, sd = attribute_statistics(np.array([[1.0], [3.0]]))
    >>> mean.tolist(), sd.round(4).tolist()
    ([2.0], [1.4142])
    """
    values = np.asarray(values, dtype=np.float64)
    if values.shape[0] == 0:
        return np.zeros(values.shape[1]), np.zeros(values.shape[1])
    mean = values.mean(axis=0)
    sd = values.std(axis=0, ddof=1) if values.shape[0] > 1 else np.zeros(values.shape[1])
    return mean, sd


def standardise(values: np.ndarray, *, mean: np.ndarray | None = None, sd: np.ndarray | None = None) -> np.ndarray:
    """Z-scores of the columns; statistics default to the values' own.

    Columns whose sd is 0 get z = 0 (no region stands out on a constant attribute).

    Parameters
    ----------
    values : ndarray, shape (n, k)
    mean, sd : ndarray, shape (k,), optional
        External statistics (the released code standardised the sketch with the
        metric map's).

    Examples
    --------
    >>> standardise(np.array([[1.0, 5.0], [3.0, 5.0]])).round(4).tolist()
    [[-0.7071, 0.0], [0.7071, 0.0]]
    """
    values = np.asarray(values, dtype=np.float64)
    own_mean, own_sd = attribute_statistics(values)
    mean = own_mean if mean is None else np.asarray(mean, dtype=np.float64)
    sd = own_sd if sd is None else np.asarray(sd, dtype=np.float64)
    safe_sd = np.where(sd > 0, sd, 1.0)
    return np.where(sd > 0, (values - mean) / safe_sd, 0.0)


def unique_mask(z: np.ndarray, *, k: float = 1.0) -> np.ndarray:
    """Regions at least ``k`` standard deviations from the mean on any attribute.

    Examples
    --------
    >>> unique_mask(np.array([[0.2, -1.5], [0.9, 0.1], [1.0, 0.0]])).tolist()
    [True, False, True]
    """
    z = np.asarray(z, dtype=np.float64)
    if z.size == 0:
        return np.zeros(z.shape[0], dtype=bool)
    return np.any(np.abs(z) >= k, axis=1)


def uniqueness_score(z_size: np.ndarray, z_pca: np.ndarray) -> np.ndarray:
    """Released-code uniqueness score ``1 - (phi(z_pca) + phi(z_size)) / 2``, phi = N(0, 1) pdf.

    It lies in about [0.60, 1]: 0.60 for an average region, towards 1 for outliers.

    Examples
    --------
    >>> uniqueness_score(np.array([0.0, 3.0]), np.array([0.0, 3.0])).round(3).tolist()
    [0.601, 0.996]
    """

    def pdf(x):
        return np.exp(-0.5 * np.square(x)) / np.sqrt(2.0 * np.pi)

    return 1.0 - (pdf(np.asarray(z_pca, float)) + pdf(np.asarray(z_size, float))) / 2.0


def disparity_matrix(
    z_first: np.ndarray,
    z_second: np.ndarray,
    *,
    disparity: str = "paper",
    raw_pca_first: np.ndarray | None = None,
    raw_pca_second: np.ndarray | None = None,
) -> np.ndarray:
    """Disparity between every region of one map and every region of the other.

    Parameters
    ----------
    z_first, z_second : ndarray, shape (n, 2) and (n', 2)
        Standardised (size, pca_shape) attributes.
    disparity : {'paper', 'released'}
        ``'paper'``: mean over attributes of ``|dz|`` (Eq. 2).
        ``'released'``: ``min(1, (|dz_size| + |pca - pca'|) / 2)`` with the *raw* PCA
        attribute, then truncated to integer percent and divided by 100 (the
        released code's Hungarian cost, original_code.md §1.4).
    raw_pca_first, raw_pca_second : ndarray, optional
        Raw PCA attribute; needed for ``'released'``.

    Examples
    --------
    >>> disparity_matrix(np.array([[1.0, 0.0]]), np.array([[0.0, 1.0], [1.0, 0.0]])).tolist()
    [[1.0, 0.0]]
    """
    z_first = np.asarray(z_first, dtype=np.float64).reshape(-1, 2)
    z_second = np.asarray(z_second, dtype=np.float64).reshape(-1, 2)
    if disparity == "paper":
        return np.abs(z_first[:, None, :] - z_second[None, :, :]).mean(axis=2)
    if disparity == "released":
        if raw_pca_first is None or raw_pca_second is None:
            raise ValueError("the released disparity needs the raw PCA attributes")
        size_term = np.abs(z_first[:, 0][:, None] - z_second[:, 0][None, :])
        pca_term = np.abs(np.asarray(raw_pca_first, float)[:, None] - np.asarray(raw_pca_second, float)[None, :])
        similarity = np.minimum(1.0, (size_term + pca_term) / 2.0)
        return np.floor(similarity * 100.0 + 1e-9) / 100.0
    raise ValueError(f"disparity must be 'paper' or 'released', not {disparity!r}")


def anchor_pairs(cost: np.ndarray) -> list[tuple[int, int]]:
    """Hungarian assignment on a (possibly rectangular) cost matrix.

    Every row or column of the smaller side is assigned; there is no cost threshold
    (the released code keeps all ``min(rows, cols)`` pairs).

    Returns
    -------
    list of (row, col)
        Sorted by row.

    Examples
    --------
    >>> anchor_pairs(np.array([[0.9, 0.1, 0.5], [0.2, 0.8, 0.7]]))
    [(0, 1), (1, 0)]
    """
    cost = np.asarray(cost, dtype=np.float64)
    if cost.size == 0:
        return []
    from ursim_core.matching.lsap import linear_sum_assignment

    rows, cols = linear_sum_assignment(cost)
    return [(int(r), int(c)) for r, c in zip(rows, cols)]


def vertex_weights(z: np.ndarray, *, kind: str = "size", floor: float = SIZE_WEIGHT_FLOOR) -> np.ndarray:
    """Vertex weights of the Laplacian from standardised (size, pca_shape) attributes.

    Parameters
    ----------
    z : ndarray, shape (n, 2)
        Standardised attributes, size first.
    kind : {'size', 'uniqueness', 'equal'}
        ``'size'``: ``z_size - min(z_size) + floor`` (paper). ``'uniqueness'``: the
        released code's uniqueness score. ``'equal'``: all ones.
    floor : float
        Added to the size weights so that none is 0 (see the module docstring).

    Examples
    --------
    >>> vertex_weights(np.array([[-1.0, 0.0], [1.0, 0.0]])).tolist()
    [0.1, 2.1]
    >>> vertex_weights(np.zeros((2, 2)), kind="equal").tolist()
    [1.0, 1.0]
    """
    z = np.asarray(z, dtype=np.float64).reshape(-1, 2)
    if kind == "equal":
        return np.ones(z.shape[0])
    if kind == "size":
        if z.shape[0] == 0:
            return np.zeros(0)
        return z[:, 0] - z[:, 0].min() + float(floor)
    if kind == "uniqueness":
        return uniqueness_score(z[:, 0], z[:, 1])
    raise ValueError(f"weights must be 'size', 'uniqueness' or 'equal', not {kind!r}")


@dataclass(frozen=True, eq=False)
class PairDescriptors:
    """Everything the matcher needs that does not depend on m.

    Attributes
    ----------
    sketch_nodes, metric_nodes : list
        Region ids in row order.
    sketch_z, metric_z : ndarray, shape (n, 2)
        Standardised (size, pca_shape).
    unique_sketch, unique_metric : list
        Region ids of the unique regions.
    anchors : list of (sketch_region, metric_region)
    sketch_weights, metric_weights : ndarray
        Laplacian vertex weights (None for the baseline).
    sketch_signatures, metric_signatures : ndarray, shape (n, T) or None
    c_matrix : ndarray, shape (n_sketch, n_metric)
        The comparison used by the matchers (signature distance, blended with the
        position distance when ``position_weight > 0``).
    notes : list of str
        Degenerate conditions met on the way (empty when none).

    Examples
    --------
    >>> g = nx.path_graph(4)  # four rooms in a row, the first much larger
    >>> nx.set_node_attributes(g, {0: 100, 1: 10, 2: 12, 3: 11}, "size")
    >>> nx.set_node_attributes(g, 0.5, "pca_shape")
    >>> d = pair_descriptors(g, g.copy())
    >>> d.unique_sketch, d.anchors, d.sketch_signatures.shape, d.c_matrix.argmin(axis=1).tolist()
    ([0], [(0, 0)], (4, 15), [0, 1, 2, 3])
    >>> d.notes[0]
    "sketch attribute 'pca_shape' has zero variance"
    """

    sketch_nodes: list
    metric_nodes: list
    sketch_z: np.ndarray
    metric_z: np.ndarray
    unique_sketch: list
    unique_metric: list
    anchors: list
    sketch_weights: np.ndarray | None
    metric_weights: np.ndarray | None
    sketch_signatures: np.ndarray | None
    metric_signatures: np.ndarray | None
    c_matrix: np.ndarray
    notes: list = field(default_factory=list)
    #: The signature (or type) comparison alone, before the position blend: what a turned
    #: sketch shares with the upright one (see ``ursim_core.matching.orientation``).
    signature_c: np.ndarray | None = None
    #: The metric map's region positions (:func:`region_positions`, ``metric_nodes`` order): the
    #: same in every orientation and refit of the sketch, which blend them again and again.
    metric_positions: np.ndarray | None = None


def pair_descriptors(
    sketch_graph: nx.Graph,
    metric_graph: nx.Graph,
    *,
    variant: str = "T4",
    weights: str | None = None,
    standardise_with: str = "own",
    uniqueness_k: float = 1.0,
    disparity: str = "paper",
    times: Sequence[float] = DEFAULT_TIMES,
    size_weight_floor: float = SIZE_WEIGHT_FLOOR,
    method: str = "auto",
    position_weight: float = 0.0,
) -> PairDescriptors:
    """Attributes, uniqueness, anchors, weights, signatures and the c matrix of a map pair.

    Parameters
    ----------
    sketch_graph, metric_graph : networkx.Graph
        Region graphs with ``size`` and ``pca_shape`` node attributes.
    variant : {'T1', 'T2', 'T3', 'T4', 'baseline'}
        T1 plain HKS + equal weights; T2 anchors + equal weights; T3 plain HKS +
        size weights; T4 anchors + size weights (URSIM); baseline crossing/dead-end types.
    weights : {'size', 'uniqueness', 'equal'}, optional
        Overrides the variant's weights (``'uniqueness'`` is the released code's T4).
    standardise_with : {'own', 'model'}
        Statistics used for the sketch's z-scores: its own (paper) or the metric
        map's (released code).
    uniqueness_k : float
        Uniqueness threshold in standard deviations.
    disparity : {'paper', 'released'}
        Anchor disparity, see :func:`disparity_matrix`.
    times : sequence of float
    size_weight_floor : float
        See :func:`vertex_weights`.
    method : {'auto', 'eigh', 'expm'}
        See :func:`heat_kernel_signatures`.
    position_weight : float
        beta of ``c = (c_signature + beta * d_position) / (1 + beta)``; 0 (the
        paper) leaves the signature distance alone.

    Examples
    --------
    >>> g = nx.path_graph(4)
    >>> nx.set_node_attributes(g, {0: 100, 1: 10, 2: 12, 3: 11}, "size")
    >>> nx.set_node_attributes(g, 0.5, "pca_shape")
    >>> d = pair_descriptors(g, g.copy())
    >>> d.anchors, bool(np.allclose(np.diag(d.c_matrix), 0))
    ([(0, 0)], True)
    """
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, not {variant!r}")
    if standardise_with not in ("own", "model"):
        raise ValueError(f"standardise must be 'own' or 'model', not {standardise_with!r}")
    notes: list[str] = []
    sketch_nodes, sketch_values = region_attributes(sketch_graph)
    metric_nodes, metric_values = region_attributes(metric_graph)
    metric_mean, metric_sd = attribute_statistics(metric_values)
    sketch_mean, sketch_sd = attribute_statistics(sketch_values)
    for name, sd, count in (("sketch", sketch_sd, len(sketch_nodes)), ("metric", metric_sd, len(metric_nodes))):
        if count > 1:
            for attribute, value in zip(ATTRIBUTES, sd):
                if value == 0:
                    notes.append(f"{name} attribute '{attribute}' has zero variance")
    if standardise_with == "model":
        sketch_z = standardise(sketch_values, mean=metric_mean, sd=metric_sd)
    else:
        sketch_z = standardise(sketch_values)
    metric_z = standardise(metric_values)

    if variant == "baseline":
        sketch_types = region_types(sketch_graph, nodes=sketch_nodes)
        metric_types = region_types(metric_graph, nodes=metric_nodes)
        types_c = (sketch_types[:, None] != metric_types[None, :]).astype(np.float64)
        metric_positions = None
        c_matrix = types_c.copy()  # the matchers' c, apart from the type comparison kept beside it
        if position_weight:
            metric_positions = region_positions(metric_graph, nodes=metric_nodes)
            c_matrix = blend_position_arrays(
                types_c, region_positions(sketch_graph, nodes=sketch_nodes), metric_positions, position_weight
            )
        return PairDescriptors(
            sketch_nodes, metric_nodes, sketch_z, metric_z, [], [], [], None, None, None, None, c_matrix, notes,
            types_c, metric_positions,
        )  # fmt: skip

    uses_anchors = variant in ("T2", "T4")
    if weights is None:
        weights = {"T1": "equal", "T2": "equal", "T3": "size", "T4": "size"}[variant]
    sketch_unique = unique_mask(sketch_z, k=uniqueness_k)
    metric_unique = unique_mask(metric_z, k=uniqueness_k)
    unique_sketch = [sketch_nodes[i] for i in np.flatnonzero(sketch_unique)]
    unique_metric = [metric_nodes[i] for i in np.flatnonzero(metric_unique)]
    anchors: list = []
    sketch_anchor_rows: list[int] = []
    metric_anchor_rows: list[int] = []
    if uses_anchors:
        if not unique_sketch or not unique_metric:
            notes.append("no anchors: no unique region in the " + ("sketch" if not unique_sketch else "metric map"))
        else:
            sketch_rows = np.flatnonzero(sketch_unique)
            metric_rows = np.flatnonzero(metric_unique)
            cost = disparity_matrix(
                sketch_z[sketch_rows],
                metric_z[metric_rows],
                disparity=disparity,
                raw_pca_first=sketch_values[sketch_rows, 1],
                raw_pca_second=metric_values[metric_rows, 1],
            )
            for row, col in anchor_pairs(cost):
                sketch_anchor_rows.append(int(sketch_rows[row]))
                metric_anchor_rows.append(int(metric_rows[col]))
                anchors.append((sketch_nodes[sketch_rows[row]], metric_nodes[metric_rows[col]]))

    sketch_weights = vertex_weights(sketch_z, kind=weights, floor=size_weight_floor)
    metric_weights = vertex_weights(metric_z, kind=weights, floor=size_weight_floor)
    signatures = []
    for graph, nodes, vertex_weight, anchor_rows in (
        (sketch_graph, sketch_nodes, sketch_weights, sketch_anchor_rows),
        (metric_graph, metric_nodes, metric_weights, metric_anchor_rows),
    ):
        laplacian = weighted_laplacian(graph, vertex_weight, nodes=nodes)
        signatures.append(
            heat_kernel_signatures(laplacian, anchors=anchor_rows if uses_anchors else None, times=times, method=method)
        )
    signature_c = signature_distance(signatures[0], signatures[1])
    metric_positions = None
    c_matrix = signature_c
    if position_weight:
        metric_positions = region_positions(metric_graph, nodes=metric_nodes)
        c_matrix = blend_position_arrays(
            signature_c, region_positions(sketch_graph, nodes=sketch_nodes), metric_positions, position_weight
        )
    return PairDescriptors(
        sketch_nodes,
        metric_nodes,
        sketch_z,
        metric_z,
        unique_sketch,
        unique_metric,
        anchors,
        sketch_weights,
        metric_weights,
        signatures[0],
        signatures[1],
        c_matrix,
        notes,
        signature_c,
        metric_positions,
    )
