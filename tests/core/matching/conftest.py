"""Fixtures shared by the matching tests."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from ursim_core.matching import kernels
from ursim_core.matching.planar import planar_graph


@pytest.fixture
def c_kernel():
    """The matcher's C module; the test is skipped where it cannot be built (no C compiler)."""
    module = kernels.kernel()
    if module is None:
        pytest.skip("the matcher's C kernels could not be built here (no C compiler)")
    return module


@pytest.fixture
def in_python(monkeypatch):
    """Call it to run the next planar matches in Python (the reference), not in the C loop."""
    return lambda: monkeypatch.setattr(kernels, "kernel", lambda: None)


def _planar_answer(result) -> tuple:
    return (
        result.pairs,
        result.cost,
        type(result.cost),
        result.structural_cost,
        result.hypotheses,
        result.seeds_expanded,
    )


@pytest.fixture
def planar_answer():
    """``planar_answer(result)``: every field of a planar match that the C loop must give as Python does."""
    return _planar_answer


def _small_planar_graph(rng, n: int):
    points = rng.uniform(0, 100, size=(n, 2))
    graph = nx.Graph()
    graph.add_nodes_from((i, {"centroid": tuple(points[i])}) for i in range(n))
    for i in range(n):
        distances = np.hypot(*(points - points[i]).T)
        graph.add_edges_from((i, int(j)) for j in np.argsort(distances)[1 : 1 + rng.integers(1, 5)])
    return planar_graph(graph)


@pytest.fixture
def small_planar_graph():
    """``small_planar_graph(rng, n)``: ``n`` regions at random points, each joined to its 1-4 nearest
    others (neighbour orders from the centroids), as a planar graph."""
    return _small_planar_graph
