"""The planar matcher's C loop on graphs with long neighbour orders (a building's corridor) against Python.

Alignments whose tables exceed ``kernels.TABLE_CELLS`` run bit-parallel in C (csrc/bitalign.c), and
by the packed numba kernel or a table in Python: the same pairs in the same order, the same costs
and counts, at one m and over a sweep of m. Some tests lower ``TABLE_CELLS`` so that every
alignment, down to one element against one, runs bit-parallel.
"""

from __future__ import annotations

import random

import networkx as nx
import numpy as np
import pytest

from ursim_core.matching import MatchConfig, kernels, prepare
from ursim_core.matching.auto_m import matched_sweep
from ursim_core.matching.planar import planar_graph, planar_match
from ursim_core.matching.single import SeedSelector, pair_cost_matrix


def _hub_graph(rng, n: int, hubs=(0.9, 0.3)):
    """Regions at random points joined to 1-3 nearest others, and regions 0, 1, ... (corridors)
    joined to the given share of all the others: orders of hundreds of neighbours."""
    points = rng.uniform(0.0, 1000.0, size=(n, 2))
    graph = nx.Graph()
    graph.add_nodes_from((i, {"centroid": tuple(points[i])}) for i in range(n))
    for i in range(len(hubs), n):
        distances = np.hypot(*(points - points[i]).T)
        distances[: len(hubs)] = np.inf
        graph.add_edges_from((i, int(j)) for j in np.argsort(distances)[1 : 1 + int(rng.integers(1, 4))])
    for hub, share in enumerate(hubs):
        graph.add_edges_from((hub, other) for other in range(n) if other != hub and rng.uniform() < share)
    return planar_graph(graph)


def test_every_alignment_bit_parallel_gives_what_python_gives(
    c_kernel, monkeypatch, in_python, planar_answer, small_planar_graph
):
    """Small graphs with many ties, every alignment (seeds' rotations, arcs of one element) through
    the bit-parallel path: its backtrace breaks ties as the table's."""
    rng = np.random.default_rng(7)
    cases = []
    for trial in range(300):
        first, second = (
            small_planar_graph(rng, int(rng.integers(1, 16))),
            small_planar_graph(rng, int(rng.integers(1, 16))),
        )
        same = rng.uniform(size=(first.n_vertices, second.n_vertices)) < rng.choice([0.1, 0.3, 0.6, 0.9])
        same[rng.integers(first.n_vertices), rng.integers(second.n_vertices)] = True
        options = {
            "rotation_search": ("min", "first")[trial % 2],
            "reflections": trial % 4 < 2,
            "pair_costs": np.round(rng.uniform(0, 4, size=same.shape)) / 4 if trial % 5 else None,
            "pair_cost_weight": (0.0, 0.5, 1.0, 2.0)[trial % 4],
        }
        cases.append((first, second, same, options))
    monkeypatch.setattr(kernels, "TABLE_CELLS", 0)
    compiled = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    in_python()
    reference = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    assert compiled == reference
    assert sum(len(answer[0]) > 2 for answer in reference) > 100


@pytest.mark.parametrize("table_cells", [1 << 16, 1 << 8])
def test_long_orders_give_in_c_what_python_gives(c_kernel, monkeypatch, table_cells, in_python, planar_answer):
    """Hubs of about 330 and 110 neighbours, dense and sparse "same" relations (many equal
    distances), seeds on the hubs (rotations of their orders), both rotation searches, reflections
    and pair costs on a grid of quarters; with the default table, and with a small one (the arcs
    between a hub's locks bit-parallel too)."""
    monkeypatch.setattr(kernels, "TABLE_CELLS", table_cells)
    rng = np.random.default_rng(14)
    cases = []
    for trial in range(8):
        first = _hub_graph(rng, int(rng.integers(330, 400)))
        second = _hub_graph(rng, int(rng.integers(330, 400)))
        assert max(map(len, first.neighbours)) > 256 and max(map(len, second.neighbours)) > 256
        same = rng.uniform(size=(first.n_vertices, second.n_vertices)) < (0.15, 0.5, 0.85)[trial % 3]
        seeds = sorted({(int(rng.integers(first.n_vertices)), int(rng.integers(second.n_vertices))) for _ in range(12)})
        seeds += [(0, 0), (1, 0), (0, 1), (0, int(rng.integers(2, second.n_vertices)))]
        random.Random(trial).shuffle(seeds)
        options = {
            "seeds": seeds,
            "rotation_search": ("min", "first")[trial % 2],
            "reflections": trial % 4 < 2,
            "pair_costs": np.round(rng.uniform(0, 4, size=same.shape)) / 4 if trial % 3 else None,
            "pair_cost_weight": (0.0, 0.5, 1.0, 2.0)[trial % 4],
        }
        cases.append((first, second, same, options))
    compiled = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    in_python()
    reference = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    assert compiled == reference
    assert sum(len(answer[0]) > 100 for answer in reference) >= 4  # expansions through the hubs


