"""Match scoring (ursim_core.evaluation.scoring): TP / FP / FN, P / R / F1, legacy modes, place accuracy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences
from ursim_core.errors import ParameterError
from ursim_core.evaluation.place import place_accuracy, place_problem, score_places
from ursim_core.evaluation.scoring import MatchScore, score_cliques, score_matches
from ursim_core.segmentation.graph import region_graph

# Three one-to-one cliques.
SIMPLE = [({1}, {10}), ({2}, {20}), ({3}, {30})]


def _counts(score: MatchScore) -> tuple[int, int, int]:
    return score.tp, score.fp, score.fn


def _ratios(score: MatchScore) -> tuple[float, float, float]:
    return score.precision, score.recall, score.f1


def test_hand_worked_counts_and_ratios():
    # (1,10) and (2,20) right; (3,31) wrong metric region; (4,40) in no clique. Clique 3 missed.
    score = score_matches([(1, 10), (2, 20), (3, 31), (4, 40)], SIMPLE)
    assert _counts(score) == (2, 2, 1)
    assert score.precision == pytest.approx(0.5)
    assert score.recall == pytest.approx(2 / 3)
    assert score.f1 == pytest.approx(2 * 0.5 * (2 / 3) / (0.5 + 2 / 3))  # 4/7
    assert score.pair_labels == ("tp", "tp", "fp", "fp")
    assert score.pair_cliques == ((0,), (1,), (), ())
    assert score.clique_labels == ("hit", "hit", "missed")
    assert score.mode == "correct"
    assert score.pairs == ((1, 10), (2, 20), (3, 31), (4, 40))


def test_all_right_is_perfect():
    score = score_matches([(1, 10), (2, 20), (3, 30)], SIMPLE)
    assert _counts(score) == (3, 0, 0)
    assert _ratios(score) == (1.0, 1.0, 1.0)


def test_many_to_many_clique():
    # Sketch regions 1, 2 correspond to metric regions 10, 11 (a clique, not a pairing).
    reference = [({1, 2}, {10, 11}), ({3}, {12})]
    score = score_matches([(2, 10), (1, 11), (3, 10)], reference)
    assert score.pair_labels == ("tp", "tp", "fp")  # (3, 10) mixes two cliques
    assert _counts(score) == (2, 1, 1)
    assert score.f1 == pytest.approx(2 * (2 / 3) * (2 / 3) / (4 / 3))


def test_pair_across_two_cliques_is_a_false_positive():
    score = score_matches([(1, 20)], SIMPLE)
    assert _counts(score) == (0, 1, 3)
    assert _ratios(score) == (0.0, 0.0, 0.0)


def test_one_pair_hitting_two_cliques():
    reference = [({1}, {10}), ({1, 2}, {10, 11}), ({5}, {50})]
    correct = score_matches([(1, 10)], reference)
    assert _counts(correct) == (1, 0, 1)  # counted once; both cliques it falls in are hit
    assert correct.pair_cliques == ((0, 1),)
    assert correct.clique_labels == ("hit", "hit", "missed")
    assert correct.f1 == pytest.approx(2 * 1 * 0.5 / 1.5)

    fnfix = score_matches([(1, 10)], reference, legacy="fnfix")
    assert _counts(fnfix) == (2, 0, 1)  # the C++ counted one TP per clique
    assert fnfix.recall == pytest.approx(2 / 3)
    assert fnfix.f1 == pytest.approx(2 * 1 * (2 / 3) / (5 / 3))

    as_built = score_matches([(1, 10)], reference, legacy=True)
    assert _counts(as_built) == (2, 0, 0)
    assert _ratios(as_built) == (1.0, 1.0, 1.0)


def test_as_built_never_counts_false_negatives():
    score = score_matches([(1, 10), (9, 90)], SIMPLE, legacy=True)
    assert _counts(score) == (1, 1, 0)
    assert score.recall == 1.0
    assert score.f1 == pytest.approx(2 * 0.5 / 1.5)
    assert score.clique_labels == ("hit", "missed", "missed")  # shown, though not counted
    assert score_matches([(1, 10), (9, 90)], SIMPLE, legacy="as-built") == score
    assert score.mode == "as-built"


def test_empty_reference_cliques_are_ignored_only_by_the_correct_scoring():
    # As loaded from a .dat: a normal set, the trailing empty set, a one-sided set.
    reference = [({1}, {10}), (set(), set()), (set(), {20})]
    correct = score_matches([(1, 10)], reference)
    assert _counts(correct) == (1, 0, 0)
    assert correct.f1 == 1.0
    assert correct.clique_labels == ("hit", "ignored", "ignored")

    fnfix = score_matches([(1, 10)], reference, legacy="fnfix")
    assert _counts(fnfix) == (1, 0, 2)
    assert fnfix.recall == pytest.approx(1 / 3)
    assert fnfix.f1 == pytest.approx(0.5)
    assert fnfix.clique_labels == ("hit", "missed", "missed")

    as_built = score_matches([(1, 10)], reference, legacy=True)
    assert _counts(as_built) == (1, 0, 0)
    assert as_built.clique_labels == ("hit", "ignored", "ignored")


def test_nothing_returned_and_nothing_to_find():
    assert _ratios(score_matches([], [])) == (1.0, 1.0, 1.0)
    assert _ratios(score_matches([], [(set(), set())])) == (1.0, 1.0, 1.0)
    for mode in (True, "fnfix"):
        legacy = score_matches([], [], legacy=mode)
        assert (legacy.tp, legacy.f1) == (0, 0.0)


def test_nothing_returned_misses_every_clique():
    score = score_matches([], SIMPLE)
    assert _counts(score) == (0, 0, 3)
    assert _ratios(score) == (0.0, 0.0, 0.0)


def test_pairs_without_any_reference_are_false_positives():
    score = score_matches([(1, 10), (2, 20)], [])
    assert _counts(score) == (0, 2, 0)
    assert score.f1 == 0.0 and score.clique_labels == ()


def test_duplicate_pairs_count_once_except_in_legacy_modes():
    correct = score_matches([(1, 10), (1, 10), (7, 70), (7, 70)], SIMPLE)
    assert _counts(correct) == (1, 1, 2)
    assert correct.pair_labels == ("tp", "tp", "fp", "fp")
    fnfix = score_matches([(1, 10), (1, 10), (7, 70), (7, 70)], SIMPLE, legacy="fnfix")
    assert _counts(fnfix) == (2, 2, 2)


def test_cliques_and_correspondences_are_accepted_as_reference():
    cliques = (
        Clique(id=1, sketch_regions=[1], metric_regions=[10]),
        Clique(id=2, sketch_regions=[2, 3], metric_regions=[20]),
    )
    as_tuples = score_matches([(3, 20), (1, 20)], [({1}, {10}), ({2, 3}, {20})])
    assert score_matches([(3, 20), (1, 20)], cliques) == as_tuples
    assert score_matches([(3, 20), (1, 20)], Correspondences(cliques=cliques)) == as_tuples
    assert _counts(as_tuples) == (1, 1, 1)


def test_invalid_legacy_mode_is_refused():
    with pytest.raises(ParameterError, match="legacy"):
        score_matches([], [], legacy="sometimes")


def test_score_cliques_uses_every_region_pair_of_a_clique():
    predicted = [({1, 2}, {10}), ({2}, {10, 20}), (set(), {30})]
    score = score_cliques(predicted, SIMPLE)
    # Pairs: (1,10) (2,10) from the first clique, (2,20) new from the second ((2,10) again is not repeated).
    assert score.pairs == ((1, 10), (2, 10), (2, 20))
    assert score.pair_labels == ("tp", "fp", "tp")
    assert _counts(score) == (2, 1, 1)


def test_an_annotation_scored_against_itself_is_perfect():
    reference = [({1, 2}, {10}), ({3}, {11, 12}), ({4}, {13}), (set(), set())]
    for mode, expected_fn in ((False, 0), ("fnfix", 1)):
        score = score_cliques(reference, reference, legacy=mode)
        assert score.fp == 0 and score.fn == expected_fn
    assert score_cliques(reference, reference).f1 == 1.0


def test_score_cliques_between_two_annotators():
    annotator_a = [
        Clique(id=1, sketch_regions=[1], metric_regions=[10]),
        Clique(id=2, sketch_regions=[2, 3], metric_regions=[20]),
    ]
    annotator_b = [
        Clique(id=7, sketch_regions=[1, 2], metric_regions=[10]),
        Clique(id=8, sketch_regions=[3], metric_regions=[20, 21]),
    ]
    score = score_cliques(annotator_b, annotator_a)
    # B's pairs: (1,10) tp, (2,10) fp, (3,20) tp, (3,21) fp; both of A's cliques are hit.
    assert score.pairs == ((1, 10), (2, 10), (3, 20), (3, 21))
    assert _counts(score) == (2, 2, 0)
    assert score.f1 == pytest.approx(2 * 0.5 * 1.0 / 1.5)


# --------------------------------------------------------------------------- place accuracy
# Against hand-worked cases, including the one-region-per-map case F1 gets wrong.


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
