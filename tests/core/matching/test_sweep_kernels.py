"""The sweep over m and the refit's fit in C against what they replace: match_at at each m, NumPy's fit."""

from __future__ import annotations

import dataclasses

import networkx as nx
import numpy as np
import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.matching import MatchConfig, kernels, prepare
from ursim_core.matching.auto_m import matched_sweep
from ursim_core.matching.constraints import MatchConstraints
from ursim_core.matching.refit import _fitted_in_numpy, fit_axis_transform
from ursim_core.matching.single import SeedSelector, match_at, match_sweep, seed_cap


def _fields(result):
    """Every field of a MatchResult (arrays by value)."""
    values = []
    for field in dataclasses.fields(result):
        value = getattr(result, field.name)
        if isinstance(value, np.ndarray):
            value = (value.shape, value.tobytes())
        elif isinstance(value, tuple) and value and isinstance(value[0], np.ndarray):
            value = tuple((array.shape, array.tobytes()) for array in value)
        values.append((field.name, value, type(value)))
    return values


def _pairs_of_graphs(count):
    """Sketch-sized pairs: a random region graph against a perturbed copy, or against another."""
    for trial in range(count):
        first = random_region_graph(int(3 + trial % 14), seed=trial)
        if trial % 3:
            second, _ = perturbed_copy(first, seed=trial, position_noise=4.0 + trial % 7)
        else:
            second = random_region_graph(int(3 + (trial * 7) % 14), seed=1000 + trial)
        yield trial, first, second


_CONFIGS = (
    MatchConfig(orientation="upright", position_refits=0, resampling_vote=False),
    MatchConfig(orientation="upright", position_refits=0, hypothesis_score="substitutions", score_weight=1.0),
    MatchConfig(orientation="upright", position_refits=0, hypothesis_score="structure"),
    MatchConfig(orientation="upright", position_refits=0, max_seeds=3, reflections=True),
    MatchConfig(orientation="upright", position_refits=0, rotation_search="first", score_weight=0.0),
)


def test_the_sweep_in_c_gives_what_match_at_gives_at_every_m(c_kernel):
    """Field by field, for every hypothesis score, a seed cap that bites, reflections and the
    released code's rotation search; c rounded to a coarse grid on some pairs, so that many pairs
    tie at the seed cap and at the values of m."""
    compared = capped = 0
    for trial, first, second in _pairs_of_graphs(60):
        config = _CONFIGS[trial % len(_CONFIGS)]
        prepared = prepare(first, second, config)
        if trial % 2:
            coarse = np.round(prepared.c_matrix * 8) / 8
            prepared = dataclasses.replace(
                prepared, descriptors=dataclasses.replace(prepared.descriptors, c_matrix=coarse)
            )
        grid = [float(m) for m in np.linspace(0.0, 0.6, 13)]
        selector = SeedSelector(prepared.c_matrix, seed_cap(config.max_seeds, *prepared.c_matrix.shape))
        swept = match_sweep(prepared, grid, selector)
        assert swept is not None
        one_by_one = [match_at(prepared, m, seed_selector=selector) for m in grid]
        assert [_fields(result) for result in swept] == [_fields(result) for result in one_by_one]
        compared += len(grid)
        capped += sum(result.seeds_count == 3 for result in swept if config.max_seeds == 3)
    assert compared == 60 * 13 and capped > 10


def test_a_sweep_over_m_is_the_same_with_and_without_the_c_sweep(c_kernel, monkeypatch):
    import ursim_core.matching.single as single

    for trial, first, second in _pairs_of_graphs(12):
        prepared = prepare(first, second, _CONFIGS[trial % len(_CONFIGS)])
        compiled = matched_sweep(prepared)
        monkeypatch.setattr(single, "match_sweep", lambda *args: None)
        reference = matched_sweep(prepared)
        monkeypatch.undo()
        assert [_fields(result) for result in compiled[0]] == [_fields(result) for result in reference[0]]
        assert sorted(compiled[1]) == sorted(reference[1])


