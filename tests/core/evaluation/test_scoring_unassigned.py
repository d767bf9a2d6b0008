"""score_matches / score_cliques refuse reference cliques whose region ids were never assigned."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences, assign_regions, load_dat
from ursim_core.errors import ParameterError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.evaluation.scoring import score_cliques, score_matches

LABELS = np.array([[1, 1, 1, 0, 2, 2, 2]], dtype=np.int32)


def clicked():
    """Two cliques as clicked (or read from a .dat file): points, no region ids yet."""
    return Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(0, 1)], metric_points=[(0, 5)]),
            Clique(id=2, sketch_points=[(0, 5)], metric_points=[(0, 1)]),
        )
    )


def test_points_without_region_ids_are_a_parameter_error_naming_assign_regions():
    with pytest.raises(ParameterError, match=r"reference.*no region ids.*assign_regions"):
        score_matches([(1, 2), (2, 1)], clicked())
    # No pairs against such a reference was a "perfect" F1 of 1.0 before.
    with pytest.raises(ParameterError, match="assign_regions"):
        score_matches([], clicked().cliques)


def test_assigned_cliques_are_scored():
    score = score_matches([(1, 2), (2, 1)], assign_regions(clicked(), LABELS, LABELS))
    assert (score.tp, score.fp, score.fn, score.f1) == (2, 0, 0, 1.0)


def test_predicted_cliques_without_region_ids_are_a_parameter_error():
    reference = assign_regions(clicked(), LABELS, LABELS)
    with pytest.raises(ParameterError, match=r"predicted.*assign_regions"):
        score_cliques(clicked(), reference)
    assert score_cliques(reference, reference).f1 == 1.0


def test_a_clique_whose_points_fell_off_every_region_is_still_ignored():
    # Assigned, but clique 2's points are far from any region: it has no ids, legitimately.
    far = Clique(id=2, sketch_points=[(0, 3)], metric_points=[(40, 40)])
    reference = assign_regions(clicked().with_clique(far), LABELS, LABELS)
    score = score_matches([(1, 2)], reference)
    assert score.clique_labels == ("hit", "ignored") and score.f1 == 1.0


def test_region_sets_without_points_keep_their_meaning():
    assert score_matches([], [(set(), set())]).f1 == 1.0
    assert score_matches([(1, 2)], [((), ()), ({1}, {2})]).clique_labels == ("ignored", "hit")


ROOT = dataset_root()


@pytest.mark.dataset
@pytest.mark.skipif(ROOT is None, reason=MISSING_REASON)
def test_a_kth_ground_truth_dat_file_must_be_assigned_first():
    reference = load_dat(ROOT / "ursim_kth_sketches" / "gt_correspondences" / "malcolm" / "gt_00_model_simple.dat")
    assert reference.cliques and not any(c.sketch_regions or c.metric_regions for c in reference.cliques)
    with pytest.raises(ParameterError, match="assign_regions"):
        score_matches([(1, 1)], reference)
