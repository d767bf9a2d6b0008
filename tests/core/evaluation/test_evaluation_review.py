"""The simulated review: edits to turn the matcher's answer into an annotator's cliques."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation.review import WORKFLOWS, simulate_review
from ursim_core.matching import MatchConfig, match
from ursim_core.segmentation import Segmentation
from ursim_core.segmentation.graph import region_graph


def corridor(rooms: int, room: int) -> np.ndarray:
    """A corridor (region 1) along the top, ``rooms`` rooms below it, each with a door."""
    wall = 2
    width = rooms * (room + wall) + wall
    labels = np.zeros((room * 2 + 3 * wall, width), np.int32)
    labels[wall : wall + room // 2, wall : width - wall] = 1
    top = wall + room // 2 + wall
    for k in range(rooms):
        left = wall + k * (room + wall)
        labels[top : top + room, left : left + room] = k + 2
        labels[top - wall : top, left + room // 2] = k + 2  # the door
    return labels


@pytest.fixture(scope="module")
def pair():
    segs = [corridor(4, room) for room in (20, 30)]
    return [Segmentation(labels=s, graph=region_graph(s), method="label-image") for s in segs]


CONFIG = MatchConfig(orientation="upright", mirrored=False)


def test_an_annotator_who_agrees_needs_no_edit(pair):
    answer = match(*pair, config=CONFIG).pairs
    reference = [({a}, {b}) for a, b in answer]
    for workflow in WORKFLOWS:
        outcome = simulate_review(*pair, reference, workflow=workflow, config=CONFIG)
        assert (outcome.edits, outcome.finished) == (0, True)


def test_a_reading_shifted_by_one_room(pair):
    # The annotator reads the sketch's rooms one along: room k of the sketch is room k + 1 of the
    # map, and the first map room has no partner.
    answer = set(match(*pair, config=CONFIG).pairs)
    assert {(2, 2), (3, 3), (4, 4), (5, 5)} <= answer
    reference = [({1}, {1}), ({2}, {3}), ({3}, {4}), ({4}, {5})]
    by_hand = simulate_review(*pair, reference, workflow="by hand", config=CONFIG)
    # Wrong: (2, 2), (3, 3), (4, 4), (5, 5); missed: the three shifted rooms.
    assert (by_hand.rejections, by_hand.links, by_hand.rounds) == (4, 3, 1)
    links_first = simulate_review(*pair, reference, workflow="links first", config=CONFIG)
    assert links_first.finished and links_first.edits < by_hand.edits
    every_edit = simulate_review(*pair, reference, workflow="every edit", config=CONFIG)
    assert every_edit.finished and every_edit.rounds == every_edit.edits + 1


def test_an_unknown_workflow_is_refused(pair):
    with pytest.raises(ParameterError, match="workflow"):
        simulate_review(*pair, [], workflow="telepathy")
