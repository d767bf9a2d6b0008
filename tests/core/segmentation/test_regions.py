"""The region table (no networkx) and the Segmentation that builds its graph from it on first use."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from ursim_core.segmentation import Segmentation, segment
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.regions import RegionTable, region_table


def _rooms() -> np.ndarray:
    rng = np.random.default_rng(3)
    labels = np.repeat(np.repeat(rng.integers(0, 7, (6, 8)), 9, axis=0), 7, axis=1).astype(np.int32)
    labels[20:30, 10:40] = 0
    return labels


def _as_lists(graph):
    return list(graph.nodes(data=True)), list(graph.edges(data=True))


def test_the_table_is_the_graph_in_the_same_order():
    labels = _rooms()
    table = region_table(labels)
    assert _as_lists(table.to_graph()) == _as_lists(region_graph(labels))
    assert _as_lists(RegionTable.from_graph(region_graph(labels)).to_graph()) == _as_lists(region_graph(labels))
    assert list(table.edges) == sorted(table.edges)
    assert table.number_of_edges() == region_graph(labels).number_of_edges() > 5
    graph = region_graph(labels)
    assert table.neighbours() == {region: sorted(graph.neighbors(region)) for region in graph.nodes}
    assert (3 in table) == (3 in graph) and 0 not in table


def test_an_empty_label_image_has_no_regions():
    table = region_table(np.zeros((4, 5), np.int32))
    assert len(table) == 0 and table.edges == {} and table.to_graph().number_of_nodes() == 0


def test_a_segmentation_builds_its_graph_once_on_first_use():
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    seg = segment(free, preset="default")
    assert seg._graph is None
    assert seg.n_regions == 2 and seg._graph is None
    graph = seg.graph
    assert seg.graph is graph and _as_lists(graph) == _as_lists(region_graph(seg.labels))


def test_a_segmentation_is_immutable_and_survives_pickling_and_copies():
    labels = _rooms()
    seg = Segmentation(labels=labels, regions=region_table(labels), method="label-image", params={"a": 1})
    with pytest.raises(AttributeError, match="immutable"):
        seg.labels = labels
    with pytest.raises(AttributeError, match="immutable"):
        del seg.method
    for again in (pickle.loads(pickle.dumps(seg)), copy.deepcopy(seg), copy.copy(seg)):
        assert np.array_equal(again.labels, labels) and again.params == {"a": 1}
        assert _as_lists(again.graph) == _as_lists(seg.graph)
    given = Segmentation(labels, region_graph(labels))
    assert given.regions.nodes == region_table(labels).nodes
    with pytest.raises(TypeError, match="graph or the region table"):
        Segmentation(labels)


def test_why_no_region_names_what_to_change():
    from ursim_core.segmentation import why_no_region

    assert "no walls" in why_no_region(np.ones((10, 10), bool))
    closed = np.zeros((20, 41), bool)
    closed[2:18, 2:20] = closed[2:18, 21:39] = True
    assert "2 separate areas" in why_no_region(closed)
    assert "separate areas" not in why_no_region(closed, method="watershed")  # MAORIS' rule only
    closed[9, 20] = True  # a door: one area
    assert "minimum size" in why_no_region(closed)
