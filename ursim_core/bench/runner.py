"""``ursim bench``: speed and memory figures printed as tables (never asserted in tests)."""

from __future__ import annotations

from pathlib import Path

from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

__all__ = ["run_bench"]


def run_bench(what: str = "all", *, datasets: str | Path | None = None, repeats: int = 5) -> int:
    """Run the benchmarks named by ``what`` ('segment', 'scale', 'match' or 'all') and print figures."""
    root = dataset_root(datasets)
    if what in ("segment", "scale", "all"):
        from ursim_core.segmentation.maoris import compile_kernels

        print(f"segmentation kernels ready in {compile_kernels():.1f} s (compiled on first use, then cached)")
    if what in ("segment", "all"):
        from ursim_core.bench.segmentation import bench_segmentation, print_table

        if root is None:
            print(f"segment: skipped ({MISSING_REASON})")
        else:
            print("== segmentation of the largest maps (median of repeats)")
            print_table(bench_segmentation(root, repeats=repeats))
    if what in ("scale", "all"):
        from ursim_core.bench.segmentation import bench_scale, print_table

        print("== segmentation scale (generated buildings)")
        print_table(bench_scale())
    if what in ("match", "all"):
        from ursim_core.bench.matching import main as bench_matching

        print("== matching (KTH pairs, then generated graphs of 300 and 1000 regions)")
        if root is None:
            print(f"match on KTH: skipped ({MISSING_REASON})")
        bench_matching(["--datasets", str(root)] if root is not None else ["--skip-kth"])
    return 0
