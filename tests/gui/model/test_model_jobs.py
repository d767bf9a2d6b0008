"""Segmentation and matching jobs (ursim_gui.model.jobs): progress, cancelling, results fed to the session."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ursim_core.errors import UrsimError
from ursim_core.io.maps import map_from_array
from ursim_gui.model.jobs import JobCancelled, MatchJob, SegmentJob
from ursim_gui.model.session import AnnotationSession


def test_segment_job_reports_progress_and_its_result_feeds_the_session():
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    reports = []
    job = SegmentJob(map_from_array(free), "default", {"doors": 40}, side="metric")
    segmentation = job.run(lambda fraction, message: reports.append(fraction), lambda: False)
    assert segmentation.n_regions == 2 and segmentation.params["doors"] == 40
    assert reports[0] == 0.0 and reports[-1] == 1.0 and reports == sorted(reports)
    assert job.description == "Segmenting metric (preset default)"
    session = AnnotationSession()
    session.set_map("metric", map_from_array(free))
    session.set_segmentation(job.side, segmentation)
    assert session.correspondences.metric.segmentation_params["doors"] == 40


def test_segment_job_checks_parameters_before_the_long_step():
    with pytest.raises(UrsimError, match="preset"):
        SegmentJob(np.ones((10, 10), bool), "no-such-preset", None).run(lambda *a: None, lambda: False)


def test_jobs_raise_job_cancelled_between_steps():
    free = np.ones((20, 20), bool)
    with pytest.raises(JobCancelled):
        SegmentJob(free, "default", None).run(lambda *a: None, lambda: True)
    # Cancelled during the long step: the finished result is not returned.
    polls = []

    def cancel_after_first_polls():
        polls.append(1)
        return len(polls) > 2

    with pytest.raises(JobCancelled):
        SegmentJob(free, "default", None).run(lambda *a: None, cancel_after_first_polls)
    assert len(polls) == 3


def test_match_job_result_applies_to_the_session(session):
    pytest.importorskip("ursim_core.matching", reason="ursim_core.matching is not available yet")
    from ursim_core.matching import MatchConfig

    reports = []
    job = MatchJob(session.segmentation("sketch"), session.segmentation("metric"), MatchConfig())
    result = job.run(lambda fraction, message: reports.append((fraction, message)), lambda: False)
    assert reports[0][0] == 0.0 and reports[-1][0] == 1.0
    session.apply_match(result)
    auto = [c for c in session.correspondences.cliques if c.source == "auto"]
    assert auto, "two identical 3x3 grids must give some match"
    assert [(c.sketch_regions[0], c.metric_regions[0]) for c in auto] == list(dict.fromkeys(result.pairs))
    with pytest.raises(JobCancelled):
        MatchJob(session.segmentation("sketch"), session.segmentation("metric")).run(lambda *a: None, lambda: True)


def _cancelled_during_the_sweep(session, config) -> int:
    """Run a match job that is cancelled at its sixth poll; the number of polls."""
    polls = []

    def cancel_during_the_sweep():
        polls.append(1)
        return len(polls) > 5

    with pytest.raises(JobCancelled):
        MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
            lambda *a: None, cancel_during_the_sweep
        )
    return len(polls)


def test_match_job_with_automatic_m_reports_each_m_and_cancels_between_them(session):
    from ursim_core.matching import MatchConfig

    fields = {field.name for field in dataclasses.fields(MatchConfig)}
    # One orientation: the sweep of m is then one matcher run per m of the grid.
    config = MatchConfig(m="auto", **({"orientation": "upright", "mirrored": False} if "orientation" in fields else {}))
    reports = []
    MatchJob(session.segmentation("sketch"), session.segmentation("metric"), config).run(
        lambda fraction, message: reports.append((fraction, message)), lambda: False
    )
    fractions = [fraction for fraction, _ in reports]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    steps = [message for _, message in reports if message.startswith("matching at m = ")]
    assert len(steps) == len(config.m_grid)

    assert _cancelled_during_the_sweep(session, config) == 6
