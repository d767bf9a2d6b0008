"""Counts in the panels read right for one: "1 pair compared", not "1 pairs compared"."""

from __future__ import annotations

from types import SimpleNamespace

from ursim_core.correspondences import Clique, Correspondences, save_correspondences
from ursim_gui.panels.agreement_panel import AgreementPanel
from ursim_gui.panels.matching_panel import describe_result


def test_the_agreement_note_counts_one_pair(qtbot):
    panel = AgreementPanel()
    qtbot.addWidget(panel)
    panel.show_second("malcolm", pairs=1)
    assert "1 pair compared" in panel.note.text()
    panel.show_second("malcolm", pairs=3)
    assert "3 pairs compared" in panel.note.text()


def test_the_match_summary_counts_one_pair_anchor_and_clique():
    one = SimpleNamespace(pairs=[(1, 1)], anchors=[(1, 1)], m=0.1, cost=1.0, reason="", resampling_votes=1)
    assert describe_result(one).startswith("1 pair, 1 anchor, m = 0.100")
    assert "voted over 1 resampling of the turned sketch" in describe_result(one)
    assert describe_result(None, automatic_cliques=1).startswith("1 automatic clique from the file")
    two = SimpleNamespace(pairs=[(1, 1), (2, 2)], anchors=[], m=0.1, cost=1.0, reason="")
    assert describe_result(two).startswith("2 pairs, 0 anchors")


def test_the_evaluation_counts_one_reference_clique_and_point(window, tmp_path):
    path = tmp_path / "one.json"
    save_correspondences(
        Correspondences(cliques=(Clique(id=1, sketch_points=[(30, 25)], metric_points=[(60, 50)]),)), path
    )
    window.session.link([1], [1])
    window.session.load_reference(path)
    panel = window.evaluation
    assert panel.source.text() == "1 reference clique"
    assert panel.values["place"].text() == "1.000 (1 / 1 point)"
