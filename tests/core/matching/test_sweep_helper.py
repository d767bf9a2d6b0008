"""The helper process that shares a sweep over m: the same results as the sweep alone."""

from __future__ import annotations

import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.matching import MatchConfig, prepare, sweep_helper
from ursim_core.matching.auto_m import sweep


@pytest.fixture(scope="module")
def prepared():
    graph = random_region_graph(60, seed=5)
    copy, _ = perturbed_copy(graph, seed=6, size_noise=0.2, position_noise=25.0)
    return prepare(graph, copy, MatchConfig(orientation="upright"))


def _summary(results):
    return [(r.m, r.pairs, r.cost, r.normalised_cost, r.seeds_count, r.hypotheses, r.reason) for r in results]


def test_a_shared_sweep_gives_the_results_of_the_sweep_alone(prepared, monkeypatch):
    alone = sweep(prepared)
    monkeypatch.setattr(sweep_helper, "MIN_REGIONS", 0)
    asked = []
    ask = sweep_helper.Helper._ask

    def counted(self, m, seeds):
        asked.append(m)
        return ask(self, m, seeds)

    monkeypatch.setattr(sweep_helper.Helper, "_ask", counted)
    reported = []
    with sweep_helper.helping() as helper:
        assert helper is not None and sweep_helper.active(prepared, 20) is helper
        shared = sweep(prepared, progress=lambda fraction, message: reported.append(fraction))
        assert helper.alive
    assert _summary(shared) == _summary(alone)
    assert asked, "the helper computed none of the values of m"
    assert reported and reported[-1] == 1.0
    assert sweep_helper.active(prepared, 20) is None  # stopped with the block


def test_a_failed_helper_leaves_the_work_to_the_caller(prepared, monkeypatch):
    alone = sweep(prepared)
    monkeypatch.setattr(sweep_helper, "MIN_REGIONS", 0)

    def broken(self, m, seeds):
        raise OSError("the helper is gone")

    monkeypatch.setattr(sweep_helper.Helper, "_ask", broken)
    with sweep_helper.helping() as helper:
        shared = sweep(prepared)
        assert not helper.alive
    assert _summary(shared) == _summary(alone)


def test_small_pairs_and_other_matchers_do_not_use_the_helper(prepared):
    with sweep_helper.helping() as helper:
        assert helper is not None
        assert sweep_helper.active(prepared, 20) is None  # 60 regions, below MIN_REGIONS
    with sweep_helper.helping(enabled=False) as helper:
        assert helper is None and sweep_helper.active(prepared, 20) is None
