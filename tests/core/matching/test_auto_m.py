"""Automatic choice of m."""

from __future__ import annotations

from dataclasses import replace

import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.matching import MatchConfig, match, match_prepared, prepare
from ursim_core.matching.auto_m import choose_m, chosen_of, matched_sweep, sweep


@pytest.fixture(scope="module")
def pair():
    graph = random_region_graph(12, seed=21)
    copy, mapping = perturbed_copy(graph, seed=22, size_noise=0.15, position_noise=20.0)
    return graph, copy, mapping


@pytest.mark.parametrize("rule", ["score", "structure"])
def test_auto_m_is_in_the_grid_and_deterministic(pair, rule):
    graph, copy, _ = pair
    config = MatchConfig(auto_rule=rule)
    first = match(graph, copy, config=config)
    second = match(graph, copy, config=config)
    assert first.m in config.m_grid
    assert (first.m, first.pairs) == (second.m, second.pairs)
    assert sorted(first.m_scan) == sorted(config.m_grid)
    assert first.m_scan[first.m] == min(first.m_scan.values())
    # The smallest m among equally good ones is chosen.
    assert all(value > first.m_scan[first.m] for m, value in first.m_scan.items() if m < first.m)


def test_auto_result_is_the_fixed_m_result(pair):
    graph, copy, _ = pair
    auto = match(graph, copy)
    fixed = match(graph, copy, config=MatchConfig(m=auto.m))
    assert auto.pairs == fixed.pairs and auto.cost == pytest.approx(fixed.cost)


def test_sweep_reuses_identical_thresholds(pair):
    graph, copy, _ = pair
    prepared = prepare(graph, copy, MatchConfig())
    results = sweep(prepared, [0.0, 0.0001, 0.3])
    assert [r.m for r in results] == [0.0, 0.0001, 0.3]
    for r in results:
        assert r.pairs == match_prepared(prepared, r.m).pairs


def test_known_results_stand_in_for_matching_and_change_nothing(pair):
    graph, copy, _ = pair
    prepared = prepare(graph, copy, MatchConfig())
    coarse = replace(prepared, config=prepared.config.replace(m_grid=prepared.config.m_grid[1::2]))
    _, known = matched_sweep(coarse)
    # Only results that were matched (not reused from the previous m) are offered.
    assert known and set(known) <= set(coarse.config.m_grid)
    plain, reused = sweep(prepared), sweep(prepared, known=known)
    assert [(r.m, r.pairs, r.cost, r.reason) for r in reused] == [(r.m, r.pairs, r.cost, r.reason) for r in plain]
    assert all(r.config == prepared.config for r in reused)  # the sweep's own options are recorded
    assert choose_m(prepared, known=known).pairs == choose_m(prepared).pairs
    # A known result is taken as it is: a planted one shows where the sweep would have matched.
    planted = sweep(prepared, known={m: replace(result, pairs=[(-1, -1)]) for m, result in known.items()})
    assert any(r.pairs == [(-1, -1)] for r in planted)


def test_chosen_of_is_what_choose_m_picks(pair):
    graph, copy, _ = pair
    prepared = prepare(graph, copy, MatchConfig())
    chosen, picked = chosen_of(prepared, sweep(prepared)), choose_m(prepared)
    assert (chosen.m, chosen.pairs, chosen.m_scan) == (picked.m, picked.pairs, picked.m_scan)


def test_auto_recovers_a_noisy_copy(pair):
    graph, copy, mapping = pair
    result = match(graph, copy)
    correct = sum(1 for a, b in result.pairs if mapping[a] == b)
    assert correct >= 10


def test_custom_grid_is_respected(pair):
    graph, copy, _ = pair
    config = MatchConfig(m_grid=(0.05, 0.15))
    assert choose_m(prepare(graph, copy, config)).m in (0.05, 0.15)
    assert replace(config, m=0.05).m == 0.05


def test_sweep_reports_progress_once_per_m():
    import networkx as nx

    from ursim_core.matching import MatchConfig, prepare
    from ursim_core.matching.auto_m import sweep

    g = nx.cycle_graph(4)
    nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    calls = []
    results = sweep(prepare(g, g.copy(), MatchConfig()), [0.0, 0.1, 0.2], progress=lambda f, m: calls.append((f, m)))
    assert len(results) == 3
    assert [f for f, _ in calls] == pytest.approx([1 / 3, 2 / 3, 1.0])
    assert calls[-1][1] == "matching at m = 0.200"
