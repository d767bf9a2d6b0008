"""The vote over the answers of a resampled sketch's segmentations (ursim_core.matching.resampling)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.matching import MatchConfig, MatchConstraints, kernels, match, match_prepared, prepare
from ursim_core.matching.resampling import (
    lowest_scored_reading,
    mean_rank_values,
    most_common_reading,
    region_correspondence,
    region_correspondences,
    vote_pairs,
    vote_reading,
    voted_result,
)
from ursim_core.segmentation import segment_canonical
from ursim_core.segmentation.canonical import RESAMPLING_OFFSETS, _turned
from ursim_core.synth import make_pair

BASE = np.array([[1, 1, 2, 2, 3, 3]])


def test_each_region_goes_to_the_region_it_overlaps_most():
    other = np.array([[4, 4, 4, 5, 0, 6]])
    assert region_correspondence(BASE, other) == {4: 1, 5: 2, 6: 3}
    assert region_correspondence(BASE, np.zeros_like(BASE)) == {}


def test_ties_go_to_the_lower_region_and_walls_are_not_regions():
    # Region 4 covers one pixel of 2 and one of 3: 2 wins. Region 5 lies on walls (-1) and
    # background (0) only, so it has no entry; the -1 in ``other`` counts for nothing either.
    labels = np.array([[2, 3, -1, 0, 1, 1]])
    other = np.array([[4, 4, 5, 5, -1, 6]])
    assert region_correspondence(labels, other) == {4: 2, 6: 1}
    assert region_correspondence(np.zeros((0, 0), int), np.zeros((0, 0), int)) == {}


def _largest_overlaps_by_hand(labels, other):
    counts: dict = {}
    for a, b in zip(labels.ravel().tolist(), other.ravel().tolist(), strict=True):
        if a > 0 and b > 0:
            counts.setdefault(b, {}).setdefault(a, 0)
            counts[b][a] += 1
    return {b: min(row, key=lambda a: (-row[a], a)) for b, row in counts.items()}


def test_the_correspondence_is_the_largest_overlap_pixel_by_pixel():
    # A reference that counts every pixel in Python, on random label images with walls (-1),
    # background (0), ties and regions that overlap nothing; several others at once as the vote
    # carries them, one at a time as region_correspondence does.
    rng = np.random.default_rng(32)
    for _ in range(300):
        shape = tuple(rng.integers(0, 9, 2))
        labels = rng.integers(-1, rng.integers(1, 7), shape)
        others = []
        for _ in range(rng.integers(1, 4)):
            other = rng.integers(-1, rng.integers(1, 7), shape)
            if rng.random() < 0.5:  # mostly the same segmentation, as two resamplings are
                other = np.where(rng.random(shape) < 0.8, labels, other)
            others.append(other)
        expected = [_largest_overlaps_by_hand(labels, other) for other in others]
        assert region_correspondences(labels, others) == expected
        assert region_correspondence(labels, others[0]) == expected[0]
    assert region_correspondences(BASE, []) == []


def test_the_c_kernel_counts_as_the_pixels_do(c_kernel, monkeypatch):
    # The int32 label images of the vote go to csrc/correspondences.c: the same dicts (in the
    # same key order) as counting by hand, on the random images above and long runs of one pair.
    rng = np.random.default_rng(41)
    for _ in range(300):
        shape = tuple(rng.integers(0, 40, 2))
        labels = np.repeat(rng.integers(-1, rng.integers(1, 9), (shape[0], max(1, shape[1] // 4))), 4, axis=1)
        labels = labels[:, : shape[1]].astype(np.int32)
        others = []
        for _ in range(rng.integers(0, 7)):
            other = rng.integers(-1, rng.integers(1, 9), labels.shape)
            if rng.random() < 0.7:
                other = np.where(rng.random(labels.shape) < 0.9, labels, other)
            others.append(other.astype(np.int32))
        expected = [_largest_overlaps_by_hand(labels, other) for other in others]
        compiled = kernels.correspondences_compiled(labels, others)
        assert compiled == expected
        assert [sorted(found) for found in compiled] == [list(found) for found in compiled]
    # What the kernel does not take, NumPy counts.
    assert kernels.correspondences_compiled(BASE, [BASE]) is None  # int64
    base = BASE.astype(np.int32)
    assert kernels.correspondences_compiled(base, [base[:, :3].copy()]) is None
    huge = np.array([[1, np.iinfo(np.int32).max]], dtype=np.int32)
    assert kernels.correspondences_compiled(huge, [huge]) is None  # ids past the histogram's bound
    monkeypatch.setattr(kernels, "LARGEST_HISTOGRAM", 8)
    assert kernels.correspondences_compiled(base, [base * 3]) is None
    assert region_correspondences(base, [base * 3]) == [{3: 1, 6: 2, 9: 3}]


def test_a_pair_needs_the_quorum():
    answers = [(BASE, [(1, 10), (2, 20), (3, 30)]), (BASE, [(1, 10), (2, 21)]), (BASE, [(1, 10), (3, 30)])]
    assert vote_pairs(BASE, answers, quorum=2) == [(1, 10), (3, 30)]
    assert vote_pairs(BASE, answers, quorum=3) == [(1, 10)]


def test_the_vote_is_one_to_one_and_ties_go_to_the_earlier_answer():
    answers = [(BASE, [(1, 10), (2, 20)]), (BASE, [(1, 20), (2, 10)])]
    assert vote_pairs(BASE, answers, quorum=1) == [(1, 10), (2, 20)]


def test_answers_in_other_segmentations_are_carried_over():
    split = np.array([[7, 8, 9, 9, 0, 0]])  # region 1 split in two, region 3 missing
    answers = [(BASE, [(1, 10), (3, 30)]), (split, [(7, 10), (8, 10), (9, 20)]), (split, [(9, 20)])]
    # 7 and 8 both carry to region 1: one vote for (1, 10) per answer, not two.
    assert vote_pairs(BASE, answers, quorum=2) == [(1, 10), (2, 20)]


def test_the_voted_result_takes_the_orientation_most_answers_read():
    first = match(_graph(), _graph(), config=MatchConfig(vote_rule="count"))
    turned = dataclasses.replace(first, orientation=(90.0, False))
    voted = voted_result(first, BASE, [(BASE, turned), (BASE, turned)])
    assert voted.orientation == (90.0, False) and voted.resampling_votes == 3
    assert voted_result(first, BASE, [(BASE, turned)]).orientation == first.orientation


def test_only_the_answers_of_the_most_common_reading_vote_on_pairs():
    first = match(_graph(), _graph(), config=MatchConfig(vote_rule="count"))
    assert first.config.vote_by_reading

    def answer(degrees, pairs):
        return dataclasses.replace(first, orientation=(degrees, False), pairs=pairs)

    first = answer(0.0, [(1, 10)])
    alike = [answer(0.4, [(1, 10), (2, 20)]), answer(359.7, [(1, 10), (2, 20)])]
    turned = [answer(180.2, [(2, 21), (3, 30)]) for _ in range(3)]
    # Three read it as the first does, three half a turn round: a tie, which the first's reading
    # wins; of its three answers two are half.
    voted = voted_result(first, BASE, [(BASE, a) for a in alike + turned])
    assert voted.pairs == [(1, 10), (2, 20)] and voted.orientation == (0.0, False)
    assert voted.resampling_votes == 6
    # Every answer voting, half of all six needed: the other reading's pairs win.
    every = voted_result(
        dataclasses.replace(first, config=MatchConfig(vote_by_reading=False)), BASE, [(BASE, a) for a in alike + turned]
    )
    assert every.pairs == [(1, 10), (2, 21), (3, 30)]
    # Four of six half a turn round: theirs is the reading, the orientation the earliest of them.
    voted = voted_result(first, BASE, [(BASE, a) for a in alike[:1] + turned + [answer(179.9, [(2, 21)])]])
    assert voted.pairs == [(2, 21), (3, 30)] and voted.orientation == (180.2, False)


def test_the_score_rule_takes_the_reading_ranked_best_over_every_segmentation():
    first = match(_graph(), _graph())
    assert first.config.vote_rule == "score"
    # Each segmentation ranked both readings; two chose the half turn by a hair, one the upright
    # reading by a wide margin: the mean says upright, the count says half turn.
    scans = [{(0.0, False): 0.30, (180.0, False): 0.50}, {(0.3, False): 0.41, (180.3, False): 0.40}]
    scans.append({(359.8, False): 0.42, (179.8, False): 0.41})

    def answer(degrees, pairs, scan):
        return dataclasses.replace(first, orientation=(degrees, False), pairs=pairs, orientation_scan=scan)

    every = [answer(0.0, [(1, 10)], scans[0]), answer(180.3, [(2, 21)], scans[1]), answer(179.8, [(2, 21)], scans[2])]
    voted = voted_result(every[0], BASE, [(BASE, a) for a in every[1:]])
    assert voted.orientation == (0.0, False) and voted.pairs == [(1, 10)]
    assert lowest_scored_reading([a.orientation for a in every], scans) == [0]
    # The vote's scan: each of the first's candidates, its reading's mean over the three.
    assert voted.orientation_scan == pytest.approx({(0.0, False): 0.3767, (180.0, False): 0.4367}, abs=1e-4)
    assert mean_rank_values([(0.0, False), (180.0, True)], scans) == [pytest.approx(0.3767, abs=1e-4), math.inf]
    counted = voted_result(
        dataclasses.replace(every[0], config=MatchConfig(vote_rule="count")), BASE, [(BASE, a) for a in every[1:]]
    )
    assert counted.orientation == (180.3, False) and counted.pairs == [(2, 21)]


def test_the_score_rule_falls_back_to_the_count_without_scans():
    orientations = [(0.0, False), (90.2, True), (90.0, True)]
    assert lowest_scored_reading(orientations, [{}, {}, {}]) == most_common_reading(orientations) == [1, 2]
    # Equal means: the reading more answers chose, then the earliest.
    scans = [{(0.0, False): 0.5, (90.0, True): 0.5}] * 3
    assert lowest_scored_reading(orientations, scans) == [1, 2]
    assert lowest_scored_reading([(0.0, False), (90.0, True)], scans[:2]) == [0]
    assert lowest_scored_reading([], []) == []


def test_the_vote_rule_is_checked():
    with pytest.raises(ParameterError, match="vote_rule|one of"):
        MatchConfig(vote_rule="majority")


def _graph():
    import networkx as nx

    g = nx.path_graph(3)
    nx.set_node_attributes(g, {0: 50, 1: 10, 2: 12}, "size")
    nx.set_node_attributes(g, 0.3, "pca_shape")
    nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    return g


@pytest.fixture(scope="module")
def turned_pair():
    plan, sketch = make_pair(seed=5)
    turned, _ = _turned(sketch.free, 25.0)
    return segment_canonical(turned, preset="default", resampled=True), segment_canonical(plan.free, preset="default")


def _voted_by_hand(sketch, first_answer, variants, m=None, correspondences=None):
    """The vote of ``voted_result`` written out: the answers of the most common reading, half of them."""
    answers = [(sketch.labels, first_answer), *((labels, match_prepared(variant, m)) for labels, variant in variants)]
    voters = lowest_scored_reading(
        [tuple(result.orientation) for _, result in answers], [result.orientation_scan for _, result in answers]
    )
    return vote_pairs(
        sketch.labels,
        [(answers[index][0], answers[index][1].pairs) for index in voters],
        quorum=(len(voters) + 1) // 2,
        correspondences=[correspondences[index] for index in voters] if correspondences else None,
    )


def test_a_resampled_sketch_is_matched_in_every_segmentation_and_voted(turned_pair):
    sketch, plan = turned_pair
    assert len(sketch.resampled) == len(RESAMPLING_OFFSETS) + 1 == 5
    prepared = prepare(sketch, plan)
    assert prepared.resampled is not None and len(prepared.resampled.variants) == 5
    voted = match(sketch, plan)
    assert voted.resampling_votes == MatchConfig().vote_segmentations == 6
    # The voted pairs are in the first segmentation's regions, one to one.
    assert {a for a, _ in voted.pairs} <= set(sketch.graph.nodes)
    assert len({a for a, _ in voted.pairs}) == len(voted.pairs) == len({b for _, b in voted.pairs})
    # Each answer alone, carried over: the vote keeps what at least half of them hold.
    first = match(sketch, plan, config=MatchConfig(resampling_vote=False))
    assert sorted(voted.pairs) == sorted(_voted_by_hand(sketch, first, prepared.resampled.variants))
    # The reading found once per preparation is the one the answers at any m give.
    for m in (None, 0.1, 0.3):
        alone = dataclasses.replace(prepared, resampled=None)  # the first segmentation's own answer
        answers = [match_prepared(alone, m), *(match_prepared(v, m) for _, v in prepared.resampled.variants)]
        from_answers = vote_reading(
            MatchConfig(), [a.orientation for a in answers], [a.orientation_scan for a in answers]
        )
        assert from_answers == prepared.resampled.reading


@pytest.mark.parametrize("count", [1, 2, 6, 12])
def test_the_first_segmentations_vote_as_many_as_configured(turned_pair, count):
    sketch, plan = turned_pair
    config = MatchConfig(vote_segmentations=count)
    prepared = prepare(sketch, plan, config)
    if count == 1:
        assert prepared.resampled is None and match(sketch, plan, config=config).resampling_votes == 0
        return
    used = min(count, 1 + len(sketch.resampled))
    variants = prepared.resampled.variants
    # The first resamplings, in the order of RESAMPLING_OFFSETS.
    assert [labels for labels, _ in variants] == [other.labels for other in sketch.resampled[: used - 1]]
    voted = match(sketch, plan, config=config)
    assert voted.resampling_votes == used
    first = match(sketch, plan, config=MatchConfig(resampling_vote=False))
    assert sorted(voted.pairs) == sorted(_voted_by_hand(sketch, first, variants))


@pytest.mark.parametrize("asked", [False, True])
def test_only_the_first_segmentation_refits_from_the_signatures_unless_asked(turned_pair, monkeypatch, asked):
    from ursim_core.matching import pipeline

    sketch, plan = turned_pair
    starts = []
    original = pipeline.signature_start

    def counting(prepared, match_one):
        starts.append(prepared.orientation)
        return original(prepared, match_one)

    monkeypatch.setattr(pipeline, "signature_start", counting)
    config = MatchConfig(vote_signature_refit=asked)
    prepare(sketch, plan, config.replace(resampling_vote=False))
    first_only = len(starts)  # once per mirror flag of the first segmentation's finalists
    starts.clear()
    prepared = prepare(sketch, plan, config)
    variants = [variant for _, variant in prepared.resampled.variants]
    assert 1 <= first_only <= 2 and prepared.config.signature_refit
    if asked:
        assert len(starts) >= first_only + len(variants)
        assert all(variant.config.signature_refit for variant in variants)
    else:
        assert len(starts) == first_only
        assert not any(variant.config.signature_refit for variant in variants)
        # Each variant is what preparing it alone without the start gives.
        one = pipeline._prepare_one(
            sketch.resampled[0],
            plan,
            MatchConfig(signature_refit=False),
            orientations=tuple(prepared.orientation_scan),
            overlaps=prepared.orientation_overlaps,
        )
        assert one.chosen.pairs == variants[0].chosen.pairs and one.orientation == variants[0].orientation


def test_the_metric_maps_wall_angle_is_measured_once_for_the_whole_vote(turned_pair, monkeypatch):
    import copy

    from ursim_core.segmentation import canonical

    sketch, plan = turned_pair
    plan = copy.copy(plan)  # a Segmentation that has not measured its wall angle yet
    measured = []
    original = canonical.wall_angle
    monkeypatch.setattr(canonical, "wall_angle", lambda labels: measured.append(labels) or original(labels))
    prepared = prepare(sketch, plan)
    assert len(prepared.resampled.variants) == 5
    assert sum(labels is plan.labels for labels in measured) == 1
    # Each segmentation of the sketch at most once too (earlier tests may have measured them).
    segmentations = [sketch, *sketch.resampled]
    assert all(sum(labels is seg.labels for labels in measured) <= 1 for seg in segmentations)
    assert all(any(labels is seg.labels for seg in segmentations) for labels in measured if labels is not plan.labels)
    count = len(measured)
    prepare(sketch, plan)
    assert len(measured) == count


@pytest.mark.parametrize("value", [None, 1, "yes"])
def test_the_others_signature_start_option_is_checked(value):
    with pytest.raises(ParameterError, match="vote_signature_refit"):
        MatchConfig(vote_signature_refit=value)


@pytest.mark.parametrize("count", [0, -1, True, 2.0, "6"])
def test_the_number_of_voting_segmentations_is_checked(count):
    with pytest.raises(ParameterError, match="vote_segmentations"):
        MatchConfig(vote_segmentations=count)


def test_the_regions_are_carried_over_once_per_preparation_not_once_per_vote(turned_pair, monkeypatch):
    from ursim_core.matching import resampling

    sketch, plan = turned_pair
    prepared = prepare(sketch, plan)
    resampled = prepared.resampled
    expected = [
        region_correspondence(sketch.labels, labels) for labels in (sketch.labels, *(v[0] for v in resampled.variants))
    ]
    assert list(resampled.correspondences) == expected
    assert expected[0] == {region: region for region in sketch.graph.nodes}
    calls = []
    monkeypatch.setattr(resampling, "region_correspondence", lambda *args: calls.append(args) or {})
    monkeypatch.setattr(resampling, "region_correspondences", lambda *args: calls.append(args) or [])
    for m in (0.1, 0.2, None):  # a sweep over m votes at every m
        voted = match_prepared(prepared, m)
        first = match_prepared(dataclasses.replace(prepared, resampled=None), m)
        by_hand = _voted_by_hand(sketch, first, resampled.variants, m, correspondences=expected)
        assert sorted(voted.pairs) == sorted(by_hand)
    assert not calls


def test_the_other_segmentations_try_the_first_ones_finalist_orientations(turned_pair, monkeypatch):
    from ursim_core.matching import pipeline

    sketch, plan = turned_pair
    made = []  # every orientation prepared after a segmentation's first
    reoriented = pipeline.reoriented
    monkeypatch.setattr(pipeline, "reoriented", lambda *args, **kw: made.append(args[2]) or reoriented(*args, **kw))
    prepared = prepare(sketch, plan)
    finalists = list(prepared.orientation_scan)
    assert 1 < len(finalists) < 8  # the first segmentation screened eight and kept a few
    # Eight for the first segmentation; the finalists only for each of the five others.
    assert len(made) == 7 + 5 * (len(finalists) - 1) and len(prepared.resampled.variants) == 5
    for _, variant in prepared.resampled.variants:
        tried = list(variant.orientation_scan)
        assert 1 <= len(tried) <= len(finalists)
        for degrees, mirrored in tried:
            # The same reading, turned by the fraction of a degree the wall angles differ by.
            assert any(flag == mirrored and abs((degrees - wanted + 180) % 360 - 180) < 3 for wanted, flag in finalists)


def test_the_sketch_is_fitted_once_and_the_others_take_the_first_ones_overlaps(turned_pair, monkeypatch):
    from ursim_core.matching import pipeline

    sketch, plan = turned_pair
    fitted = []
    measure = pipeline.candidate_overlaps
    monkeypatch.setattr(pipeline, "candidate_overlaps", lambda *args: fitted.append(args[1]) or measure(*args))
    prepared = prepare(sketch, plan)
    assert fitted == [sketch]  # the first segmentation only
    measured = prepared.orientation_overlaps
    assert len(measured) == 8 and all(0 < value <= 1 for value in measured.values())
    for _, variant in prepared.resampled.variants:
        for (degrees, mirrored), score in variant.orientation_scan.items():
            # Each orientation's score is its answer's cost over the overlap of the nearest
            # orientation of the first segmentation (the same reading).
            nearest = min(
                (o for o in measured if o[1] == mirrored), key=lambda o: abs((o[0] - degrees + 180) % 360 - 180)
            )
            assert abs((nearest[0] - degrees + 180) % 360 - 180) < 3
            if len(variant.orientation_scan) > 1:
                assert variant.orientation_overlaps[(degrees, mirrored)] == measured[nearest]
                assert score > 0


def test_no_vote_when_switched_off_given_constraints_or_another_matcher(turned_pair):
    sketch, plan = turned_pair
    assert match(sketch, plan, config=MatchConfig(resampling_vote=False)).resampling_votes == 0
    assert match(sketch, plan, config=MatchConfig(matcher="hungarian")).resampling_votes == 0
    first = match(sketch, plan, config=MatchConfig(resampling_vote=False)).pairs[0]
    constrained = match(sketch, plan, constraints=MatchConstraints(fixed=(first,)))
    assert constrained.resampling_votes == 0 and first in constrained.pairs
    assert not MatchConfig.paper().resampling_vote and not MatchConfig.released().resampling_vote


@pytest.mark.parametrize("value", [None, "all", True])
def test_the_vote_orientations_option_is_checked(value):
    with pytest.raises(ParameterError, match="vote_orientations"):
        MatchConfig(vote_orientations=value)


def test_the_others_can_take_the_first_ones_finalists_as_they_are(turned_pair, monkeypatch):
    """vote_orientations='first': every other segmentation is matched in exactly the first one's
    finalists, and only the first label image (and the metric map's) has its wall angle measured."""
    import copy

    from ursim_core.segmentation import canonical

    sketch, plan = turned_pair
    sketch = copy.copy(sketch)  # a Segmentation that has not measured its wall angle yet
    measured = []
    original = canonical.wall_angle
    monkeypatch.setattr(canonical, "wall_angle", lambda labels: measured.append(labels) or original(labels))
    prepared = prepare(sketch, plan, MatchConfig(vote_orientations="first"))
    finalists = list(prepared.orientation_scan)
    for _, variant in prepared.resampled.variants:
        assert set(variant.orientation_scan) <= set(finalists)
    others = [other.labels for other in sketch.resampled]
    assert not any(labels is other for labels in measured for other in others)
    assert match(sketch, plan, config=MatchConfig(vote_orientations="first")).resampling_votes == 6
