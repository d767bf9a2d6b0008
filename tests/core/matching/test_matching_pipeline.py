"""MatchConfig, prepare / match_prepared / match, and degenerate inputs."""

from __future__ import annotations

import dataclasses

import networkx as nx
import numpy as np
import pytest

from ursim_core.bench.matching import perturbed_copy, random_region_graph
from ursim_core.errors import ParameterError
from ursim_core.evaluation.scoring import score_matches
from ursim_core.matching import MatchConfig, match, match_prepared, prepare, seed_pairs
from ursim_core.segmentation import Segmentation
from ursim_core.segmentation.graph import region_graph


def _region_graph(sizes, pcas, centroids, edges):
    graph = nx.Graph()
    for node, (size, pca, centroid) in enumerate(zip(sizes, pcas, centroids), start=1):
        graph.add_node(
            node,
            size=size,
            pca_shape=pca,
            centroid=centroid,
            bbox=(centroid[0] - 5, centroid[1] - 5, centroid[0] + 5, centroid[1] + 5),
        )
    graph.add_edges_from(edges)
    return graph


@pytest.fixture
def floor_plan():
    # Corridor (2) with three rooms and a hall (5) hanging off it, plus a closet off the hall.
    return _region_graph(
        sizes=[400, 900, 380, 420, 2500, 60],
        pcas=[0.2, 0.95, 0.3, 0.25, 0.4, 0.1],
        centroids=[(0, 0), (20, 30), (0, 30), (0, 60), (50, 30), (70, 50)],
        edges=[(1, 2), (2, 3), (2, 4), (2, 5), (5, 6)],
    )


