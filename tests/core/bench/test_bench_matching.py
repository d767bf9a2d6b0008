"""``bench_kth_turned``: every variant timed, each run as a first match (nothing remembered)."""

from __future__ import annotations

import numpy as np

from ursim_core.bench import matching as bench
from ursim_core.segmentation import canonical


def test_the_turned_benchmark_times_every_variant_on_the_dataset_layout(synthetic_dataset, tmp_path, capsys):
    (tmp_path / "ursim_kth_sketches").symlink_to(synthetic_dataset, target_is_directory=True)
    figures = bench.bench_kth_turned(tmp_path, repeats=2)
    assert set(figures) == {"turned_voted_median_ms", "turned_first_median_ms", "turned_single_median_ms"}
    assert all(value > 0 for value in figures.values())
    assert "median of 2 runs" in capsys.readouterr().out


def test_a_timed_run_starts_with_no_wall_angle_remembered():
    free = np.zeros((60, 80), bool)
    free[10:50, 10:70] = True
    canonical.wall_angle(free)
    assert canonical._voted_angle.cache_info().currsize >= 1
    bench.forget_remembered()
    assert canonical._voted_angle.cache_info().currsize == 0


def test_without_the_datasets_the_turned_benchmark_says_so(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("ursim_core.evaluation.datasets.dataset_root", lambda explicit=None: None)
    assert bench.bench_kth_turned(tmp_path / "nowhere") == {}
    assert "datasets not found" in capsys.readouterr().out
