"""``ursim evaluate``: run the paper's experiments on a dataset folder and write a report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ursim_core.cli.common import announce_kernel_compilation, check_output_folder, progress_bar

HELP = "Run the paper's experiments on a dataset folder and write a report."
EXAMPLES = """examples:
  ursim evaluate ../shared/datasets/ursim_kth_sketches -o report/
  ursim evaluate ../shared/datasets/ursim_halmstad_robot_maps/E5 --matchers planar --variants T4
  ursim evaluate ../shared/datasets/ursim_kth_sketches --matchers planar --variants T4 --augment dihedral"""

_MATCHERS = ["planar", "hungarian", "vf2"]
_VARIANTS = ["baseline", "T1", "T2", "T3", "T4"]


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DATASET")
    parser.add_argument("-o", "--output", metavar="REPORT", help="report folder (CSV, plots, summary.md)")
    parser.add_argument("--matchers", nargs="+", default=_MATCHERS, choices=_MATCHERS)
    parser.add_argument("--variants", nargs="+", default=_VARIANTS, choices=_VARIANTS)
    parser.add_argument(
        "--legacy-scoring",
        nargs="?",
        const="as-built",
        default="none",
        choices=["none", "as-built", "fnfix"],
        help="reproduce the released scorer: 'as-built' (default when given: false negatives dropped, "
        "explains the paper's figures) or 'fnfix' (its flag initialised)",
    )
    parser.add_argument(
        "--paper",
        action="store_true",
        help="the paper's method (no position term, structural score + substitutions) instead of the default",
    )
    parser.add_argument(
        "--released",
        action="store_true",
        help="every released-code option on (segmentation, binarisation, statistics, weights, rotations)",
    )
    parser.add_argument(
        "--preset", help="segmentation preset of the sketches / input maps (default: the matching pipeline's)"
    )
    parser.add_argument("--metric-preset", help="segmentation preset of the model map (default: the pipeline's)")
    parser.add_argument("--maps", nargs="+", metavar="NAME", help="only these maps (e.g. 00 03 17)")
    parser.add_argument("--cache", metavar="DIR", help="cache segmentations in DIR between runs")
    parser.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask cluster (e.g. tcp://host:8786; start one with 'dask scheduler' and "
        "'dask worker ADDRESS'; needs pip install 'ursim-studio[distributed]')",
    )
    parser.add_argument(
        "--augment",
        metavar="SPEC",
        help="also score every sketch turned / mirrored, each orientation as its own run: 'dihedral' "
        "(the 8 orientations) or 'angles=15,30,...' (degrees counter-clockwise; upright always included)",
    )


def run(args: argparse.Namespace) -> int:
    from ursim_core.evaluation.augment import parse_augment
    from ursim_core.evaluation.report import write_report
    from ursim_core.evaluation.runner import run_evaluation
    from ursim_core.evaluation.tables import format_tables

    if args.output:
        # Refused now rather than after the whole run.
        check_output_folder(args.output)
    augment = None if args.augment is None else parse_augment(args.augment)
    announce_kernel_compilation()
    progress = progress_bar(1, "evaluate")

    legacy: bool | str = {"none": False, "as-built": True, "fnfix": "fnfix"}[args.legacy_scoring]
    overrides = None
    if args.paper:
        import dataclasses

        from ursim_core.matching import MatchConfig

        set_by_runner = {"variant", "matcher", "m", "weights", "m_grid"}
        overrides = {k: v for k, v in dataclasses.asdict(MatchConfig.paper()).items() if k not in set_by_runner}
    result = run_evaluation(
        Path(args.dataset),
        matchers=args.matchers,
        variants=args.variants,
        preset=args.preset,
        metric_preset=args.metric_preset,
        legacy_scoring=legacy,
        released=args.released,
        maps=args.maps,
        workers=args.workers,
        cache_dir=args.cache,
        config_overrides=overrides,
        progress=progress,
        augment=augment,
        scheduler=args.scheduler,
    )
    for warning in result.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(format_tables(result))
    if args.output:
        write_report(result, Path(args.output))
        print(f"report written to {args.output}")
    return 0
