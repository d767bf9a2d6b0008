"""Evaluation of the session against a reference (ursim_gui.model.session_evaluation): scores, TP / FP marks, misses."""

from __future__ import annotations

import numpy as np
from conftest import METRIC_LABELS, SKETCH_LABELS, Recorder, interior, seg_of

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    load_correspondences,
    save_correspondences,
    save_dat,
)


def write_reference(tmp_path):
    """Reference: sketch room r matches metric room r, for rooms 1..4."""
    cliques = tuple(
        Clique(id=r, sketch_points=[interior(SKETCH_LABELS, r)], metric_points=[interior(METRIC_LABELS, r)])
        for r in (1, 2, 3, 4)
    )
    save_correspondences(Correspondences(cliques=cliques), tmp_path / "reference.json")
    return tmp_path / "reference.json"


def test_evaluation_follows_edits_and_the_reference(session, tmp_path):
    right = session.link([1], [1])
    wrong = session.link([2], [3])
    assert session.evaluation is None and session.clique_status(right) is None
    recorder = Recorder(session)
    session.load_reference(write_reference(tmp_path))
    assert recorder.count("reference_changed") == 1
    assert session.reference[0] == (frozenset({1}), frozenset({1}))
    score = session.evaluation
    assert (score.tp, score.fp, score.fn) == (1, 1, 3)
    assert session.clique_status(right) == "tp" and session.clique_status(wrong) == "fp"
    assert session.missed_reference() == [1, 2, 3]

    session.link([2], [2])
    assert (session.evaluation.tp, session.evaluation.fp, session.evaluation.fn) == (2, 1, 2)
    session.set_status(wrong, "rejected")
    assert session.evaluation.fp == 0 and session.clique_status(wrong) is None
    session.undo()
    assert session.evaluation.fp == 1

    session.clear_reference()
    assert session.evaluation is None and session.reference is None and session.missed_reference() == []


def test_a_clique_with_one_wrong_pair_is_marked_fp(session, tmp_path):
    session.load_reference(write_reference(tmp_path))
    mixed = session.link([1, 2], [1])
    assert session.clique_status(mixed) == "fp"


def test_dat_reference_regions_follow_the_current_segmentation(session, tmp_path):
    reference = load_correspondences(write_reference(tmp_path))
    save_dat(reference, tmp_path / "reference.dat")
    session.load_reference(tmp_path / "reference.dat")
    session.link([1], [1])
    assert session.evaluation.tp == 1
    renumbered = np.where(SKETCH_LABELS > 0, 10 - SKETCH_LABELS, 0).astype(np.int32)
    session.set_segmentation("sketch", seg_of(renumbered))
    assert session.reference[0] == (frozenset({9}), frozenset({1}))
    assert session.evaluation.tp == 1  # the clique's ids moved with the points too
