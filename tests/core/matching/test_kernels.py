"""The planar matcher's loop in C against the Python reference, and how the kernel is built."""

from __future__ import annotations

import random
import shutil

import networkx as nx
import numpy as np
import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.matching import kernels
from ursim_core.matching.planar import planar_graph, planar_match
from ursim_core.native import NativeModule


def test_the_c_loop_gives_what_python_gives_on_random_graphs_with_many_ties(
    c_kernel, in_python, planar_answer, small_planar_graph
):
    """Same pairs in the same order, same cost (float or int), counts: dense "same" relations and
    pair costs on a grid of quarters make many equal distances and equal scores."""
    rng = np.random.default_rng(0)
    cases = []
    for trial in range(400):
        first, second = (
            small_planar_graph(rng, int(rng.integers(1, 14))),
            small_planar_graph(rng, int(rng.integers(1, 14))),
        )
        same = rng.uniform(size=(first.n_vertices, second.n_vertices)) < rng.choice([0.1, 0.3, 0.6, 0.9])
        same[rng.integers(first.n_vertices), rng.integers(second.n_vertices)] = True
        seeds = None
        if trial % 3 == 0:  # the caller's order, not the matrix's
            seeds = [(int(a), int(b)) for a, b in zip(*np.nonzero(same))]
            random.Random(trial).shuffle(seeds)
        options = {
            "seeds": seeds,
            "rotation_search": ("min", "first")[trial % 2],
            "reflections": trial % 4 < 2,
            "pair_costs": np.round(rng.uniform(0, 4, size=same.shape)) / 4 if trial % 5 else None,
            "pair_cost_weight": (0.0, 0.5, 1.0, 2.0)[trial % 4],
        }
        cases.append((first, second, same if trial % 2 else same.tolist(), options))
    compiled = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    in_python()
    reference = [planar_answer(planar_match(first, second, same, **options)) for first, second, same, options in cases]
    assert compiled == reference
    assert sum(len(answer[0]) > 2 for answer in reference) > 100  # expansions, not only one-pair answers


@pytest.mark.parametrize("n_regions", [12, 60])
def test_the_c_loop_gives_what_python_gives_on_perturbed_copies(c_kernel, n_regions, in_python, planar_answer):
    """A region graph against a perturbed copy of itself, "same" at several thresholds of a cost."""
    graph = random_region_graph(n_regions, seed=n_regions)
    copy, _ = perturbed_copy(graph, seed=1, size_noise=0.3, position_noise=30)
    first, second = planar_graph(graph), planar_graph(copy)
    costs = np.random.default_rng(n_regions).uniform(size=(n_regions, n_regions))
    calls = [
        (costs <= m, {"pair_costs": costs, "pair_cost_weight": 1.0, "reflections": True}) for m in (0.05, 0.2, 0.5)
    ]
    compiled = [planar_answer(planar_match(first, second, same, **options)) for same, options in calls]
    in_python()
    assert compiled == [planar_answer(planar_match(first, second, same, **options)) for same, options in calls]
    assert max(len(answer[0]) for answer in compiled) >= n_regions // 3


def test_the_kernel_runs_the_common_case_and_python_the_rest(c_kernel, monkeypatch):
    import ursim_core.matching.planar as planar

    graph = nx.path_graph(4)
    nx.set_node_attributes(graph, {i: (0.0, 10.0 * i) for i in range(4)}, "centroid")
    line = planar_graph(graph)
    same = np.eye(4, dtype=bool)

    def python_loop(*args, **kwargs):
        raise AssertionError("the Python loop ran")

    monkeypatch.setattr(planar, "expand_locked", python_loop)
    assert sorted(planar_match(line, line, same).pairs) == [(0, 0), (1, 1), (2, 2), (3, 3)]
    # Alternatives kept, and constraints, are the Python loop's: it runs (and here fails).
    with pytest.raises(AssertionError, match="Python loop"):
        planar_match(line, line, same, keep_alternatives=True)
    # A corridor's neighbour order, too long for the kernel's table, is aligned bit-parallel in C.
    star = nx.star_graph(300)
    nx.set_node_attributes(star, {i: (0.0, 0.0) if i == 0 else (np.sin(i), np.cos(i)) for i in star}, "centroid")
    hub = planar_graph(star)
    assert len(planar_match(hub, hub, np.eye(301, dtype=bool), seeds=[(0, 0)]).pairs) == 301


def test_bad_arguments_are_refused_by_the_kernel(c_kernel):
    graph = nx.path_graph(3)
    nx.set_node_attributes(graph, {i: (0.0, 10.0 * i) for i in range(3)}, "centroid")
    line = planar_graph(graph)
    same = np.ones((3, 3), dtype=bool)
    with pytest.raises(IndexError, match="outside the graphs"):
        kernels.match_compiled(line, line, same, [(0, 3)])
    with pytest.raises(TypeError, match="seed must be a"):
        kernels.match_compiled(line, line, same, [(0, 1, 2)])
    with pytest.raises(ValueError, match="n1 x n2"):
        kernels.match_compiled(line, line, same[:2], [(0, 0)])


def test_an_edited_source_is_built_again(tmp_path):
    if kernels.kernel() is None:
        pytest.skip("no C compiler here")
    sources = tmp_path / "csrc"
    shutil.copytree(kernels.MODULE.source_dir, sources, ignore=shutil.ignore_patterns("__pycache__"))
    module = NativeModule("_matching_kernels", sources)
    assert module.built_path() is None
    built = module.build()
    assert module.built_path() == built
    assert module.load(built).planar_match is not None
    (sources / "planar.c").write_text((sources / "planar.c").read_text() + "\n/* edited */\n")
    assert module.built_path() is None  # stale: the digest no longer matches


def test_without_a_compiler_the_matcher_warns_once_and_runs_in_python(tmp_path, monkeypatch):
    sources = tmp_path / "csrc"
    shutil.copytree(kernels.MODULE.source_dir, sources, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(kernels, "MODULE", NativeModule("_matching_kernels", sources))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    kernels.forget()
    try:
        with pytest.warns(RuntimeWarning, match="no C compiler.*runs in Python"):
            assert kernels.kernel() is None
        graph = nx.path_graph(3)
        nx.set_node_attributes(graph, {i: (0.0, 10.0 * i) for i in range(3)}, "centroid")
        line = planar_graph(graph)
        assert planar_match(line, line, np.eye(3, dtype=bool)).cost == 0
    finally:
        kernels.forget()


def test_ursim_kernels_jit_keeps_the_matcher_in_python(monkeypatch):
    monkeypatch.setenv("URSIM_KERNELS", "jit")
    kernels.forget()
    try:
        assert kernels.kernel() is None
    finally:
        kernels.forget()


def test_a_module_that_cannot_be_loaded_is_built_again(tmp_path, monkeypatch):
    """A module cut short (its digest still right) is reported and built again, then used."""
    if kernels.kernel() is None:
        pytest.skip("no C compiler here")
    sources = tmp_path / "csrc"
    shutil.copytree(kernels.MODULE.source_dir, sources, ignore=shutil.ignore_patterns("__pycache__"))
    module = NativeModule("_matching_kernels", sources)
    built = module.build()
    built.write_bytes(b"\x7fELF cut short")
    assert module.built_path() == built  # the digest still names these sources
    monkeypatch.setattr(kernels, "MODULE", module)
    kernels.forget()
    try:
        with pytest.warns(RuntimeWarning, match="cannot be loaded.*building them again"):
            loaded = kernels.kernel()
        assert loaded is not None and loaded.planar_match is not None
        assert built.stat().st_size > 1000
    finally:
        kernels.forget()
