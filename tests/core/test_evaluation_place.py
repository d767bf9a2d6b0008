"""Place accuracy against hand-worked cases, including the one-region-per-map case F1 gets wrong."""

from __future__ import annotations

import math

import numpy as np

from ursim_core.correspondences import Clique
from ursim_core.evaluation.scoring import place_accuracy, place_problem, score_matches, score_places
from ursim_core.segmentation.graph import region_graph


def _rooms():
    """A 20 x 30 map of three rooms side by side (10 columns each), walls between them."""
    labels = np.zeros((20, 30), np.int32)
    labels[:, 0:9] = 1
    labels[:, 10:19] = 2
    labels[:, 20:30] = 3
    return labels


# One clique per room, one point on each side, at the rooms' centres.
REFERENCE = [([(10, 4)], [(10, 4)]), ([(10, 14)], [(10, 14)]), ([(10, 25)], [(10, 25)])]


def test_right_pairs_score_one():
    labels = _rooms()
    score = place_accuracy([(1, 1), (2, 2), (3, 3)], REFERENCE, labels, labels, labels)
    assert score.accuracy == 1.0 and score.successes == 3 and score.n_points == 3 and score.n_cliques == 3


def test_one_region_per_map_has_f1_one_but_low_place_accuracy():
    labels = _rooms()
    one = (labels > 0).astype(np.int32)
    region_cliques = [({1}, {1})] * 3  # every GT point falls in the single region
    assert score_matches([(1, 1)], region_cliques).f1 == 1.0
    score = place_accuracy([(1, 1)], REFERENCE, one, one, labels)
    # The robot goes to the interior of the whole map, which lies in one room of three.
    assert math.isclose(score.accuracy, 1 / 3)


def test_unmatched_and_far_points_fail_and_swaps_fail():
    labels = _rooms()
    # Room 3 unmatched, rooms 1 and 2 swapped: nothing succeeds.
    assert place_accuracy([(1, 2), (2, 1)], REFERENCE, labels, labels, labels).accuracy == 0.0
    # Room 1 right, room 2 unmatched, room 3 right.
    assert math.isclose(place_accuracy([(1, 1), (3, 3)], REFERENCE, labels, labels, labels).accuracy, 2 / 3)


def test_mean_over_points_then_over_cliques():
    labels = _rooms()
    # Clique 0 has two sketch points, one in room 1 and one in room 2; its place is room 1.
    reference = [([(10, 4), (10, 14)], [(10, 4)]), ([(10, 25)], [(10, 25)])]
    score = place_accuracy([(1, 1), (2, 3), (3, 3)], reference, labels, labels, labels)
    # Clique 0: 1 of 2 points (room 2 sends to room 3); clique 1: 1 of 1. Mean (0.5 + 1) / 2.
    assert score.per_clique == (0.5, 1.0) and score.accuracy == 0.75 and score.successes == 2


def test_largest_matched_region_is_the_target_and_place_is_a_union():
    labels = _rooms()
    sketch = labels.copy()
    # Sketch region 1 matched to metric rooms 1 (180 px) and 3 (200 px): the robot goes to room 3.
    reference = [([(10, 4)], [(10, 4)])]
    assert place_accuracy([(1, 1), (1, 3)], reference, sketch, labels, labels).accuracy == 0.0
    # A clique whose metric points cover rooms 1 and 3: its place is both, so it succeeds.
    reference = [([(10, 4)], [(10, 4), (10, 25)])]
    assert place_accuracy([(1, 1), (1, 3)], reference, sketch, labels, labels).accuracy == 1.0


def test_reference_segmentation_is_fixed_and_not_the_matchers():
    labels = _rooms()
    merged = labels.copy()
    merged[merged == 2] = 1  # the matcher's metric segmentation merged rooms 1 and 2
    reference = [([(10, 14)], [(10, 14)])]
    # Matched to the merged region, the robot goes to its interior, which is in room 1 or 2 of
    # the reference: the place (room 2) decides, not the merged region.
    score = place_accuracy([(2, 1)], reference, labels, merged, labels)
    graph = region_graph(merged)
    row, col = graph.nodes[1]["interior"]
    assert score.accuracy == (1.0 if labels[row, col] == 2 else 0.0)


def test_cliques_without_both_sides_are_not_scored_and_empty_is_nan():
    labels = _rooms()
    reference = [Clique(id=1, sketch_points=[(10, 4)], metric_points=[]), ([(10, 4)], [(10, 4)])]
    score = place_accuracy([(1, 1)], reference, labels, labels, labels)
    assert score.n_cliques == 1 and score.clique_indices == (1,) and score.accuracy == 1.0
    assert math.isnan(place_accuracy([(1, 1)], [], labels, labels, labels).accuracy)


def test_point_within_tolerance_of_a_region_counts():
    labels = _rooms()
    # (10, 9) is on the wall between rooms 1 and 2: the 10 px rule gives it a region.
    problem = place_problem([([(10, 9)], [(10, 4)])], labels, labels)
    assert problem.sketch_regions[0][0] in (1, 2)
    far = np.zeros((40, 40), np.int32)
    far[:5, :5] = 1
    problem = place_problem([([(39, 39)], [(2, 2)])], far, far)
    assert problem.sketch_regions == ((0,),)
    assert score_places([(1, 1)], problem, region_graph(far)).accuracy == 0.0
