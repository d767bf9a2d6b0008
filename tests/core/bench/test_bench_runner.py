"""``ursim bench``'s runner (ursim_core.bench.runner): optional benchmarks, missing data, the scale tables."""

from __future__ import annotations

import ursim_core.bench.runner as runner


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


def test_scale_prints_both_tables_with_the_whole_process_match(capsys):
    # Tiny buildings: the figures are printed, never asserted; the rows and columns are.
    assert runner.run_bench("scale", sizes=(200, 400)) == 0
    out = capsys.readouterr().out
    assert "segmentation scale" in out and "whole-process `ursim match`" in out
    match_table = out.split("whole-process `ursim match`")[1]
    assert "maxrss_mb" in match_table and "time_ratio" in match_table and "error" not in match_table


def test_review_without_the_kth_dataset_says_what_is_missing(tmp_path, capsys):
    assert runner.run_bench("review", datasets=tmp_path) == 1
    assert "'ursim bench review' needs ursim_kth_sketches" in capsys.readouterr().err
