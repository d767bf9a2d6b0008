"""Positions refitted from a first answer: the sketch laid on the metric map by its own matches.

The position term of ``c`` (:mod:`ursim_core.matching.positions`) compares region centroids
normalised to each map's extent, which assumes that the sketch covers the metric map's extent in
proportion. A sketch that shows part of the building, or squeezes one wing, breaks that. Once the
planar matcher has an answer, its pairs say where the sketch lies: a scale and a shift per axis
(the sketch is already turned to the orientation tried), fitted to the pairs' centroids by
weighted least squares that lets outlying pairs go (:func:`fit_axis_transform`). The sketch's
centroids are then moved into the metric map's frame and normalised by the metric map's extent,
``c`` is blended again and the matcher runs once more; the new answer is kept only when its
hypothesis score is lower (:func:`refit_positions`), the score the orientations are ranked by.

Measured (``MatchConfig(position_refits=0)`` is the old behaviour): generated pairs of
``ursim bench invariance --seeds 8`` 0.77 -> 0.86 mean F1; the 18 KTH sketches in 8 orientations
0.72 -> 0.76 in sample, all of it sketch 01 (0.17 -> 1.00), so held out (leave one sketch out over
0, 1 and 3 refits) it stays 0.72. One refit: three gave the same on both. What the refit gets right on
sketch 01 is its orientation: ``MatchConfig(keep_refit=False)`` ranks the orientations by the
refitted answers and keeps the chosen one's answer from before the refit (01: 0.83); held out over
``keep_refit`` true and false, 0.74 in every orientation (round 30).

A second start (:func:`signature_start`, ``MatchConfig(signature_refit=True)``): the answer
matched without the position term, which does not depend on where the sketch was laid, is refitted
the same way (:func:`refit_from`). Seeds 8-15 of ``ursim bench invariance`` (held out) 0.863 ->
0.892 mean F1, seeds 0-7 unchanged (0.842); the KTH sketches unchanged in every orientation. On by
default since round 20 (about 15 % more prepare time per KTH pair, within the 50 ms budget).
"""

from __future__ import annotations

import dataclasses

import networkx as nx
import numpy as np

from ursim_core.matching.kernels import NO_FIT, fit_axes_compiled
from ursim_core.matching.positions import blend_position_arrays, metric_positions_of

__all__ = [
    "fit_axis_transform",
    "refitted_graph",
    "refitted_positions",
    "refit_from",
    "refit_by_transform",
    "refit_positions",
    "signature_start",
]

#: Reweighting rounds of the fit; pairs whose residual exceeds ``_CUTOFF`` median residuals
#: get no weight in the next round (Tukey's biweight).
_ROUNDS = 3
_CUTOFF = 3.0
#: A fitted scale below this, relative to the ratio of the pairs' spreads (1 for a fit that keeps
#: them apart as they are), or a negative one, squeezes the sketch into a line: not a placement.
_SMALLEST_SCALE = 0.05


