"""``ursim bench segment`` and ``scale`` (ursim_core.bench.segmentation): what a timed run holds."""

from __future__ import annotations

import weakref

import numpy as np

from ursim_core.bench.segmentation import _times, bench_scale


def test_a_timed_run_does_not_hold_the_last_runs_output():
    # A held output (256 MB of labels at 8000 x 8000 px) made every later run's memory come
    # fresh from the host and added itself to the peak resident size reported.
    alive_at_start = []
    last = []

    def run():
        alive_at_start.append(bool(last) and last[-1]() is not None)
        output = np.zeros(1000)
        last.append(weakref.ref(output))
        return output

    walls, cpus, result = _times(run, 3)
    assert alive_at_start == [False, False, False]
    assert len(walls) == len(cpus) == 3 and result is not None and last[-1]() is result


def test_the_scale_table_counts_the_regions_of_each_size():
    rows = bench_scale(sizes=(200, 400), repeats=2)
    assert [row["size"] for row in rows] == [200, 400]
    assert all(row["regions"] >= 1 for row in rows) and "time_ratio" in rows[1]
