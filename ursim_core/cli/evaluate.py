"""``ursim evaluate``: run the paper's experiments on a dataset folder and write a report."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ursim_core.cli.common import announce_kernel_compilation, check_output_folder, progress_bar

HELP = "Run the paper's experiments on a dataset folder and write a report."
EXAMPLES = """examples:
  ursim evaluate ../shared/datasets/ursim_kth_sketches -o report/
  ursim evaluate ../shared/datasets/ursim_halmstad_robot_maps/E5 --matchers planar --variants T4
  ursim evaluate ../shared/datasets/ursim_halmstad_robot_maps/E5 --variants T4
  ursim evaluate ../shared/datasets/ursim_kth_sketches --matchers planar --variants T4 --augment dihedral
  ursim evaluate ../shared/datasets/ursim_kth_sketches --matchers planar --variants T4 --augment dihedral \
      --cross-validate orientation_overlap=0,0.5,1,2"""

# As ursim_core.evaluation.results names them (not imported here: `--help` stays fast).
_MATCHERS = ["auto", "planar", "hungarian", "vf2", "overlay"]
_DEFAULT_MATCHERS = ["auto", "hungarian", "vf2"]
_VARIANTS = ["baseline", "T1", "T2", "T3", "T4"]


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DATASET")
    parser.add_argument("-o", "--output", metavar="REPORT", help="report folder (CSV, plots, summary.md)")
    parser.add_argument(
        "--matchers",
        nargs="+",
        default=list(_DEFAULT_MATCHERS),
        choices=_MATCHERS,
        help="default: auto hungarian vf2 (auto: what `ursim match` runs: the planar matcher for "
        "sketches, the overlay matcher for robot maps, as the Halmstad layout's are)",
    )
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
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a matching option for every run (a MatchConfig field, e.g. orientation=upright); repeatable",
    )
    parser.add_argument(
        "--cross-validate",
        metavar="NAME=V1,V2,...",
        help="evaluate once per value of a matching option and report leave-one-map-out figures: each "
        "map scored with the value that does best on the other maps (needs one matcher and one variant)",
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
    overrides = _overrides(args)
    choices = None
    if args.cross_validate:
        from ursim_core.errors import ParameterError
        from ursim_core.evaluation.crossval import parse_choices

        choices = parse_choices(args.cross_validate)
        if len(args.matchers) != 1 or len(args.variants) != 1:
            raise ParameterError("needs exactly one --matchers and one --variants value", field="cross_validate")
    values = choices[1] if choices else [None]
    # One segmentation of each map serves every value.
    segmentations: dict = {}
    results = {}
    for value in values:
        run_overrides = dict(overrides or {})
        if choices:
            run_overrides[choices[0]] = value
        results[json.dumps(value)] = run_evaluation(
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
            config_overrides=run_overrides or None,
            progress=progress,
            augment=augment,
            scheduler=args.scheduler,
            segmentation_cache=segmentations,
        )
    for key, result in results.items():
        for warning in result.warnings:
            print(f"warning: {warning}", file=sys.stderr)
        if choices:
            print(f"\n## {choices[0]} = {key}")
        print(format_tables(result))
        if args.output:
            folder = Path(args.output) / f"{choices[0]}={key}" if choices else Path(args.output)
            write_report(result, folder)
            print(f"report written to {folder}")
    if choices:
        from ursim_core.evaluation.crossval import cross_validate

        cv = cross_validate(
            {json.loads(key): result for key, result in results.items()},
            option=choices[0],
            matcher=args.matchers[0],
            variant=args.variants[0],
        )
        print(f"\nLeave-one-map-out cross-validation of {choices[0]} (automatic m):")
        print(cv.table())
        if args.output:
            from ursim_core.io.atomic import atomic_write_text

            path = Path(args.output) / "crossval.md"
            atomic_write_text(path, f"# Cross-validation of {choices[0]}\n\n" + cv.table(markdown=True) + "\n")
            print(f"cross-validation written to {path}")
    return 0


def _overrides(args: argparse.Namespace) -> dict | None:
    """Matching options from --paper and --set (--set wins)."""
    import dataclasses

    from ursim_core.evaluation.crossval import parse_option

    overrides: dict = {}
    if args.paper:
        from ursim_core.matching import MatchConfig

        set_by_runner = {"variant", "matcher", "m", "weights", "m_grid"}
        overrides = {k: v for k, v in dataclasses.asdict(MatchConfig.paper()).items() if k not in set_by_runner}
    for text in args.set:
        name, value = parse_option(text)
        overrides[name] = value
    return overrides or None
