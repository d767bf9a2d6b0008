"""``ursim bench review`` (ursim_core.bench.review): the table, and a Halmstad E5 pair reviewed end to end."""

from __future__ import annotations

import pytest


def test_review_table_has_a_row_per_review_and_the_totals(capsys):
    from ursim_core.bench.review import print_review

    row = {"sketch": "03", "annotator": "a", "cliques": 5}
    for workflow, edits in (("by hand", 4), ("links first", 2), ("every edit", 6)):
        row.update({workflow: edits, f"{workflow} rounds": 1, f"{workflow} finished": workflow != "every edit"})
    print_review([row])
    out = capsys.readouterr().out
    assert "total edits: by hand 4, links first 2 (-50%), every edit 6 (+50%) over 1 reviews of 5 cliques" in out
    assert "6*" in out and "1 not finished" in out


def test_review_of_a_halmstad_robot_map_uses_the_overlay_and_finishes(tmp_path, monkeypatch):
    """The E5 part of ``ursim bench review`` on one pair (a folder of links to the dataset's files):
    a row per annotator, every workflow reaches the annotator's cliques, and the robot map is
    matched as one (the overlay), as ``ursim evaluate`` matches it."""
    import os

    import ursim_core.evaluation.review as review
    from ursim_core.bench.review import bench_review_halmstad
    from ursim_core.correspondences import load_dat
    from ursim_core.evaluation import datasets

    root = datasets.dataset_root()
    if root is None:
        pytest.skip(datasets.MISSING_REASON)
    source = root / "ursim_halmstad_robot_maps" / "E5"
    if not (source / "GT" / "Malcolm" / "gt_E5_03_model_simple.dat").is_file():
        pytest.skip(f"no Halmstad E5 pair E5_03 under {root}")
    folder = tmp_path / "E5"
    (folder / "GT" / "Malcolm").mkdir(parents=True)
    os.symlink(source / "E5_03.png", folder / "E5_03.png")
    for name in ("gt_E5_03_model_simple.dat", "model_simple.png"):
        os.symlink(source / "GT" / "Malcolm" / name, folder / "GT" / "Malcolm" / name)
    matchers = set()
    simulate = review.simulate_review

    def recording(*args, config=None, **kwargs):
        matchers.add(config.resolved().matcher)
        return simulate(*args, config=config, **kwargs)

    monkeypatch.setattr(review, "simulate_review", recording)
    rows = bench_review_halmstad(folder)
    cliques = load_dat(folder / "GT" / "Malcolm" / "gt_E5_03_model_simple.dat").cliques
    assert [(row["sketch"], row["annotator"]) for row in rows] == [("E5_03", "malcolm")]
    assert 0 < rows[0]["cliques"] <= len(cliques)
    assert all(rows[0][f"{workflow} finished"] for workflow in review.WORKFLOWS)
    assert matchers == {"overlay"}