def test_a_building_sized_pairs_sweep_runs_on_two_threads_with_the_same_results(c_kernel, monkeypatch):
    import ursim_core.matching.single as single

    threads = []

    def recorded(*args, **kwargs):
        threads.append(kwargs["threads"])
        return kernels.sweep_compiled(*args, **kwargs)

    monkeypatch.setattr(single, "sweep_compiled", recorded)
    monkeypatch.setenv("URSIM_THREADS", "4")
    for trial, first, second in _pairs_of_graphs(6):
        prepared = prepare(first, second, _CONFIGS[trial % len(_CONFIGS)])
        monkeypatch.setattr(single, "THREADED_REGIONS", 10**9)
        alone = matched_sweep(prepared)[0]
        monkeypatch.setattr(single, "THREADED_REGIONS", 0)  # every pair counts as building-sized
        shared = matched_sweep(prepared)[0]
        assert [_fields(result) for result in shared] == [_fields(result) for result in alone]
    assert threads == [1, 2] * 6


def test_a_worker_told_one_thread_sweeps_a_building_sized_pair_on_one(c_kernel, monkeypatch):
    """``ursim evaluate``'s and ``match-batch``'s workers are told their share of the CPUs
    (``URSIM_THREADS``): a building-sized pair's sweep then takes no second thread."""
    import ursim_core.matching.single as single

    threads = []

    def recorded(*args, **kwargs):
        threads.append(kwargs["threads"])
        return kernels.sweep_compiled(*args, **kwargs)

    monkeypatch.setattr(single, "sweep_compiled", recorded)
    monkeypatch.setattr(single, "THREADED_REGIONS", 0)
    monkeypatch.setenv("URSIM_THREADS", "1")
    _, first, second = next(iter(_pairs_of_graphs(1)))
    matched_sweep(prepare(first, second, _CONFIGS[0]))
    assert threads == [1]


def test_the_sweep_in_c_leaves_constraints_nan_and_other_matchers_to_match_at(c_kernel):
    graph = random_region_graph(6, seed=3)
    prepared = prepare(graph, graph.copy(), _CONFIGS[0])
    selector = SeedSelector(prepared.c_matrix, seed_cap("auto", 6, 6))
    assert match_sweep(prepared, [0.1, 0.2], selector) is not None
    constrained = dataclasses.replace(prepared, constraints=MatchConstraints(fixed=((0, 0),)))
    assert match_sweep(constrained, [0.1, 0.2], selector) is None
    hungarian = dataclasses.replace(prepared, config=prepared.config.replace(matcher="hungarian"))
    assert match_sweep(hungarian, [0.1, 0.2], selector) is None
    with_nan = prepared.c_matrix.copy()
    with_nan[0, 0] = np.nan
    nan_prepared = dataclasses.replace(
        prepared, descriptors=dataclasses.replace(prepared.descriptors, c_matrix=with_nan)
    )
    assert match_sweep(nan_prepared, [0.1, 0.2], SeedSelector(with_nan, 36)) is None
    # A selector with another cap than the configured one cannot give the configured seeds.
    assert match_sweep(prepared, [0.1, 0.2], SeedSelector(prepared.c_matrix, 2)) is None


def test_bad_arguments_are_refused_by_the_sweep_kernel(c_kernel):
    graph = random_region_graph(4, seed=0)
    prepared = prepare(graph, graph.copy(), _CONFIGS[0])
    first, second = prepared.sketch_planar, prepared.metric_planar
    c_matrix = prepared.c_matrix
    order = np.argsort(c_matrix.ravel(), kind="stable")
    values = c_matrix.ravel()[order]
    ms = np.array([0.1, 0.2])
    with pytest.raises(ValueError, match="must be n1 x n2"):
        kernels.sweep_compiled(first, second, c_matrix[:2], order, values, 10, ms)
    with pytest.raises(ValueError, match="index c"):
        kernels.sweep_compiled(first, second, c_matrix, order + 100, values, 10, ms)
    with pytest.raises(ValueError, match="values must ascend"):
        kernels.sweep_compiled(first, second, c_matrix, order, values[::-1].copy(), 10, ms)
    with pytest.raises(TypeError, match="planar_sweep: c "):
        c_kernel.planar_sweep(*first.flat_orders[:2], *second.flat_orders[:2], 1, 1, c_matrix.astype(np.float32),
                              order, values, 10, ms, 1, 1.0, 1, 0, 1, 1 << 16)  # fmt: skip
    with pytest.raises(ValueError, match="threads >= 1"):
        c_kernel.planar_sweep(*first.flat_orders[:2], *second.flat_orders[:2], 1, 1, c_matrix, order, values, 10,
                              ms, 1, 1.0, 1, 0, 0, 1 << 16)  # fmt: skip


