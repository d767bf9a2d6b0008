"""The side-by-side match figure: large maps are drawn scaled down, small ones as before."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.render.figures import side_by_side_matches
from ursim_core.segmentation.graph import region_graph


def _map(rows: int, cols: int):
    labels = np.zeros((rows, cols), np.int32)
    labels[2 : rows - 2, 2 : cols // 2] = 1
    labels[2 : rows - 2, cols // 2 : cols - 2] = 2
    image = np.where(labels > 0, 255, 0).astype(np.uint8)
    return labels, region_graph(labels), image


def test_a_map_within_the_limit_is_drawn_at_full_size():
    sketch, metric = _map(60, 90), _map(120, 80)
    figure = side_by_side_matches(sketch, metric, [(1, 1), (2, 2)], max_side=200)
    unlimited = side_by_side_matches(sketch, metric, [(1, 1), (2, 2)], max_side=None)
    assert figure.shape[0] == 60
    assert np.array_equal(figure, unlimited)


def test_a_map_above_the_limit_is_drawn_scaled_down():
    sketch, metric = _map(400, 300), _map(120, 80)
    figure = side_by_side_matches(sketch, metric, [(1, 1), (2, 2)], max_side=100)
    assert figure.shape[0] == 100
    assert figure.shape[1] == 75 + 24 + round(80 * 100 / 120)
    # Matched regions keep their shared colours: both halves show non-grey colour.
    assert (figure[:, :75].std(axis=2) > 20).any() and (figure[:, 99:].std(axis=2) > 20).any()


def test_a_region_table_serves_as_the_graph_when_the_map_is_scaled_down_too():
    # overlay_segmentation takes a RegionTable for a graph; scaled down, the figure called
    # graph.nodes(data=...), which a table's dict of nodes is not.
    from ursim_core.segmentation.regions import region_table

    labels, graph, image = _map(400, 300)
    with_table = side_by_side_matches((labels, region_table(labels), image), _map(120, 80), [(1, 1)], max_side=100)
    with_graph = side_by_side_matches((labels, graph, image), _map(120, 80), [(1, 1)], max_side=100)
    assert np.array_equal(with_table, with_graph)


@pytest.mark.parametrize("shape", [(40, 50), (1200, 700)])  # one band of rows; several (and a partial one)
def test_the_table_blend_gives_the_pixels_of_the_float_blend(shape):
    from ursim_core.render.figures import _base_image, _blended, label_colors

    rng = np.random.default_rng(0)
    labels = rng.integers(0, 30, shape).astype(np.int32)
    grey = rng.integers(0, 256, shape).astype(np.uint8)
    # Half of the pixels white, as free space is in a map (the blend's shortcut for them).
    grey[rng.random(grey.shape) < 0.5] = 255
    base = _base_image(grey, None, labels.shape)
    table = label_colors(labels)
    inside = labels > 0
    assert (inside & (grey == 255)).any() and (inside & (grey != 255)).any()
    for opacity in (0.0, 0.3, 0.55, 0.7, 1.0):
        expected = base.astype(np.float32)
        expected[inside] = (1 - opacity) * expected[inside] + opacity * table.astype(np.float32)[labels[inside]]
        assert np.array_equal(_blended(base, labels, inside, table, opacity), expected.astype(np.uint8))
