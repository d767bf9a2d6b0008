"""``ursim bench``: print speed and memory figures (never asserted; see :mod:`ursim_core.bench`)."""

from __future__ import annotations

import argparse

HELP = "Print speed and memory figures."
EXAMPLES = """examples:
  ursim bench segment
  ursim bench startup --repeats 7
  ursim bench scale --sizes 1000 2000 4000
  ursim bench invariance --seeds 12
  ursim bench invariance --seeds 8 --first-seed 8
  ursim bench invariance --seeds 8 --told
  ursim bench review
  ursim bench all --datasets ../shared/datasets"""

#: Benchmarks by name; "all" runs segment, scale and match (the others on request).
BENCHMARKS = ("segment", "scale", "match", "startup", "compile", "files", "quality", "invariance", "review", "all")


def _count(text: str) -> int:
    """``--repeats`` and ``--seeds``: a whole number, at least 1 (else a usage error)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expects a whole number of at least 1, got '{text}'")
    return value


def _start(text: str) -> int:
    """``--first-seed``: a whole number, at least 0 (else a usage error)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expects a whole number of at least 0, got '{text}'")
    return value


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "what",
        choices=BENCHMARKS,
        nargs="?",
        default="all",
        help="startup: whole-process times of ursim --help / match / segment; compile: first-run kernel "
        "compilation; files: correspondence file load/save; quality: segmentation F1 of every preset, "
        "in-sample and leave-one-map-out; invariance: matching F1 and place accuracy on generated pairs turned, "
        "mirrored, cropped and rescaled; review: edits of a simulated annotator on the KTH sketches, with and "
        "without matching again on the review; all: segment, scale and match",
    )
    parser.add_argument("--datasets", help="datasets folder (default: $URSIM_DATASETS or ../shared/datasets)")
    parser.add_argument("--repeats", type=_count, default=5)
    parser.add_argument("--csv", metavar="FILE", help="quality: also write every row to FILE")
    parser.add_argument("--seeds", type=_count, default=8, help="invariance: generated pairs (default 8)")
    parser.add_argument(
        "--first-seed",
        type=_start,
        default=0,
        metavar="N",
        help="invariance: the first pair's seed (default 0; 8 with --seeds 8 holds out seeds 8-15)",
    )
    parser.add_argument(
        "--told",
        action="store_true",
        help="invariance: also match the same pairs told each sketch's orientation (the share of the gap "
        "that is the orientation's)",
    )
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        metavar="PX",
        help="scale: building sides in pixels (default 1000 2000 4000 8000)",
    )


def run(args: argparse.Namespace) -> int:
    from ursim_core.bench.runner import run_bench

    return run_bench(
        args.what,
        datasets=args.datasets,
        repeats=args.repeats,
        sizes=args.sizes,
        csv=args.csv,
        seeds=args.seeds,
        first_seed=args.first_seed,
        told=args.told,
    )
