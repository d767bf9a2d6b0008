"""``ursim bench``: speed and memory figures printed as tables (never asserted in tests)."""

from __future__ import annotations

from pathlib import Path

from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

__all__ = ["run_bench", "SCALE_SIZES"]

#: Sides in pixels of the generated buildings of ``ursim bench scale`` (issue 14 targets at 8000).
SCALE_SIZES = (1000, 2000, 4000, 8000)


#: Benchmarks that other modules of this package provide (module, function), run on request.
_OPTIONAL = {
    "compile": ("ursim_core.bench.kernels", "bench_compile"),
    "files": ("ursim_core.bench.files", "bench_files"),
}


def run_bench(
    what: str = "all",
    *,
    datasets: str | Path | None = None,
    repeats: int = 5,
    sizes: tuple[int, ...] | None = None,
    csv: str | Path | None = None,
    seeds: int = 8,
    first_seed: int = 0,
    told: bool = False,
) -> int:
    """Run the benchmarks named by ``what`` and print figures.

    ``what``: 'segment', 'scale', 'match' or 'all' (those three), 'startup' (whole-process
    times, :mod:`ursim_core.bench.startup`), 'compile' (first-run kernel compilation), 'files'
    (correspondence files) or 'quality' (segmentation F1, in-sample and leave-one-map-out, of
    every preset on maoris_segmentation, :mod:`ursim_core.bench.quality`; ``csv``: also the rows)
    or 'invariance' (matching accuracy on ``seeds`` generated pairs turned, mirrored, cropped and
    rescaled, :mod:`ursim_core.bench.invariance`; ``first_seed``: the first of them, so that pairs not
    looked at while tuning can be held out, e.g. seeds 8-15; ``told``: the matcher is also told each
    case's orientation, a second table) or 'review' (edits of a simulated
    annotator on the KTH sketches, :mod:`ursim_core.bench.review`).
    ``sizes``: the building sides of 'scale' (default :data:`SCALE_SIZES`).
    Returns the exit code: 1 when the benchmark is not available.
    """
    root = dataset_root(datasets)
    if what == "startup":
        from ursim_core.bench.startup import bench_startup, print_startup

        kth = None if root is None else root / "ursim_kth_sketches"
        if kth is None:
            print(f"startup: KTH cases skipped ({MISSING_REASON})")
        print("== whole-process start-up (issue 10 item 4 targets)")
        print_startup(bench_startup(kth, repeats=repeats))
        if kth is not None:
            from ursim_core.bench.startup import bench_segment_processes, print_segment_processes

            print("== whole `ursim segment --preset default` process on every KTH map, against the C++ MAORIS")
            print_segment_processes(bench_segment_processes(kth, repeats=max(1, repeats // 2)))
        return 0
    if what == "quality":
        import sys

        if root is None or not (root / "maoris_segmentation").is_dir():
            print(f"error: 'ursim bench quality' needs maoris_segmentation ({MISSING_REASON})", file=sys.stderr)
            return 1
        from ursim_core.bench.quality import bench_quality

        bench_quality(root, csv_path=csv)
        return 0
    if what == "review":
        import sys

        if root is None or not (root / "ursim_kth_sketches").is_dir():
            print(f"error: 'ursim bench review' needs ursim_kth_sketches ({MISSING_REASON})", file=sys.stderr)
            return 1
        from ursim_core.bench.review import bench_review, bench_review_halmstad, print_review

        print(
            "== simulated review of the KTH sketches: rejections + links until the answer is each annotator's "
            "(by hand; matched again on the review after each link, then rejecting; after every edit)"
        )
        print_review(bench_review(root))
        e5 = root / "ursim_halmstad_robot_maps" / "E5"
        if e5.is_dir():
            print("== the same on the Halmstad E5 robot maps (the overlay matcher; two linked places lay a map)")
            print_review(bench_review_halmstad(e5))
        else:
            print(f"review on Halmstad E5: skipped ({e5} not found)")
        return 0
    if what == "invariance":
        from ursim_core.bench.invariance import bench_invariance, print_invariance

        chosen = range(first_seed, first_seed + seeds)
        print(
            f"== matching on {seeds} generated pairs (seeds {chosen[0]}-{chosen[-1]}), each transformed 6 ways "
            "(issue 11 bar: mean F1 >= 0.95)"
        )
        # The told table matches the same segmentations again: they do not depend on what the
        # matcher is told.
        kept: dict | None = {} if told else None
        print_invariance(bench_invariance(chosen, segmentations=kept))
        if told:
            print(
                "== the same pairs, the matcher told each sketch's orientation (what a right reading of every "
                "case would score; `--orientation` and `--mirrored` of `ursim match`)"
            )
            print_invariance(bench_invariance(chosen, told=True, segmentations=kept))
        del kept  # freed before the robot-map copies, which are other images
        from ursim_core.matching import MatchConfig

        print(
            "== robot-map-like inputs: a copy of each plan turned, cropped, rescaled (not mirrored), "
            "the default matcher told only that the input is a metric map (the scale is estimated)"
        )
        metric = MatchConfig(input_kind="metric")
        kinds = ("upright", "turned", "cropped", "rescaled")
        print_invariance(bench_invariance(chosen, kinds=kinds, config=metric, plan_copy=True))
        return 0
    if what in _OPTIONAL:
        import importlib
        import sys

        module_name, function_name = _OPTIONAL[what]
        try:
            function = getattr(importlib.import_module(module_name), function_name)
        except (ImportError, AttributeError):
            print(
                f"error: 'ursim bench {what}' is not available in this version ({module_name}.{function_name} is missing)",
                file=sys.stderr,
            )
            return 1
        result = function()
        return result if isinstance(result, int) else 0
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
        from ursim_core.bench.scale import bench_match_process
        from ursim_core.bench.segmentation import bench_scale, print_table

        print(f"== segmentation scale (generated buildings, median of {repeats} runs; targets at 8000 px: 5 s, 1.5 GB)")
        print_table(bench_scale(sizes or SCALE_SIZES, repeats=repeats))
        print("== whole-process `ursim match` of two different buildings of each size (targets at 8000 px: 30 s, 3 GB)")
        print_table(bench_match_process(sizes or SCALE_SIZES))
        print("time_ratio: wall time over the previous size's (each step is 4x the pixels; target <= 4.5)")
    if what in ("match", "all"):
        from ursim_core.bench.matching import main as bench_matching

        print("== matching (KTH pairs, then generated graphs of 300 and 1000 regions)")
        if root is None:
            print(f"match on KTH: skipped ({MISSING_REASON})")
        bench_matching(["--datasets", str(root)] if root is not None else ["--skip-kth"])
    return 0
