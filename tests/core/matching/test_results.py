"""MatchResult copies made without ``__init__`` (:func:`replaced`, :func:`new_result`)."""

from __future__ import annotations

import dataclasses

import networkx as nx
import pytest

from ursim_core.matching import MatchConfig, match_prepared, prepare
from ursim_core.matching.results import MatchResult, new_result, replaced
from ursim_core.matching.single import match_at


def _graph() -> nx.Graph:
    graph = nx.cycle_graph(4)
    nx.set_node_attributes(graph, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    nx.set_node_attributes(graph, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    nx.set_node_attributes(graph, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    return graph


def _answer() -> MatchResult:
    return match_prepared(prepare(_graph(), _graph(), MatchConfig(orientation="upright")))


def _fields(result: MatchResult) -> dict:
    return {field.name: getattr(result, field.name) for field in dataclasses.fields(MatchResult)}


def test_replaced_is_dataclasses_replace():
    answer = _answer()
    for changes in ({}, {"m": 0.3}, {"m_scan": {0.1: 0.5}, "config": MatchConfig(m=0.2)}):
        fast, slow = replaced(answer, **changes), dataclasses.replace(answer, **changes)
        assert type(fast) is MatchResult
        for name, value in _fields(slow).items():
            assert getattr(fast, name) is value or (isinstance(value, float) and getattr(fast, name) == value)
    before = answer.m
    assert replaced(answer, m=before + 1) is not answer and answer.m == before  # the original is untouched
    with pytest.raises(TypeError, match="no field 'mm'"):
        replaced(answer, mm=0.3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        replaced(answer, m=0.3).m = 0.4  # still frozen


def test_new_result_is_the_constructor():
    answer = _answer()
    made = new_result(_fields(answer))
    assert type(made) is MatchResult
    assert all(getattr(made, name) is value for name, value in _fields(answer).items())
    fields = _fields(answer)
    del fields["m_scan"]
    with pytest.raises(TypeError, match="fields are"):
        new_result(fields)


def test_every_answer_has_lists_of_its_own():
    # The answers of one preparation share its anchors' values, not the lists: a caller that
    # edits one answer's lists does not edit the others'.
    prepared = prepare(_graph(), _graph(), MatchConfig(orientation="upright"))
    first, second = match_at(prepared, 0.1), match_at(prepared, 0.2)
    assert first.anchors, "the example needs anchors"
    assert first.anchors == second.anchors and first.anchors is not second.anchors
    assert first.m_scan is not second.m_scan
