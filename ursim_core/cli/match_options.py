"""The options of a pair for ``ursim match`` and ``ursim match-batch``: their parser and the
:class:`~ursim_core.matching.MatchConfig` they make.

A pair's options travel as a plain dict (:func:`options_of`), so that ``match-batch`` can hand
them to worker processes and Dask workers; :func:`match_config` turns them back into a config.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from ursim_core.cli.common import add_map_options, finite_or_nan
from ursim_core.errors import ParameterError

__all__ = ["add_pair_options", "orientation_value", "match_config", "OPTION_NAMES", "options_of"]


def add_pair_options(parser: argparse.ArgumentParser) -> None:
    """The matching, segmentation and map-loading options of a pair (``match`` and ``match-batch``)."""
    # The presets' defaults come from the matcher's options (which import no networkx).

    parser.add_argument("--m", default="auto", help="threshold m on the signature difference, or 'auto' (default)")
    parser.add_argument(
        "--orientation",
        type=orientation_value,
        metavar="any|upright|DEGREES",
        help="how the sketch is turned: 'any' (default: unknown, the matcher finds it), 'upright', or the degrees "
        "to turn it counter-clockwise (after --mirrored yes) to bring it to the metric map",
    )
    parser.add_argument(
        "--mirrored",
        choices=["yes", "no", "unknown"],
        help="whether the sketch is a mirror image of the map (default: unknown with 'any', no otherwise)",
    )
    parser.add_argument(
        "--partial",
        action="store_true",
        help="the sketch shows only part of the metric map: lay it in the part of the map it resembles or box "
        "onto box, whichever lands better, read its orientation where it resembles a part of the map, and "
        "start placing its regions there (elastic_laying=boxes_or_window, window_reading_margin=0.1, "
        "window_start=true)",
    )
    parser.add_argument("--variant", choices=["T1", "T2", "T3", "T4", "baseline"], help="descriptor variant")
    parser.add_argument(
        "--matcher",
        choices=["auto", "planar", "hungarian", "vf2", "overlay"],
        help="matcher (default auto: overlay when the scale is known, from --scale or two ROS YAML "
        "maps, else planar; overlay lays two metric maps on each other)",
    )
    parser.add_argument(
        "--scale",
        type=float,
        metavar="RATIO",
        help="metric-map pixels per input pixel when known (1 for two robot maps of one resolution; read "
        "from the resolutions of two ROS YAML maps when not given): the default matcher then overlays the "
        "maps, and the input may cover any part of the metric map",
    )
    parser.add_argument(
        "--input-kind",
        choices=["sketch", "metric"],
        help="what SKETCH is: 'metric' (a robot map, a floor plan drawn to scale) makes the default matcher "
        "overlay the maps, estimating the scale when none is known (default: a sketch, unless the scale is known)",
    )
    parser.add_argument("--released", action="store_true", help="start from the released C++ code's options")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="any other matching option (a MatchConfig field, e.g. vote_orientations=first); repeatable, "
        "and it wins over the options above",
    )
    add_preset_options(parser)
    parser.add_argument(
        "--param", action="append", metavar="NAME=VALUE", help="segmentation parameter override (both maps)"
    )
    add_map_options(parser)


def orientation_value(text: str):
    """``--orientation``: 'any', 'upright' or a finite number of degrees (else a usage error)."""
    if text in ("any", "upright"):
        return text
    value = finite_or_nan(text)
    if math.isnan(value):
        raise argparse.ArgumentTypeError(f"expects 'any', 'upright' or a number of degrees, got '{text}'")
    return value


def match_config(args: argparse.Namespace):
    from ursim_core.matching import MatchConfig

    m: Any = args.m
    if m != "auto":
        try:
            m = float(m)
        except ValueError:
            raise ParameterError(f"--m expects 'auto' or a number, got '{args.m}'") from None
    base = MatchConfig.released() if args.released else MatchConfig()
    overrides: dict[str, Any] = {"m": m}
    if getattr(args, "orientation", None) is not None:
        overrides["orientation"] = args.orientation
    if getattr(args, "mirrored", None) is not None:
        overrides["mirrored"] = {"yes": True, "no": False, "unknown": None}[args.mirrored]
    if getattr(args, "partial", False):
        from ursim_core.matching.config import PARTIAL_SKETCH

        overrides.update(PARTIAL_SKETCH)
    if args.variant:
        overrides["variant"] = args.variant
    if args.matcher:
        overrides["matcher"] = args.matcher
    if getattr(args, "scale", None) is not None:
        overrides["scale"] = args.scale
    if getattr(args, "input_kind", None) is not None:
        overrides["input_kind"] = args.input_kind
    if getattr(args, "set", None):
        import dataclasses

        from ursim_core.evaluation.crossval import parse_option

        known = {f.name for f in dataclasses.fields(MatchConfig)}
        for text in args.set:
            name, value = parse_option(text)
            if name not in known:
                raise ParameterError(
                    f"unknown matching option '{name}' (known: {', '.join(sorted(known))})", field="set"
                )
            overrides[name] = value
    return base.replace(**overrides)


#: The options of ``ursim match`` that a pair's run needs (also what ``match-batch`` passes on).
OPTION_NAMES = (
    "m",
    "orientation",
    "mirrored",
    "partial",
    "variant",
    "matcher",
    "scale",
    "input_kind",
    "released",
    "set",
    "sketch_preset",
    "metric_preset",
    "param",
    "threshold",
    "nonzero_free",
    "max_pixels",
)


def options_of(args: argparse.Namespace) -> dict[str, Any]:
    """The pair options of parsed arguments as a plain (picklable) dict."""
    return {name: getattr(args, name) for name in OPTION_NAMES}


def add_preset_options(parser: argparse.ArgumentParser) -> None:
    """``--sketch-preset`` and ``--metric-preset``, the segmentations the matcher expects by
    default (:data:`~ursim_core.matching.config.MATCH_PRESETS`); for match and for goal / route."""
    from ursim_core.matching.config import MATCH_PRESETS

    parser.add_argument(
        "--sketch-preset",
        default=MATCH_PRESETS["sketch"],
        help=f"segmentation preset for the sketch (default {MATCH_PRESETS['sketch']}, measured best for matching)",
    )
    parser.add_argument(
        "--metric-preset",
        default=MATCH_PRESETS["metric"],
        help=f"segmentation preset for the metric map (default {MATCH_PRESETS['metric']})",
    )
