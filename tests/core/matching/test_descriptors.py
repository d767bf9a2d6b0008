"""Tests of ursim_core.matching.descriptors: standardisation, uniqueness, anchors, Laplacian, signatures."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from ursim_core.matching import descriptors as d


def _graph(sizes, pcas, edges):
    graph = nx.Graph()
    for node, (size, pca) in enumerate(zip(sizes, pcas)):
        graph.add_node(node, size=size, pca_shape=pca, centroid=(0.0, float(node)))
    graph.add_edges_from(edges)
    return graph


def _random_connected_graph(n, seed):
    rng = np.random.default_rng(seed)
    graph = nx.random_labeled_tree(n, seed=seed) if hasattr(nx, "random_labeled_tree") else nx.random_tree(n, seed=seed)
    for _ in range(n // 2):
        a, b = rng.integers(0, n, 2)
        if a != b:
            graph.add_edge(int(a), int(b))
    return graph


def test_standardise_uses_sample_sd_and_external_statistics():
    values = np.array([[1.0, 0.2], [2.0, 0.4], [6.0, 0.9]])
    z = d.standardise(values)
    expected = (values - values.mean(axis=0)) / values.std(axis=0, ddof=1)
    assert np.allclose(z, expected)
    z_model = d.standardise(values, mean=np.array([2.0, 0.5]), sd=np.array([2.0, 0.1]))
    assert np.allclose(z_model[:, 0], [-0.5, 0.0, 2.0])
    assert np.allclose(z_model[:, 1], [-3.0, -1.0, 4.0])


def test_zero_variance_and_single_region_give_zero_z():
    assert np.array_equal(d.standardise(np.array([[3.0, 0.5], [3.0, 0.5]])), np.zeros((2, 2)))
    assert np.array_equal(d.standardise(np.array([[3.0, 0.5]])), np.zeros((1, 2)))


def test_unique_mask_threshold_is_inclusive():
    z = np.array([[1.0, 0.0], [-0.999, 0.5], [0.0, -2.0]])
    assert d.unique_mask(z, k=1.0).tolist() == [True, False, True]
    assert d.unique_mask(z, k=2.5).tolist() == [False, False, False]


def test_uniqueness_score_range():
    score = d.uniqueness_score(np.linspace(-4, 4, 41), np.linspace(4, -4, 41))
    assert score.min() == pytest.approx(1 - 1 / np.sqrt(2 * np.pi))
    assert score.max() < 1.0


def test_anchor_disparities_and_hungarian_pairs():
    z_sketch = np.array([[2.0, 0.0], [-1.0, 1.5]])
    z_metric = np.array([[-1.2, 1.4], [1.8, 0.1], [0.0, -3.0]])
    cost = d.disparity_matrix(z_sketch, z_metric)
    assert cost[0, 1] == pytest.approx((0.2 + 0.1) / 2)
    assert d.anchor_pairs(cost) == [(0, 1), (1, 0)]
    released = d.disparity_matrix(
        z_sketch,
        z_metric,
        disparity="released",
        raw_pca_first=np.array([0.5, 0.9]),
        raw_pca_second=np.array([0.88, 0.51, 0.1]),
    )
    # (|2 - (-1.2)| + |0.5 - 0.88|) / 2 = 1.79 -> clipped at 1; (0.2 + 0.01) / 2 = 0.105 -> 0.10
    assert released[0, 0] == 1.0
    assert released[0, 1] == pytest.approx(0.10)


def test_size_weights_are_positive_and_ordered():
    z = np.array([[-1.0, 0.0], [0.5, 0.0], [2.0, 0.0]])
    weights = d.vertex_weights(z, kind="size", floor=0.1)
    assert weights.tolist() == pytest.approx([0.1, 1.6, 3.1])
    assert np.allclose(d.vertex_weights(z, kind="uniqueness"), d.uniqueness_score(z[:, 0], z[:, 1]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_laplacian_symmetric_psd_with_sqrt_weight_kernel(seed):
    graph = _random_connected_graph(12, seed)
    weights = np.random.default_rng(seed).uniform(0.2, 3.0, 12)
    laplacian = d.weighted_laplacian(graph, weights)
    assert np.allclose(laplacian, laplacian.T)
    eigenvalues, eigenvectors = np.linalg.eigh(laplacian)
    assert eigenvalues.min() > -1e-10
    assert abs(eigenvalues[0]) < 1e-10
    assert eigenvalues[1] > 1e-8  # connected: a single zero eigenvalue
    kernel = eigenvectors[:, 0] * np.sign(eigenvectors[0, 0])
    assert np.allclose(kernel, np.sqrt(weights) / np.linalg.norm(np.sqrt(weights)))
    assert np.allclose(laplacian @ np.sqrt(weights), 0)


def test_laplacian_sparse_matches_dense():
    graph = _random_connected_graph(30, 5)
    weights = np.linspace(0.5, 2.0, 30)
    dense = d.weighted_laplacian(graph, weights, dense=True)
    assert np.allclose(d.weighted_laplacian(graph, weights, dense=False).toarray(), dense)


@pytest.mark.parametrize("anchors", [[0, 3, 7], None])
def test_dense_and_expm_signatures_agree(anchors):
    graph = _random_connected_graph(40, 3)
    weights = np.random.default_rng(3).uniform(0.1, 2.0, 40)
    laplacian = d.weighted_laplacian(graph, weights)
    dense = d.heat_kernel_signatures(laplacian, anchors=anchors, method="eigh")
    sparse_path = d.heat_kernel_signatures(
        d.weighted_laplacian(graph, weights, dense=False), anchors=anchors, method="expm", block=16
    )
    assert np.allclose(dense, sparse_path, atol=1e-9)
    uneven = (0.0, 0.3, 1.7)
    assert np.allclose(
        d.heat_kernel_signatures(laplacian, anchors=anchors, times=uneven, method="eigh"),
        d.heat_kernel_signatures(laplacian, anchors=anchors, times=uneven, method="expm"),
        atol=1e-9,
    )


def test_anchor_signature_at_time_zero_is_the_indicator():
    graph = nx.path_graph(5)
    laplacian = d.weighted_laplacian(graph, np.ones(5))
    signature = d.heat_kernel_signatures(laplacian, anchors=[1, 4])
    assert np.allclose(signature[:, 0], [0, 1, 0, 0, 1])
    # Heat spreads from the anchors: the middle vertex warms up over time.
    assert signature[2, 5] > signature[2, 1] > 0


def test_signatures_invariant_under_relabelling():
    graph = _random_connected_graph(15, 7)
    rng = np.random.default_rng(7)
    nx.set_node_attributes(graph, {n: int(rng.integers(50, 500)) for n in graph}, "size")
    nx.set_node_attributes(graph, {n: float(rng.uniform(0, 1)) for n in graph}, "pca_shape")
    permutation = rng.permutation(15) + 100
    relabelled = nx.relabel_nodes(graph, {n: int(permutation[n]) for n in graph})
    for variant in ("T1", "T2", "T3", "T4"):
        original = d.pair_descriptors(graph, graph, variant=variant)
        moved = d.pair_descriptors(relabelled, relabelled, variant=variant)
        order = [moved.sketch_nodes.index(int(permutation[n])) for n in original.sketch_nodes]
        assert np.allclose(original.sketch_signatures, moved.sketch_signatures[order]), variant


def test_signature_distance_matrix():
    first = np.array([[0.0, 1.0, 2.0], [1.0, 1.0, 1.0]])
    second = np.array([[0.0, 0.0, 0.0]])
    assert d.signature_distance(first, second).tolist() == [[1.0], [1.0]]
    assert d.signature_distance(first, first, chunk_bytes=8).tolist() == [[0.0, 2 / 3], [2 / 3, 0.0]]


def test_variants_and_baseline_types():
    graph = _graph([500, 100, 120, 90, 110], [0.9, 0.2, 0.3, 0.1, 0.2], [(0, 1), (1, 2), (1, 3), (3, 4)])
    t1 = d.pair_descriptors(graph, graph, variant="T1")
    assert t1.anchors == [] and np.allclose(t1.sketch_weights, 1.0)
    t4 = d.pair_descriptors(graph, graph, variant="T4")
    assert t4.anchors == [(0, 0)] and t4.unique_sketch == [0]
    assert np.allclose(np.diag(t4.c_matrix), 0)
    base = d.pair_descriptors(graph, graph, variant="baseline")
    # Crossings are 1 and 3 (degree > 1); everything else is a dead end.
    assert base.c_matrix[1].tolist() == [1.0, 0.0, 1.0, 0.0, 1.0]


def test_model_standardisation_changes_only_the_sketch():
    sketch = _graph([5000, 1000, 1200], [0.9, 0.2, 0.3], [(0, 1), (1, 2)])
    metric = _graph([500, 100, 120], [0.9, 0.2, 0.3], [(0, 1), (1, 2)])
    own = d.pair_descriptors(sketch, metric, standardise_with="own")
    model = d.pair_descriptors(sketch, metric, standardise_with="model")
    assert np.allclose(own.sketch_z, own.metric_z)
    assert np.allclose(model.metric_z, own.metric_z)
    assert model.unique_sketch == [0, 1, 2]  # ten times larger than the model: every region is "unique by size"


def test_no_unique_region_is_reported():
    graph = _graph([100, 100, 100], [0.5, 0.5, 0.5], [(0, 1), (1, 2)])
    result = d.pair_descriptors(graph, graph, variant="T4")
    assert result.anchors == []
    assert any("no anchors" in note for note in result.notes)
    assert any("zero variance" in note for note in result.notes)
    assert np.allclose(result.c_matrix, 0)


@pytest.mark.parametrize("variant", ["T4", "baseline"])
def test_the_metric_maps_positions_are_kept_for_every_blend_of_the_pair(variant):
    """``metric_positions`` are the metric map's positions; blending them again gives ``c``; with
    no position term there are none to keep (and no centroid is read)."""
    from ursim_core.bench.matching import random_region_graph
    from ursim_core.matching.positions import blend_position_arrays, metric_positions_of, region_positions

    sketch, metric = random_region_graph(7, seed=1), random_region_graph(9, seed=2)
    descriptors = d.pair_descriptors(sketch, metric, variant=variant, position_weight=2.0)
    expected = region_positions(metric, nodes=descriptors.metric_nodes)
    assert np.array_equal(descriptors.metric_positions, expected)
    assert metric_positions_of(descriptors, metric) is descriptors.metric_positions
    sketch_positions = region_positions(sketch, nodes=descriptors.sketch_nodes)
    base = descriptors.signature_c
    assert np.array_equal(blend_position_arrays(base, sketch_positions, expected, 2.0), descriptors.c_matrix)
    plain = d.pair_descriptors(sketch, metric, variant=variant, position_weight=0.0)
    assert plain.metric_positions is None
    assert np.array_equal(metric_positions_of(plain, metric), expected)
