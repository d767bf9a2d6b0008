"""Hungarian-on-signatures and VF2 baselines."""

from __future__ import annotations

import networkx as nx
import numpy as np

from ursim_core.matching.baselines import hungarian_match, vf2_match


def test_hungarian_keeps_only_pairs_below_m():
    c = np.array([[0.05, 0.40, 0.90], [0.30, 0.10, 0.80]])
    assert hungarian_match(c, 0.2) == [(0, 0), (1, 1)]
    assert hungarian_match(c, 0.07) == [(0, 0)]
    assert hungarian_match(c.T, 0.2) == [(0, 0), (1, 1)]
    assert hungarian_match(np.zeros((0, 3)), 0.5) == []


def test_hungarian_prefers_the_global_optimum():
    # Greedy would take (0, 0) at 0.1 and force (1, 1) at 0.9; the assignment takes 0.2 + 0.2.
    c = np.array([[0.1, 0.2], [0.2, 0.9]])
    assert hungarian_match(c, 1.0) == [(0, 1), (1, 0)]


def test_vf2_finds_an_induced_path_in_a_cycle_respecting_c():
    path = nx.relabel_nodes(nx.path_graph(3), {0: "a", 1: "b", 2: "c"})
    cycle = nx.cycle_graph(4)
    c = np.ones((3, 4))
    c[0, 1] = c[1, 2] = c[2, 3] = 0.0  # a-1, b-2, c-3 only
    result = vf2_match(path, cycle, c, 0.5)
    assert result.pairs == [("a", 1), ("b", 2), ("c", 3)] and result.gave_up == ""


def test_vf2_pattern_is_the_smaller_graph():
    big = nx.path_graph(4)
    small = nx.path_graph(2)
    c = np.zeros((4, 2))
    result = vf2_match(big, small, c, 0.1)
    assert len(result.pairs) == 2 and all(a in big for a, _ in result.pairs)


def test_vf2_no_isomorphism_and_guards():
    triangle = nx.cycle_graph(3)
    star = nx.star_graph(3)
    assert vf2_match(triangle, star, np.zeros((3, 4)), 0.1).pairs == []
    gave_up = vf2_match(triangle, star, np.zeros((3, 4)), 0.1, timeout=0.0)
    assert gave_up.pairs == [] and "gave up" in gave_up.gave_up
    capped = vf2_match(triangle, star, np.zeros((3, 4)), 0.1, max_vertices=3)
    assert "max_vertices" in capped.gave_up


def test_vf2_finds_the_same_isomorphism_in_every_process():
    """The answer depended on the interpreter's string-hash seed (nodes were tagged with strings),
    so `ursim evaluate` on a process pool and on a Dask cluster disagreed on the VF2 rows."""
    import subprocess
    import sys

    script = (
        "import networkx as nx, numpy as np\n"
        "from ursim_core.matching.baselines import vf2_match\n"
        "small, big = nx.cycle_graph(range(10, 16)), nx.cycle_graph(range(20, 26))\n"
        "big.add_edges_from([(20, 30), (30, 31)])\n"
        "print(vf2_match(small, big, np.zeros((6, 8)), 0.5).pairs)\n"
    )
    answers = set()
    for seed in ("1", "2", "3", "4", "5"):
        env = {**__import__("os").environ, "PYTHONHASHSEED": seed}
        answers.add(
            subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True).stdout
        )
    assert len(answers) == 1 and "(10, " in answers.pop()
