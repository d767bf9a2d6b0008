"""Planar seed-and-expand matcher (Algorithm 1)."""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.matching.planar import (
    PlanarGraph,
    cyclic_neighbours,
    hypothesis_cost,
    planar_graph,
    planar_match,
)


def _geometric_graph(positions, edges):
    graph = nx.Graph()
    for node, (row, col) in positions.items():
        graph.add_node(node, centroid=(float(row), float(col)))
    graph.add_edges_from(edges)
    return graph


def _wheel(mirror=False, labels=None):
    """Centre 0 and a rim of six regions 1..6 around it (clockwise on screen when not mirrored)."""
    labels = labels or {i: i for i in range(7)}
    positions = {labels[0]: (0.0, 0.0)}
    for k in range(1, 7):
        angle = 2 * math.pi * k / 6
        col = math.cos(angle) * (-1 if mirror else 1)
        positions[labels[k]] = (math.sin(angle) * 10, col * 10)
    edges = [(labels[0], labels[k]) for k in range(1, 7)]
    edges += [(labels[k], labels[k % 6 + 1]) for k in range(1, 7)]
    return _geometric_graph(positions, edges)


def test_cyclic_order_is_clockwise_on_screen_from_smallest_id():
    # Centre with neighbours right (id 5), below (id 2), left (id 9), above (id 7).
    graph = _geometric_graph(
        {0: (0, 0), 5: (0, 1), 2: (1, 0), 9: (0, -1), 7: (-1, 0)}, [(0, 5), (0, 2), (0, 9), (0, 7)]
    )
    order = cyclic_neighbours(graph, [0, 2, 5, 7, 9])[0]
    # Reference = smallest id (2, below); then increasing image angle: left, above, right.
    assert [[0, 2, 5, 7, 9][i] for i in order] == [2, 9, 7, 5]


def test_hypothesis_cost_hand_worked():
    path = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1], [0, 2], [1]], edges=[(0, 1), (1, 2)])
    triangle = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1, 2], [0, 2], [0, 1]], edges=[(0, 1), (1, 2), (0, 2)])
    assert hypothesis_cost(path, path, [(0, 0), (1, 1), (2, 2)]) == 0
    # Everything matched but the triangle has one extra edge among matched vertices: |2 - 3| = 1.
    assert hypothesis_cost(path, triangle, [(0, 0), (1, 1), (2, 2)]) == 1
    # One pair: 2 + 2 unmatched vertices, 2 + 3 edges touching them, 0 inner edges on both sides.
    assert hypothesis_cost(path, triangle, [(1, 1)]) == 9


def test_identity_recovered_on_relabelled_copy():
    graph = _wheel()
    relabel = {0: 40, 1: 12, 2: 31, 3: 18, 4: 25, 5: 11, 6: 37}
    copy = _wheel(labels=relabel)
    first, second = planar_graph(graph), planar_graph(copy)
    truth = {i: second.nodes.index(relabel[node]) for i, node in enumerate(first.nodes)}
    # Only the centre and one rim region compare equal to their counterparts (the wheel is
    # symmetric, so one rim region fixes the rotation); the rest must come from expansion.
    same = [[j == truth[i] and i in (0, 1) for j in range(7)] for i in range(7)]
    result = planar_match(first, second, same)
    assert sorted(result.pairs) == sorted(truth.items())
    assert result.cost == 0


def test_first_rotation_bug_loses_a_pair_that_the_minimum_search_finds():
    star = _geometric_graph(
        {0: (0, 0), 1: (0, 10), 2: (10, 0), 3: (0, -10), 4: (-10, 0)}, [(0, 1), (0, 2), (0, 3), (0, 4)]
    )
    # Same star, but ids chosen so that the smallest neighbour id sits at a different place.
    rotated = nx.relabel_nodes(star, {0: 0, 1: 4, 2: 1, 3: 2, 4: 3})
    first, second = planar_graph(star), planar_graph(rotated)
    truth = {0: 0, 1: 4, 2: 1, 3: 2, 4: 3}
    same = [[truth[i] == j for j in range(5)] for i in range(5)]
    best = planar_match(first, second, same, seeds=[(0, 0)])
    assert sorted(best.pairs) == sorted(truth.items())
    released = planar_match(first, second, same, seeds=[(0, 0)], rotation_search="first")
    assert len(released.pairs) == 4 and set(released.pairs) < set(truth.items())
    assert released.cost > best.cost


