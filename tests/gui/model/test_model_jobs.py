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


def test_the_laid_sketch_is_made_in_the_match_job_and_not_again_by_the_session(session, monkeypatch):
    # The laying's flow ran on the GUI thread when the match was shown (20-30 ms a KTH pair).
    import ursim_gui.model.session as session_module
    from ursim_core.matching import MatchConfig
    from ursim_gui.model.jobs import LaidMatch
    from ursim_gui.model.view_state import laid_sketch_of

    sketch, metric = session.segmentation("sketch"), session.segmentation("metric")
    outcome = MatchJob(sketch, metric, MatchConfig(), laid_sketch=True).run(lambda *a: None, lambda: False)
    assert isinstance(outcome, LaidMatch) and outcome.result.laid
    expected = laid_sketch_of(outcome.result, sketch.labels, metric.labels)
    assert outcome.laid is not None and np.array_equal(outcome.laid, expected)
    made = []
    monkeypatch.setattr(session_module, "laid_sketch_of", lambda *args: made.append(args) or laid_sketch_of(*args))
    session.apply_match(outcome.result, laid=outcome.laid)
    assert session.laid_sketch() is outcome.laid and not made
    # A match applied without its laid sketch: the session makes it once, when asked.
    session.apply_match(outcome.result)
    assert not made
    laid = session.laid_sketch()
    assert len(made) == 1 and np.array_equal(laid, expected) and session.laid_sketch() is laid
