"""Agreement between annotators (ursim_gui.model.agreement): counts, F1, place accuracy, pooled table and CSV."""

from __future__ import annotations

from conftest import scaled

from ursim_core.correspondences import Clique, Correspondences
from ursim_gui.model.agreement import agreement_csv, pair_agreement, pooled


def at(region: int, scale: int = 1) -> tuple[int, int]:
    """A point inside room ``region`` (1 | 2 | 3) of the three-room map."""
    return (30 * scale, (25, 75, 120)[region - 1] * scale)


def clique(i, sketch, metric, **kw):
    return Clique(id=i, sketch_points=[at(sketch)], metric_points=[at(metric, 2)], **kw)


def test_pair_agreement_counts_f1_and_disagreeing_cliques(labels3):
    a = Correspondences(
        cliques=(clique(1, 1, 1, source="auto"), clique(2, 2, 3, source="auto"), clique(3, 3, 2, status="rejected"))
    )
    b = Correspondences(cliques=(clique(1, 1, 1), clique(2, 2, 2)))
    result = pair_agreement("p", a, b, labels3, scaled(labels3, 2))
    a_vs_b = result.comparisons["A vs B"]
    assert (a_vs_b.tp, a_vs_b.fp, a_vs_b.fn, a_vs_b.f1) == (1, 1, 1, 0.5)
    # Place accuracy: B's room 1 is reached through A's (1, 1); B's room 2 is sent to room 3 by A.
    assert a_vs_b.place == 0.5
    assert result.disagreeing == (2,)  # the rejected clique 3 is no claim
    assert result.comparisons["matcher vs A"].f1 == 1.0  # A kept both automatic cliques
    # The best one-to-one answer for both: (1, 1) and one of A's and B's readings of room 2,
    # B's found first; no answer scores above 0.75 on average.
    assert (result.comparisons["ceiling vs A"].f1, result.comparisons["ceiling vs B"].f1) == (0.5, 1.0)
    whole = pooled([result, result])
    assert (whole["A vs B"].tp, whole["A vs B"].fp, whole["A vs B"].f1) == (2, 2, 0.5)
    lines = agreement_csv([result]).splitlines()
    assert (
        lines[0].startswith("pair,A_vs_B_tp") and lines[1].startswith("p,1,1,1,0.5000") and lines[2].startswith("ALL,")
    )
