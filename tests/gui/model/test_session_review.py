"""Matching again after a review: accepted, rejected and manual cliques are kept and steer the answer."""

from __future__ import annotations

import pytest
from conftest import METRIC_LABELS, NOW, SKETCH_LABELS, fake_match, map_of, seg_of

from ursim_core.matching import MatchConfig
from ursim_gui.model.jobs import MatchJob
from ursim_gui.model.session import AnnotationSession


@pytest.fixture
def session():
    session = AnnotationSession(annotator="tester", timestamp=lambda: NOW)
    for side, labels in (("sketch", SKETCH_LABELS), ("metric", METRIC_LABELS)):
        session.set_map(side, map_of(labels))
        session.set_segmentation(side, seg_of(labels))
    return session


def _pairs(session, **where):
    return [
        (clique.sketch_regions, clique.metric_regions)
        for clique in session.correspondences.cliques
        if all(getattr(clique, name) == value for name, value in where.items())
    ]


def test_matching_again_keeps_accepted_and_rejected_cliques(session):
    session.apply_match(fake_match([(1, 1), (2, 2), (3, 4), (5, 5)]))
    ids = {clique.sketch_regions[0]: clique.id for clique in session.correspondences.cliques}
    session.set_status(ids[1], "accepted")
    session.set_status(ids[3], "rejected")

    session.apply_match(fake_match([(1, 2), (3, 4), (2, 2), (6, 6), (9, 1)]))

    # The review survives; (1, 2) and (9, 1) would give accepted regions a second partner and
    # (3, 4) was rejected: none is proposed. The pending cliques of the first answer are replaced.
    assert _pairs(session, status="accepted") == [((1,), (1,))]
    assert _pairs(session, status="rejected") == [((3,), (4,))]
    assert sorted(_pairs(session, status=None)) == [((2,), (2,)), ((6,), (6,))]
    session.undo()
    assert len(session.correspondences.cliques) == 4


def test_review_constraints_follow_the_cliques(session):
    assert session.review_constraints() is None
    session.apply_match(fake_match([(1, 1), (2, 2), (3, 4)]))
    assert session.review_constraints() is None  # pending automatic cliques say nothing
    ids = {clique.sketch_regions[0]: clique.id for clique in session.correspondences.cliques}
    session.set_status(ids[1], "accepted")
    session.set_status(ids[3], "rejected")
    session.link([5, 6], [5])
    session.link([7], [])  # half-made: region 7 is the person's, not the matcher's

    constraints = session.review_constraints()

    assert set(constraints.fixed) == {(1, 1), (5, 5)}
    assert constraints.forbidden == {(3, 4)}
    assert constraints.excluded_sketch == {6, 7} and constraints.excluded_metric == set()


def test_review_constraints_skip_cliques_of_another_segmentation(session):
    session.link([1], [1])
    session.link([2], [2])
    session.set_segmentation("sketch", seg_of((SKETCH_LABELS == 1).astype(SKETCH_LABELS.dtype)))
    assert session.review_constraints().fixed == ((1, 1),)


def test_a_match_job_honours_the_review(session):
    # The grids match themselves room for room; the person says otherwise for rooms 1 and 2.
    session.link([1], [2])
    session.link([2], [1])
    job = MatchJob(
        session.segmentation("sketch"),
        session.segmentation("metric"),
        MatchConfig(orientation="upright"),
        constraints=session.review_constraints(),
    )
    result = job.run(lambda fraction, message="": None, lambda: False)
    assert {(1, 2), (2, 1)} <= set(result.pairs)
    assert all(pair not in result.pairs for pair in [(1, 1), (2, 2)])

    session.apply_match(result)
    manual = _pairs(session, source="manual")
    assert manual == [((1,), (2,)), ((2,), (1,))]
    auto_regions = [region for pair in _pairs(session, source="auto") for region in pair[0]]
    assert 1 not in auto_regions and 2 not in auto_regions and len(auto_regions) == len(set(auto_regions))
