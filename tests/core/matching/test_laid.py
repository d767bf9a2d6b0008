"""The elastic answer's pairs in the pipeline (ursim_core.matching.laid): which partners a region keeps.

The same rule on whole matches is tested with the laid sketch (test_elastic.py)."""

from __future__ import annotations

import networkx as nx
import pytest

from ursim_core.errors import ParameterError
from ursim_core.matching import MatchConfig
from ursim_core.matching.laid import joined_partners


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


def test_elastic_partners_must_be_a_rule():
    assert MatchConfig().elastic_partners == "neighbours"
    with pytest.raises(ParameterError, match="elastic_partners"):
        MatchConfig(elastic_partners="some")