def _median(values: np.ndarray) -> float:
    """``np.median`` of a 1-D float array, bit for bit, without the ``numpy.ma`` import (9 ms of
    every ``ursim match``) that np.median's NaN check makes on its first call."""
    n = len(values)
    middle = np.partition(values, [(n - 1) // 2, n // 2])
    return float(0.5 * (middle[(n - 1) // 2] + middle[n // 2]))


def _weighted_line(x: np.ndarray, y: np.ndarray, weights: np.ndarray) -> tuple[float, float]:
    """Slope and intercept of ``y ~ slope * x + intercept`` by least squares, each row weighted by
    ``weights`` (the residuals multiplied by them, as ``lstsq`` on the weighted rows).

    In closed form (weighted means and moments), not ``np.linalg.lstsq``, whose LAPACK call cost
    about 15 us: the refit fits six lines per answer, dozens of answers per turned sketch. The same
    fits to rounding (every KTH evaluation row identical, round 39); when the weighted points all
    but share one x, ``lstsq``'s minimum-norm answer is kept.

    Examples
    --------
    >>> _weighted_line(np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 5.0]), np.ones(3))
    (2.0, 1.0)
    """
    squared = weights * weights
    total = squared.sum()
    mean_x, mean_y = (squared @ x) / total, (squared @ y) / total
    dx = x - mean_x
    spread = squared @ (dx * dx)
    if not spread > 1e-12 * total * max(1.0, mean_x * mean_x):
        design = np.stack([x, np.ones(len(x))], axis=1)
        slope, intercept = np.linalg.lstsq(design * weights[:, None], y * weights, rcond=None)[0]
        return float(slope), float(intercept)
    slope = (squared @ (dx * (y - mean_y))) / spread
    return float(slope), float(mean_y - slope * mean_x)


def fit_axis_transform(pairs, sketch_graph: nx.Graph, metric_graph: nx.Graph) -> np.ndarray | None:
    """Scale and shift per axis that carry the sketch's centroids onto their partners'.

    Parameters
    ----------
    pairs : sequence of (sketch node, metric node)
    sketch_graph, metric_graph : networkx.Graph
        Region graphs with ``centroid`` (row, col) and ``size`` node attributes.

    Returns
    -------
    ndarray of shape (2, 2) or None
        ``[[row scale, row shift], [col scale, col shift]]``; None with fewer than 3 pairs or a
        degenerate fit. Each pair weighs the square root of its smaller region's size.

    Examples
    --------
    >>> s, m = nx.Graph(), nx.Graph()
    >>> for n, (r, c) in enumerate([(0, 0), (10, 0), (0, 20), (10, 20)]):
    ...     s.add_node(n, centroid=(r, c), size=10)
    ...     m.add_node(n, centroid=(2 * r + 5, c + 1), size=10)
    >>> fit_axis_transform([(n, n) for n in range(4)], s, m).round(3).tolist()
    [[2.0, 5.0], [1.0, 1.0]]
    """
    pairs = list(pairs)
    if len(pairs) < 3:
        return None
    source = np.array([sketch_graph.nodes[a]["centroid"] for a, _ in pairs], float).reshape(-1, 2)
    target = np.array([metric_graph.nodes[b]["centroid"] for _, b in pairs], float).reshape(-1, 2)
    source_spread, target_spread = np.ptp(source, axis=0), np.ptp(target, axis=0)
    if np.any(source_spread <= 0) or np.any(target_spread <= 0):
        return None  # every pair on one line: no scale along the other axis
    sizes = [min(sketch_graph.nodes[a]["size"], metric_graph.nodes[b]["size"]) for a, b in pairs]
    weights = np.sqrt(np.maximum(np.asarray(sizes, float), 0.0))
    compiled = fit_axes_compiled(source, target, weights, rounds=_ROUNDS, cutoff=_CUTOFF)
    if compiled is NO_FIT:
        return None
    if compiled is not None:
        transform = np.array(compiled)
    else:
        transform = _fitted_in_numpy(source, target, weights)
        if transform is None:
            return None
    if np.any(transform[:, 0] * source_spread / target_spread < _SMALLEST_SCALE):
        return None
    return transform


def _fitted_in_numpy(source: np.ndarray, target: np.ndarray, weights: np.ndarray) -> np.ndarray | None:
    """The fit of :func:`fit_axis_transform` in NumPy (the reference; the C loop's fallback)."""
    transform = np.zeros((2, 2))
    for axis in range(2):
        x, y = source[:, axis], target[:, axis]
        current = weights.copy()
        for _ in range(_ROUNDS):
            if np.count_nonzero(current) < 2:
                return None
            slope, intercept = _weighted_line(x, y, current)
            residuals = np.abs(slope * x + intercept - y)
            spread = _CUTOFF * _median(residuals) + 1e-9
            current = weights * np.clip(1.0 - (residuals / spread) ** 2, 0.0, 1.0) ** 2
        transform[axis] = (slope, intercept)
    return transform


def refitted_positions(sketch_graph: nx.Graph, sketch_nodes, metric_graph: nx.Graph, transform) -> np.ndarray:
    """``region_positions(refitted_graph(sketch_graph, metric_graph, transform), nodes=sketch_nodes)``
    without copying the graph: the sketch's centroids moved by ``transform`` and normalised by the
    metric map's extent (the same values)."""
    extent = _extent_of(metric_graph)
    nodes = sketch_graph.nodes
    centroids = np.array([nodes[node]["centroid"] for node in sketch_nodes], dtype=np.float64).reshape(-1, 2)
    moved = transform[:, 0] * centroids + transform[:, 1]
    low, high = np.array(extent[:2], dtype=np.float64), np.array(extent[2:], dtype=np.float64)
    size = high - low
    return np.where(size > 0, (moved - low) / np.where(size > 0, size, 1.0), 0.5)


def _extent_of(metric_graph: nx.Graph) -> tuple:
    """The metric map's extent ``(row0, col0, row1, col1)``: its regions' boxes, or their centroids."""
    boxes = np.array([box for _, box in metric_graph.nodes(data="bbox")], float).reshape(-1, 4)
    if len(boxes):
        return (*boxes[:, :2].min(axis=0).tolist(), *boxes[:, 2:].max(axis=0).tolist())
    centroids = np.array([c for _, c in metric_graph.nodes(data="centroid")], float).reshape(-1, 2)
    return (*centroids.min(axis=0).tolist(), *centroids.max(axis=0).tolist())


def refitted_graph(sketch_graph: nx.Graph, metric_graph: nx.Graph, transform: np.ndarray) -> nx.Graph:
    """A copy of the sketch graph whose centroids are moved into the metric map's frame and whose
    extent is the metric map's, so :func:`~ursim_core.matching.positions.region_positions`
    normalises both maps alike."""
    extent = _extent_of(metric_graph)
    moved = sketch_graph.copy()
    for _, data in moved.nodes(data=True):
        row, col = data["centroid"]
        data["centroid"] = (
            float(transform[0, 0] * row + transform[0, 1]),
            float(transform[1, 0] * col + transform[1, 1]),
        )
        data["bbox"] = extent
    return moved


def _refittable(prepared) -> bool:
    """Whether ``prepared`` has a position term to refit: signatures apart from positions, a
    position weight, and the metric regions' boxes (the extent positions are normalised by)."""
    descriptors = prepared.descriptors
    if descriptors is None or descriptors.signature_c is None or not prepared.config.position_weight:
        return False
    return all("bbox" in data for _, data in prepared.metric_graph.nodes(data=True))


def refit_from(prepared, pairs, match_once):
    """The preparation with the sketch laid on the metric map by ``pairs``, and its answer.

    Parameters
    ----------
    prepared : Prepared
        The planar matcher's preparation in one orientation.
    pairs : sequence of (sketch node, metric node)
        The pairs the scale and shift per axis are fitted to (:func:`fit_axis_transform`).
    match_once : callable
        ``match_once(prepared) -> MatchResult``.

    Returns
    -------
    (Prepared, MatchResult) or None
        None when there is no position term to refit or no fit (fewer than 3 pairs, degenerate).
    """
    if not _refittable(prepared):
        return None
    transform = fit_axis_transform(pairs, prepared.sketch_graph, prepared.metric_graph)
    if transform is None:
        return None
    return refit_by_transform(prepared, transform, match_once)


def refit_by_transform(prepared, transform, match_once):
    """The preparation with the sketch's positions carried into the metric map's frame by
    ``transform`` (a scale and shift per axis, as :func:`fit_axis_transform` gives), and its
    answer; None when there is no position term to refit.

    :func:`refit_from` lays the sketch by an answer's pairs; ``MatchConfig.window_start`` by the
    window of the metric map the sketch resembles
    (:func:`~ursim_core.matching.oriented.window_position_starts`)."""
    if not _refittable(prepared):
        return None
    descriptors, config = prepared.descriptors, prepared.config
    c_matrix = blend_position_arrays(
        descriptors.signature_c,
        refitted_positions(prepared.sketch_graph, descriptors.sketch_nodes, prepared.metric_graph, transform),
        metric_positions_of(descriptors, prepared.metric_graph),
        config.position_weight,
    )
    candidate = dataclasses.replace(
        prepared, descriptors=dataclasses.replace(descriptors, c_matrix=c_matrix), chosen=None
    )
    return candidate, match_once(candidate)


def refit_positions(prepared, result, match_once):
    """``(prepared, result)`` after one refit of the sketch's positions, or as given.

    Parameters
    ----------
    prepared : Prepared
        The planar matcher's preparation in one orientation.
    result : MatchResult
        Its answer.
    match_once : callable
        ``match_once(prepared) -> MatchResult`` (the configured m, automatic or fixed).

    Returns
    -------
    (Prepared, MatchResult)
        The refitted preparation and its answer when that answer's hypothesis score is lower;
        else the inputs unchanged.
    """
    refitted = refit_from(prepared, result.pairs, match_once)
    if refitted is not None and refitted[1].normalised_cost < result.normalised_cost:
        return refitted
    return prepared, result


def signature_start(prepared, match_once):
    """The answer matched without the position term (``c`` = the signature comparison alone).

    A start for :func:`refit_from` that does not depend on where the sketch was laid: on a
    sketch that shows part of the map, the first answer (positions normalised to each map's
    extent) can be wrong while the signatures and the structure still pair most regions right.
    None when there is no position term (the first answer already is this one).
    """
    descriptors = prepared.descriptors
    if descriptors is None or descriptors.signature_c is None or not prepared.config.position_weight:
        return None
    plain = dataclasses.replace(
        prepared, descriptors=dataclasses.replace(descriptors, c_matrix=descriptors.signature_c), chosen=None
    )
    return match_once(plain)