def test_reflections_match_a_mirrored_drawing():
    first, second = planar_graph(_wheel()), planar_graph(_wheel(mirror=True))
    same = [[i == j for j in range(7)] for i in range(7)]
    only_centre = [(0, 0)]
    plain = planar_match(first, second, same, seeds=only_centre)
    mirrored = planar_match(first, second, same, seeds=only_centre, reflections=True)
    assert sorted(mirrored.pairs) == [(i, i) for i in range(7)] and mirrored.cost == 0
    # Without reflections the rim is walked the wrong way round: a structurally valid (the wheel is
    # symmetric) but wrong correspondence.
    assert sorted(plain.pairs) != [(i, i) for i in range(7)]


def test_no_seed_gives_empty_result():
    path = PlanarGraph(nodes=[0, 1], neighbours=[[1], [0]], edges=[(0, 1)])
    result = planar_match(path, path, [[False, False], [False, False]])
    assert result.pairs == [] and result.cost == math.inf and result.hypotheses == 0


def test_single_seed_hypotheses_win_ties_and_seeds_are_consumed():
    path = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1], [0, 2], [1]], edges=[(0, 1), (1, 2)])
    lonely = PlanarGraph(nodes=[0], neighbours=[[]], edges=[])
    same = [[True], [True], [True]]
    result = planar_match(path, lonely, same)
    # Nothing can expand: every hypothesis costs the same, so the first one-pair hypothesis wins.
    assert result.pairs == [(0, 0)]
    everything = [[True] * 3 for _ in range(3)]
    full = planar_match(path, path, everything, keep_alternatives=True)
    assert full.cost == 0
    # The first expansion, from (0, 0), reaches (1, 1) and (2, 2), which are then not expanded again.
    assert full.seeds_expanded < 9
    assert full.alternatives[0][1] == [(0, 0), (1, 1), (2, 2)]


def test_deterministic_and_accurate_on_generated_graphs():
    graph = random_region_graph(60, seed=4)
    copy, mapping = perturbed_copy(graph, seed=5)
    from ursim_core.matching import MatchConfig, match

    results = [match(graph, copy, config=MatchConfig(m=0.01)) for _ in range(2)]
    assert results[0].pairs == results[1].pairs
    correct = sum(1 for a, b in results[0].pairs if mapping[a] == b)
    assert correct >= 0.95 * graph.number_of_nodes()


@pytest.mark.parametrize("rotation_search", ["min", "first"])
def test_pairs_are_one_to_one(rotation_search):
    graph = random_region_graph(40, seed=8)
    copy, _ = perturbed_copy(graph, seed=9, size_noise=0.5, position_noise=60)
    first, second = planar_graph(graph), planar_graph(copy)
    rng = np.random.default_rng(0)
    same = (rng.uniform(size=(40, 40)) < 0.1).tolist()
    result = planar_match(first, second, same, rotation_search=rotation_search)
    sketch_side = [a for a, _ in result.pairs]
    metric_side = [b for _, b in result.pairs]
    assert len(set(sketch_side)) == len(sketch_side) and len(set(metric_side)) == len(metric_side)
    assert result.cost == hypothesis_cost(first, second, result.pairs)


@pytest.mark.parametrize("n_regions", [12, 45])
def test_lists_and_arrays_give_the_same_answer(monkeypatch, n_regions):
    """Sketch-sized pairs read "same" as lists and count inner edges in Python: the answer and
    every hypothesis are those of the array paths that larger pairs take."""
    import ursim_core.matching.planar as planar

    graph = random_region_graph(n_regions, seed=3)
    copy, _ = perturbed_copy(graph, seed=4, size_noise=0.3, position_noise=40)
    first, second = planar_graph(graph), planar_graph(copy)
    rng = np.random.default_rng(n_regions)
    same = rng.uniform(size=(n_regions, n_regions)) < 0.2
    costs = rng.uniform(size=(n_regions, n_regions))

    def answer():
        result = planar_match(
            first, second, same, reflections=True, keep_alternatives=True, pair_costs=costs, pair_cost_weight=2.0
        )
        return result.pairs, result.cost, result.structural_cost, result.hypotheses, result.alternatives

    monkeypatch.setattr(planar, "_LISTED_COSTS", n_regions * n_regions)
    monkeypatch.setattr(planar, "_LISTED_ENTRIES", 10**9)
    listed = answer()
    monkeypatch.setattr(planar, "_LISTED_COSTS", 0)
    monkeypatch.setattr(planar, "_LISTED_ENTRIES", -1)
    assert answer() == listed
    assert len(listed[4]) > 3  # several expansions were compared, not only one-pair hypotheses
