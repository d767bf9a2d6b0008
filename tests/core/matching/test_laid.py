"""The elastic answer's pairs in the pipeline (ursim_core.matching.laid): which partners a region keeps."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.matching import MatchConfig, match
from ursim_core.matching.laid import joined_partners
from ursim_core.segmentation.interface import Segmentation
from ursim_core.segmentation.regions import region_table


def _rooms(widths, height=60, wall=4, top=6):
    """A row of rooms of the given widths, walls between them (no doors): a label image."""
    labels = np.zeros((height + 2 * top, sum(widths) + wall * (len(widths) + 1) + 8), np.int32)
    left = 4 + wall
    for index, width in enumerate(widths, start=1):
        labels[top : top + height, left : left + width] = index
        left += width + wall
    return labels


def _segmentation(labels):
    return Segmentation(labels=labels, regions=region_table(labels))


def test_a_region_keeps_its_closest_partner_and_the_ones_that_touch_it():
    metric = nx.Graph([(1, 2), (2, 5)])
    metric.add_nodes_from([3, 4])
    overlaps = {(1, 1): 0.5, (1, 2): 0.2, (1, 5): 0.16, (1, 3): 0.3, (2, 4): 0.9}
    # 2 touches 1, and 5 touches 2 once 2 is kept; 3 touches none of them.
    assert joined_partners(overlaps, metric) == [(1, 1), (1, 2), (1, 5), (2, 4)]


def test_the_graph_answer_decides_which_partner_is_kept_first():
    metric = nx.Graph()
    metric.add_nodes_from([1, 2])
    overlaps = {(1, 1): 0.5, (1, 2): 0.4}
    assert joined_partners(overlaps, metric) == [(1, 1)]
    assert joined_partners(overlaps, metric, preferred=[(1, 2), (7, 7)]) == [(1, 2)]


def test_the_partners_kept_do_not_depend_on_the_order_of_the_overlaps():
    metric = nx.Graph()
    metric.add_nodes_from([1, 2, 3])
    overlaps = {(1, 3): 0.4, (1, 2): 0.4, (2, 1): 0.3, (3, 1): 0.3}
    shuffled = dict(reversed(list(overlaps.items())))
    # A tie keeps the smaller id; several sketch regions on one metric region are all kept.
    assert joined_partners(overlaps, metric) == joined_partners(shuffled, metric) == [(1, 2), (2, 1), (3, 1)]


def test_a_drawn_room_over_two_walled_rooms_is_paired_with_one():
    # The sketch draws the last two rooms of the map as one room: bent onto the map, it covers
    # both, which are rooms apart (a wall between them, no door).
    metric = _segmentation(_rooms([40, 40, 40, 40]))
    sketch = _segmentation(_rooms([40, 40, 84]))
    told = MatchConfig(orientation="upright", mirrored=False)
    assert sorted(match(sketch, metric, config=told).pairs) == [(1, 1), (2, 2), (3, 3)]
    before = match(sketch, metric, config=told.replace(elastic_partners="all"))
    assert sorted(before.pairs) == [(1, 1), (2, 2), (3, 3), (3, 4)]


def test_a_drawn_room_over_a_room_the_map_splits_is_paired_with_both():
    # The same room on the map, split by its segmentation into two regions that touch.
    labels = _rooms([40, 40, 84])
    right = labels[:, 150:]
    right[right == 3] = 4
    metric = _segmentation(labels)
    assert metric.graph.has_edge(3, 4)
    sketch = _segmentation(_rooms([40, 40, 84]))
    told = MatchConfig(orientation="upright", mirrored=False)
    assert sorted(match(sketch, metric, config=told).pairs) == [(1, 1), (2, 2), (3, 3), (3, 4)]


def test_elastic_partners_must_be_a_rule():
    assert MatchConfig().elastic_partners == "neighbours"
    with pytest.raises(ParameterError, match="elastic_partners"):
        MatchConfig(elastic_partners="some")
