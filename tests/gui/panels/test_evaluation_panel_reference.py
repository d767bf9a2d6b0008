"""The evaluation panel names the reference it scores against: "12 reference cliques" beside the scores
did not say which file, nor whose."""

from __future__ import annotations

from ursim_core.correspondences import Clique, Correspondences, save_correspondences


def write_reference(path, annotator: str) -> None:
    cliques = (Clique(id=1, sketch_points=[(30, 25)], metric_points=[(60, 50)]),)
    save_correspondences(Correspondences(cliques=cliques, annotator=annotator), path)


def test_the_panel_says_whose_reference_it_scores_against(window, tmp_path):
    panel, session = window.evaluation, window.session
    assert not panel.reference_name.isVisible()
    write_reference(tmp_path / "pair_03.json", "malcolm")
    session.load_reference(tmp_path / "pair_03.json")
    assert panel.reference_name.isVisible() and "by malcolm" in panel.reference_name.full_text()
    session.clear_reference()
    assert not panel.reference_name.isVisible()


def test_a_long_name_is_elided_not_widening_the_panel(window, tmp_path):
    panel, session = window.evaluation, window.session
    width = panel.minimumSizeHint().width()
    write_reference(tmp_path / "long.json", "an annotator with a very long name " * 6)
    session.load_reference(tmp_path / "long.json")
    assert panel.minimumSizeHint().width() == width
    shown = panel.reference_name.text()
    assert shown != panel.reference_name.full_text() and "…" in shown


def test_the_panel_names_the_reference_file(window, tmp_path):
    panel, session = window.evaluation, window.session
    path = tmp_path / "pair_03.json"
    write_reference(path, "malcolm")
    session.load_reference(path)
    assert "pair_03.json" in panel.reference_name.full_text()
    assert panel.reference_name.toolTip() == str(path)