@pytest.mark.parametrize("score", ["signature", "substitutions", "structure"])
def test_a_sweep_over_long_orders_gives_in_c_what_python_gives_at_every_m(c_kernel, score, in_python):
    """sweep_compiled, on one thread and on two, against Python's planar_match at each m from the
    same seeds (c on a grid of eighths: ties at the seed cap and between values of m)."""
    rng = np.random.default_rng({"signature": 1, "substitutions": 2, "structure": 3}[score])
    first, second = _hub_graph(rng, 320), _hub_graph(rng, 300, hubs=(0.9, 0.5))
    c_matrix = np.round(rng.uniform(0.0, 1.0, size=(first.n_vertices, second.n_vertices)) * 8) / 8
    config = MatchConfig(hypothesis_score=score, score_weight=0.0 if score == "structure" else 2.0, reflections=True)
    selector = SeedSelector(c_matrix, 16)
    ms = [0.0, 0.125, 0.3, 0.5]
    options = {"score": score, "weight": config.score_weight, "reflections": True}
    one = kernels.sweep_compiled(first, second, c_matrix, *selector.ordered, 16, ms, **options, threads=1)
    two = kernels.sweep_compiled(first, second, c_matrix, *selector.ordered, 16, ms, **options, threads=2)
    assert one == two
    in_python()
    reference = []
    for m in ms:
        seeds = selector.at(m)
        if not seeds:
            reference.append(([], None, 0, 0, 0, 0))
            continue
        result = planar_match(
            first, second, c_matrix <= m, seeds=seeds, reflections=True,
            pair_costs=pair_cost_matrix(config, c_matrix, m), pair_cost_weight=config.score_weight,
        )  # fmt: skip
        cost = result.cost
        reference.append(
            (result.pairs, cost, result.structural_cost, result.hypotheses, result.seeds_expanded, len(seeds))
        )
    assert [(entry, type(entry[1])) for entry in one] == [(entry, type(entry[1])) for entry in reference]
    assert sum(len(entry[0]) > 100 for entry in reference) >= 2


@pytest.fixture(scope="module")
def building_pair():
    """Two generated 2000 px buildings (a corridor bordering hundreds of rooms), prepared in one
    orientation as ``ursim match`` segments them."""
    from ursim_core.segmentation import segment, segment_canonical
    from ursim_core.synth import make_large_building

    sketch = segment_canonical(make_large_building(2000, seed=0).free, preset="default")
    metric = segment(make_large_building(2000, seed=1).free, preset="default")
    return prepare(sketch, metric, MatchConfig(orientation=270.0, mirrored=True, position_refits=0))


def test_a_buildings_sweep_is_the_same_in_c_and_in_python(c_kernel, building_pair, monkeypatch, in_python):
    import ursim_core.matching.single as single

    prepared = building_pair
    # The corridor borders about 250 rooms: with a smaller table, its alignments are bit-parallel.
    assert max(map(len, prepared.metric_planar.neighbours)) > 200
    monkeypatch.setattr(kernels, "TABLE_CELLS", 1 << 12)
    swept = []
    monkeypatch.setattr(
        single,
        "sweep_compiled",
        lambda *args, **kwargs: swept.append(kernels.sweep_compiled(*args, **kwargs)) or swept[-1],
    )
    compiled = [(r.m, r.pairs, r.cost, r.seeds_count, r.hypotheses, r.reason) for r in matched_sweep(prepared)[0]]
    assert swept and swept[0] is not None  # the whole sweep in one call of the C loop
    in_python()
    monkeypatch.setattr(single, "match_sweep", lambda *args: None)
    reference = [(r.m, r.pairs, r.cost, r.seeds_count, r.hypotheses, r.reason) for r in matched_sweep(prepared)[0]]
    assert compiled == reference
    assert max(len(entry[1]) for entry in reference) > 100
