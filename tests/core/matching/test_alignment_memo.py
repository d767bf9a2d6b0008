"""The remembered alignments give what the edit distance computes, and forget nothing they need."""

import random

import networkx as nx
import numpy as np
import pytest

from ursim_core.matching import alignment_memo
from ursim_core.matching.alignment_memo import arc_pairs, forget, seed_alignment
from ursim_core.matching.edit_distance import aligned_index_pairs, aligned_pairs, cyclic_align
from ursim_core.matching.planar import planar_graph, planar_match


@pytest.fixture(autouse=True)
def _empty_memos():
    forget()
    yield
    forget()


def _random_case(rng: random.Random):
    n1, n2 = rng.randint(1, 6), rng.randint(1, 6)
    same = [[rng.random() < 0.4 for _ in range(n2)] for _ in range(n1)]
    first = rng.sample(range(n1), rng.randint(1, n1))
    second = rng.sample(range(n2), rng.randint(1, n2))
    return first, second, same


@pytest.mark.parametrize("rotation_search", ["min", "first"])
@pytest.mark.parametrize("reflections", [False, True])
def test_seed_alignment_is_the_cyclic_alignment(rotation_search, reflections):
    rng = random.Random(7)
    for _ in range(400):
        first, second, same = _random_case(rng)
        expected = cyclic_align(first, second, same, rotation_search=rotation_search, reflections=reflections)
        wanted = (expected.reflected, tuple(aligned_pairs(expected)))
        # Twice: computed, then remembered.
        for _ in range(2):
            found = seed_alignment(first, second, same, rotation_search=rotation_search, reflections=reflections)
            assert found == wanted


def test_arc_pairs_are_the_aligned_index_pairs():
    rng = random.Random(11)
    for _ in range(400):
        first, second, same = _random_case(rng)
        wanted = tuple(aligned_index_pairs(first, second, same))
        assert arc_pairs(first, second, same) == wanted
        assert arc_pairs(first, second, same) == wanted


def test_a_cell_between_the_sequences_is_part_of_the_key():
    first, second = [0, 1], [0, 1]
    crossed = [[False, True], [True, False]]
    straight = [[True, False], [False, True]]
    assert arc_pairs(first, second, crossed) == ((0, 0), (1, 1))
    assert arc_pairs([0], [0, 1], crossed) == ((0, 1),)
    assert arc_pairs([0], [0, 1], straight) == ((0, 0),)
    assert seed_alignment([0, 1, 2], [0, 1, 2], [[i == (j + 1) % 3 for j in range(3)] for i in range(3)])[1] == (
        (1, 0),
        (2, 1),
        (0, 2),
    )
    assert seed_alignment([0, 1, 2], [0, 1, 2], [[i == j for j in range(3)] for i in range(3)])[1] == (
        (0, 0),
        (1, 1),
        (2, 2),
    )


def test_a_cell_outside_the_sequences_is_not():
    first, second = [0], [1]
    same = [[False, True], [True, False]]
    arc_pairs(first, second, same)
    changed_elsewhere = [[True, True], [False, False]]
    before = len(alignment_memo._arcs)
    assert arc_pairs(first, second, changed_elsewhere) == ((0, 1),)
    assert len(alignment_memo._arcs) == before  # remembered, not computed again


def test_the_memos_stay_bounded(monkeypatch):
    monkeypatch.setattr(alignment_memo, "MEMO_LIMIT", 3)
    rng = random.Random(3)
    for _ in range(50):
        first, second, same = _random_case(rng)
        seed_alignment(first, second, same, reflections=True)
        arc_pairs(first, second, same)
        assert len(alignment_memo._seeds) <= 3 and len(alignment_memo._arcs) <= 3


def test_arrays_are_aligned_without_the_memo():
    same = np.array([[True, False], [False, True]])
    assert arc_pairs([0, 1], [0, 1], same) == ((0, 0), (1, 1))
    assert seed_alignment([0, 1], [1, 0], same) == (False, ((1, 1), (0, 0)))
    assert not alignment_memo._arcs and not alignment_memo._seeds


def _random_planar(rng: random.Random, n: int):
    graph = nx.random_labeled_tree(n, seed=rng.randrange(1 << 30)) if n > 1 else nx.empty_graph(1)
    for _ in range(n // 2):
        a, b = rng.sample(range(n), 2) if n > 1 else (0, 0)
        if a != b:
            graph.add_edge(a, b)
    nx.set_node_attributes(graph, {v: (rng.random() * 100, rng.random() * 100) for v in graph}, "centroid")
    return planar_graph(graph)


def test_planar_matches_in_a_row_are_those_of_fresh_memos():
    """A sweep's matches reuse alignments of earlier ones: each answer is the one computed afresh."""
    rng = random.Random(5)
    for _ in range(30):
        first, second = _random_planar(rng, rng.randint(2, 9)), _random_planar(rng, rng.randint(2, 9))
        costs = np.array([[rng.random() for _ in range(second.n_vertices)] for _ in range(first.n_vertices)])
        answers = []
        for m in (0.2, 0.4, 0.6, 0.8):
            same = costs <= m
            kept = planar_match(first, second, same, reflections=True, pair_costs=costs, pair_cost_weight=8.0)
            forget()
            fresh = planar_match(first, second, same, reflections=True, pair_costs=costs, pair_cost_weight=8.0)
            assert (kept.pairs, kept.cost) == (fresh.pairs, fresh.cost)
            answers.append(kept.pairs)
        assert any(answers)