def _fit_case(rng, n, outliers=0):
    sketch, metric = nx.Graph(), nx.Graph()
    for k in range(n):
        row, col = rng.uniform(0, 500, 2)
        noise = 200.0 if k < outliers else 10.0
        sketch.add_node(k, centroid=(float(row), float(col)), size=int(rng.integers(1, 4000)))
        metric.add_node(
            k,
            centroid=(float(1.4 * row + 30 + rng.normal(0, noise)), float(0.7 * col - 8 + rng.normal(0, noise))),
            size=int(rng.integers(1, 4000)),
        )
    return [(k, k) for k in range(n)], sketch, metric


def test_the_refits_fit_in_c_is_numpys_to_rounding(c_kernel):
    rng = np.random.default_rng(5)
    fitted = 0
    for trial in range(600):
        pairs, sketch, metric = _fit_case(rng, int(rng.integers(3, 16)), outliers=trial % 4)
        source = np.array([sketch.nodes[a]["centroid"] for a, _ in pairs])
        target = np.array([metric.nodes[b]["centroid"] for _, b in pairs])
        weights = np.sqrt([min(sketch.nodes[a]["size"], metric.nodes[b]["size"]) for a, b in pairs])
        compiled = kernels.fit_axes_compiled(source, target, weights, rounds=3, cutoff=3.0)
        reference = _fitted_in_numpy(source, target, weights)
        if reference is None:
            assert compiled is kernels.NO_FIT
            continue
        assert compiled is not kernels.NO_FIT and compiled is not None
        assert np.allclose(np.array(compiled), reference, rtol=1e-9, atol=1e-9)
        fitted += 1
    assert fitted > 500


def test_a_fit_with_one_x_or_too_few_kept_pairs_is_numpys_answer(c_kernel):
    # Three pairs sharing one sketch column: that axis is fitted by lstsq in NumPy.
    sketch, metric = nx.Graph(), nx.Graph()
    for k, (row, col) in enumerate([(0.0, 5.0), (10.0, 5.0), (20.0, 5.0 + 1e-13)]):
        sketch.add_node(k, centroid=(row, col), size=100)
        metric.add_node(k, centroid=(2 * row + 1, col + k), size=100)
    source = np.array([sketch.nodes[k]["centroid"] for k in range(3)])
    target = np.array([metric.nodes[k]["centroid"] for k in range(3)])
    assert kernels.fit_axes_compiled(source, target, np.full(3, 10.0), rounds=3, cutoff=3.0) is None
    # Zero weights leave fewer than two pairs: no fit, in both.
    weights = np.array([10.0, 0.0, 0.0])
    assert kernels.fit_axes_compiled(source, target, weights, rounds=3, cutoff=3.0) is kernels.NO_FIT
    assert _fitted_in_numpy(source, target, weights) is None
    with pytest.raises(ValueError, match="n x 2"):
        kernels.fit_axes_compiled(source[:2], target, np.ones(3), rounds=3, cutoff=3.0)


def test_fit_axis_transform_is_the_same_without_the_c_fit(c_kernel, monkeypatch):
    rng = np.random.default_rng(11)
    cases = [_fit_case(rng, int(rng.integers(3, 12)), outliers=trial % 3) for trial in range(100)]
    compiled = [fit_axis_transform(*case) for case in cases]
    monkeypatch.setattr(kernels, "kernel", lambda: None)
    reference = [fit_axis_transform(*case) for case in cases]
    for a, b in zip(compiled, reference):
        assert (a is None) == (b is None)
        if a is not None:
            assert np.allclose(a, b, rtol=1e-9, atol=1e-9)