def test_config_validation_names_the_field():
    with pytest.raises(ParameterError, match="variant"):
        MatchConfig(variant="T9")
    with pytest.raises(ParameterError, match="'m'"):
        MatchConfig(m=-0.1)
    with pytest.raises(ParameterError, match="auto_rule"):
        MatchConfig(auto_rule="oracle")
    with pytest.raises(ParameterError, match="max_seeds"):
        MatchConfig(max_seeds=0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        MatchConfig().m = 0.1  # type: ignore[misc]


def test_presets():
    released = MatchConfig.released()
    assert (
        released.standardise,
        released.weights,
        released.disparity,
        released.rotation_search,
        released.hypothesis_score,
        released.position_weight,
    ) == ("model", "uniqueness", "released", "first", "structure", 0.0)
    paper = MatchConfig.paper()
    assert paper.effective_weights == "size" and paper.hypothesis_score == "substitutions"
    assert MatchConfig.released(m=0.3).m == 0.3
    assert MatchConfig(variant="T2").effective_weights == "equal"
    assert MatchConfig(variant="baseline").effective_weights is None


@pytest.mark.parametrize(
    "config",
    [
        MatchConfig(m=0.01),
        MatchConfig.paper(m=0.01),
        MatchConfig.released(m=0.01),
        MatchConfig(),
        MatchConfig(m=0.01, reflections=True),
        MatchConfig(variant="T1", m=0.01),
        MatchConfig(variant="T3", m=0.01),
    ],
)
def test_graph_against_relabelled_copy_gives_identity(config):
    graph = random_region_graph(25, seed=11)
    copy, mapping = perturbed_copy(graph, seed=12, size_noise=0.0, position_noise=0.0)
    result = match(graph, copy, config=config)
    reference = [({a}, {b}) for a, b in mapping.items()]
    assert score_matches(result.pairs, reference).f1 == pytest.approx(1.0)
    assert result.reason == ""


def test_match_accepts_segmentations_and_reports_its_parts():
    labels = np.zeros((30, 60), np.int32)
    labels[2:28, 2:18] = 1
    labels[12:18, 18:40] = 2
    labels[2:28, 40:58] = 3
    labels[5:10, 40:45] = 4
    segmentation = Segmentation(labels=labels, graph=region_graph(labels))
    result = match(segmentation, segmentation, config=MatchConfig(m=0.02))
    assert sorted(result.pairs) == [(1, 1), (2, 2), (3, 3), (4, 4)]
    assert result.c_matrix.shape == (4, 4) and result.signatures[0].shape == (4, 15)
    assert result.seeds_count >= 4 and result.cost == pytest.approx(result.normalised_cost * (4 + 4 + 3 + 3))
    assert all(a == b for a, b in result.anchors)


def test_prepared_sweep_equals_individual_matches(floor_plan):
    copy, _ = perturbed_copy(floor_plan, seed=3, size_noise=0.2, position_noise=3.0)
    prepared = prepare(floor_plan, copy, MatchConfig())
    for m in (0.0, 0.05, 0.2):
        assert match_prepared(prepared, m).pairs == match(floor_plan, copy, config=MatchConfig(m=m)).pairs


def test_seed_pairs_order_and_cap():
    c = np.array([[0.3, 0.0, 0.2], [0.1, 0.5, 0.05]])
    assert seed_pairs(c, 0.2) == [(0, 1), (0, 2), (1, 0), (1, 2)]
    assert seed_pairs(c, 0.2, max_seeds=2) == [(0, 1), (1, 2)]


@pytest.mark.parametrize("matcher", ["planar", "hungarian", "vf2"])
def test_degenerate_inputs_give_reasons_not_exceptions(matcher, floor_plan):
    config = MatchConfig(matcher=matcher)
    empty = match(nx.Graph(), floor_plan, config=config)
    assert empty.pairs == [] and "no regions" in empty.reason

    single = _region_graph([100], [0.5], [(0, 0)], [])
    result = match(single, floor_plan, config=config)
    assert "single region" in result.reason

    flat = _region_graph([100] * 3, [0.5] * 3, [(0, 0), (0, 10), (0, 20)], [(1, 2), (2, 3)])
    result = match(flat, flat, config=config)
    assert "zero variance" in result.reason and "no anchors" in result.reason

    split = floor_plan.copy()
    split.remove_edge(2, 5)
    result = match(split, floor_plan, config=config)
    assert "2 connected components" in result.reason


def test_no_seed_reason():
    triangle = _region_graph([10, 20, 30], [0.1, 0.2, 0.3], [(0, 0), (0, 10), (10, 5)], [(1, 2), (2, 3), (1, 3)])
    pair = _region_graph([10, 20], [0.1, 0.2], [(0, 0), (0, 10)], [(1, 2)])
    # Baseline types: all crossings vs all dead ends, so c = 1 everywhere.
    result = match(triangle, pair, config=MatchConfig(variant="baseline", position_weight=0.0, m=0.5))
    assert result.pairs == [] and "no seeds" in result.reason and result.cost == float("inf")
    assert result.normalised_cost == 1.0


def test_baseline_variant_compares_region_types(floor_plan):
    result = match(floor_plan, floor_plan.copy(), config=MatchConfig(variant="baseline", position_weight=0.0, m=0.0))
    crossing = [floor_plan.degree(n) > 1 for n in sorted(floor_plan)]
    expected = [[float(a != b) for b in crossing] for a in crossing]
    assert result.c_matrix.tolist() == expected
    assert result.signatures is None and result.anchors == []
    # Crossings 2 and 5 against crossings 2 and 5, dead ends against dead ends: 2 * 2 + 4 * 4 seeds.
    assert result.seeds_count == 20
    assert result.pairs and result.c_matrix[result.pairs[0][0] - 1, result.pairs[0][1] - 1] == 0.0


def test_large_graphs_use_the_seed_cap():
    graph = random_region_graph(400, seed=2)
    copy, mapping = perturbed_copy(graph, seed=3)
    result = match(graph, copy, config=MatchConfig(m=0.05))
    assert result.seeds_count <= max(64, 100_000 // 400)
    correct = sum(1 for a, b in result.pairs if mapping[a] == b)
    assert correct >= 0.95 * 400


def test_capped_seeds_are_the_lowest_c_with_ties_in_loop_order():
    import numpy as np

    from ursim_core.matching.single import seed_pairs

    rng = np.random.default_rng(3)
    c_matrix = rng.integers(0, 6, (40, 50)) / 10.0  # many ties
    rows, cols = np.nonzero(c_matrix <= 0.3)
    keep = np.sort(np.argsort(c_matrix[rows, cols], kind="stable")[:100])
    expected = list(zip(rows[keep].tolist(), cols[keep].tolist()))
    assert seed_pairs(c_matrix, 0.3, max_seeds=100) == expected


def test_seed_selector_gives_the_capped_seeds_of_every_m():
    import numpy as np

    from ursim_core.matching.single import SeedSelector, seed_pairs

    rng = np.random.default_rng(4)
    c_matrix = rng.integers(0, 12, (30, 45)) / 20.0  # many ties
    for cap in (1, 7, 64, 5000):
        selector = SeedSelector(c_matrix, cap)
        for m in np.arange(0.0, 0.7, 0.025):
            assert selector.at(float(m)) == seed_pairs(c_matrix, float(m), max_seeds=cap)
