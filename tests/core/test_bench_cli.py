"""``ursim bench``: the optional benchmarks and the start-up table (figures are printed, never asserted)."""

from __future__ import annotations

import pytest

import ursim_core.bench.runner as runner
from ursim_core.bench.startup import print_startup


def test_a_missing_optional_benchmark_says_so(monkeypatch, capsys):
    monkeypatch.setitem(runner._OPTIONAL, "files", ("ursim_core.bench.no_such_module", "bench_files"))
    assert runner.run_bench("files") == 1
    assert "not available" in capsys.readouterr().err


def test_an_optional_benchmark_is_called(monkeypatch, capsys):
    import types

    module = types.ModuleType("fake_bench")
    module.bench_compile = lambda: print("compiled in 1.0 s")
    monkeypatch.setitem(__import__("sys").modules, "fake_bench", module)
    monkeypatch.setitem(runner._OPTIONAL, "compile", ("fake_bench", "bench_compile"))
    assert runner.run_bench("compile") == 0
    assert "compiled in 1.0 s" in capsys.readouterr().out


def test_startup_table_states_each_target(capsys):
    print_startup(
        [
            {"case": "ursim --help", "median_s": 0.1, "min_s": 0.09, "n": 5, "target_s": 0.15},
            {"case": "ursim match (KTH 00 vs model)", "median_s": 1.0, "min_s": 0.9, "n": 5, "target_s": 0.5},
        ]
    )
    out = capsys.readouterr().out
    assert "meets target" in out and "2.0x over target" in out


def test_scale_prints_both_tables_with_the_whole_process_match(capsys):
    # Tiny buildings: the figures are printed, never asserted; the rows and columns are.
    assert runner.run_bench("scale", sizes=(200, 400)) == 0
    out = capsys.readouterr().out
    assert "segmentation scale" in out and "whole-process `ursim match`" in out
    match_table = out.split("whole-process `ursim match`")[1]
    assert "maxrss_mb" in match_table and "time_ratio" in match_table and "error" not in match_table


@pytest.mark.parametrize("option", ["--seeds", "--repeats"])
@pytest.mark.parametrize("value", ["0", "-3", "x"])
def test_counts_below_one_are_usage_errors(option, value, capsys):
    from ursim_core.cli import main

    with pytest.raises(SystemExit) as stopped:
        main(["bench", "invariance", option, value])
    assert stopped.value.code == 2
    assert "at least 1" in capsys.readouterr().err


def test_review_without_the_kth_dataset_says_what_is_missing(tmp_path, capsys):
    assert runner.run_bench("review", datasets=tmp_path) == 1
    assert "'ursim bench review' needs ursim_kth_sketches" in capsys.readouterr().err


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
