"""``ursim goal``: a sketch point becomes a goal pose in the robot's map (PoseStamped-like JSON).

Registered by ``ursim_core.cli.main.build_parser`` with ``goal.add_parser(commands)``. The
loading, segmenting and matching shared with ``ursim route`` (:func:`prepare_navigation`) lives
here so that both commands read maps and correspondences the same way.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ursim_core.cli.common import check_map_options, finite_or_nan, refuse_overwriting_inputs
from ursim_core.errors import ParameterError

__all__ = [
    "add_parser",
    "cmd_goal",
    "prepare_navigation",
    "navigation_inputs",
    "Navigation",
    "add_navigation_options",
    "parse_point",
    "finite_number",
    "tolerance_value",
    "write_json",
]

EXAMPLES = """examples:
  ursim goal sketch.png map.yaml --at 120,340
  ursim goal sketch.png map.yaml --at 120,340 --correspondences corr.json --target mirror
  ursim goal sketch.png map.yaml --at 120,340 --at 60,80 -o goals.json

Prints a PoseStamped-like JSON object (frame_id "map"; a list for several --at). The pose is in
metres when METRIC is a map_server YAML; for a plain image it is null and "ursim.pixel" gives
the goal in (row, col) pixels. Exit code 1 when a point has no goal (the reason and the nearest
matched region are printed on stderr)."""


@dataclass(frozen=True)
class Navigation:
    """Everything a goal or route needs: both maps, their segmentations and the match table."""

    sketch_map: Any
    metric_map: Any
    sketch_seg: Any
    metric_seg: Any
    table: Any
    source: str


#: Beyond any image's pixel index (OpenCV and the label images index with 32-bit integers): a
#: point farther out is a typo, and its pixel would not even print readably.
_MAX_COORDINATE = 2.0**31


def parse_point(text: str) -> tuple[float, float]:
    """``"ROW,COL"`` -> (row, col); argparse type of ``--at``.

    Both must be finite numbers of at most 2**31 px (NaN and infinity have no pixel).

    Examples
    --------
    >>> parse_point("12, 30.5")
    (12.0, 30.5)
    >>> parse_point("nan,3")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected ROW,COL (two finite numbers of pixels), got 'nan,3'
    """
    parts = text.replace(" ", "").split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        point = float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROW,COL (two numbers), got '{text}'") from None
    # float() reads 'nan', 'inf' and '1e400' (infinity) without complaint.
    if not all(math.isfinite(v) and abs(v) <= _MAX_COORDINATE for v in point):
        raise argparse.ArgumentTypeError(f"expected ROW,COL (two finite numbers of pixels), got '{text}'")
    return point


def finite_number(text: str) -> float:
    """A finite float; argparse type of ``--yaw`` (NaN or infinity would make no heading).

    Examples
    --------
    >>> finite_number("1.5")
    1.5
    >>> finite_number("inf")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a finite number, got 'inf'
    """
    value = finite_or_nan(text)
    if math.isnan(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got '{text}'")
    return value


def tolerance_value(text: str) -> float:
    """A finite float >= 0; argparse type of ``--tolerance`` (NaN compares false with every distance).

    Examples
    --------
    >>> tolerance_value("10")
    10.0
    >>> tolerance_value("nan")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a finite number of pixels >= 0, got 'nan'
    """
    value = finite_or_nan(text)
    if not value >= 0:  # NaN too
        raise argparse.ArgumentTypeError(f"expected a finite number of pixels >= 0, got '{text}'")
    return value


def add_navigation_options(parser: argparse.ArgumentParser) -> None:
    """Map, segmentation and correspondence options shared by ``ursim goal`` and ``ursim route``."""
    from ursim_core.cli.match_options import add_preset_options

    parser.add_argument("sketch", metavar="SKETCH", help="the sketch image")
    parser.add_argument("metric", metavar="METRIC", help="the robot's map: map_server YAML (or an image: pixels only)")
    parser.add_argument(
        "--correspondences",
        metavar="FILE",
        help="use these cliques (JSON) instead of matching; their label images are used when present",
    )
    add_preset_options(parser)
    parser.add_argument(
        "--tolerance", type=tolerance_value, default=10, help="px from a region a point still counts (default 10)"
    )
    parser.add_argument("-o", "--output", metavar="FILE", help="also write the JSON to FILE")
    group = parser.add_argument_group("map loading")
    group.add_argument("--threshold", type=int, default=250, help="images: grey above which a pixel is free (250)")
    group.add_argument("--nonzero-free", action="store_true", help="images: every non-zero pixel is free")
    group.add_argument("--max-pixels", type=int, default=64_000_000, help="refuse larger maps (default 64 Mpx)")


HELP = "Turn a point on the sketch into a goal pose in the robot's map (PoseStamped-like JSON)."


def configure(parser: argparse.ArgumentParser) -> None:
    """The options of ``ursim goal`` (called by :func:`ursim_core.cli.main.build_parser`)."""
    add_navigation_options(parser)
    parser.add_argument(
        "--at",
        action="append",
        required=True,
        type=parse_point,
        metavar="ROW,COL",
        help="the sketch point in pixels (repeatable)",
    )
    parser.add_argument(
        "--target",
        choices=["interior", "mirror"],
        default="interior",
        help="interior point of the matched region (default) or the point mirroring the tap's place in its region",
    )
    parser.add_argument("--yaw", type=finite_number, default=0.0, help="heading of the goal in the map frame, radians")


def run(args: argparse.Namespace) -> int:
    return cmd_goal(args)


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``goal`` to a set of sub-commands (``subparsers`` from ``add_subparsers``), on its own."""
    import sys

    from ursim_core.cli.common import add_subcommand

    return add_subcommand(subparsers, "goal", sys.modules[__name__])


def prepare_navigation(args: argparse.Namespace, *, correspondences=None) -> Navigation:
    """Load both maps, segment them (or load the correspondence file's label images) and match.

    ``correspondences``: the file of ``args.correspondences`` when the caller has loaded it
    already (for its overwrite check, :func:`navigation_inputs`); else it is loaded here.
    """
    from ursim_core.io.maps import load_map
    from ursim_core.navigation.goal import match_table

    def load(path):
        return load_map(path, threshold=args.threshold, nonzero_free=args.nonzero_free, max_pixels=args.max_pixels)

    sketch_map, metric_map = load(args.sketch), load(args.metric)
    if args.correspondences:
        from ursim_core.correspondences import assign_regions, load_correspondences

        corr = correspondences if correspondences is not None else load_correspondences(Path(args.correspondences))
        sketch_seg = _labels_or_segment(corr.sketch, sketch_map, args.sketch_preset)
        metric_seg = _labels_or_segment(corr.metric, metric_map, args.metric_preset)
        # Points are authoritative: region ids follow the segmentations used here.
        corr = assign_regions(corr, sketch_seg.labels, metric_seg.labels, tolerance=args.tolerance)
        return Navigation(sketch_map, metric_map, sketch_seg, metric_seg, match_table(corr), "correspondences")
    from ursim_core.matching import match_maps

    # As ursim match matches: the sketch in its canonical pose with its resamplings, two YAMLs'
    # scale (a turned KTH sketch's goals went to the wrong room with plain segment + match).
    found = match_maps(sketch_map, metric_map, sketch_preset=args.sketch_preset, metric_preset=args.metric_preset)
    return Navigation(sketch_map, metric_map, found.sketch_seg, found.metric_seg, match_table(found.result), "match")


def _labels_or_segment(ref, the_map, preset: str):
    from ursim_core.segmentation import load_label_image, segment

    if ref.labels_path is not None and Path(ref.labels_path).is_file():
        return load_label_image(ref.labels_path, shape=the_map.shape)
    return segment(the_map, preset=preset)


def navigation_inputs(args: argparse.Namespace) -> tuple[list, Any]:
    """The files ``ursim goal`` and ``ursim route`` read, for the overwrite check, and the loaded
    correspondence file (None without ``--correspondences``).

    Beside the arguments: the image of a ROS YAML map, and the maps and label images the
    correspondence file names (:mod:`ursim_core.cli.inputs`).
    """
    from ursim_core.cli.inputs import correspondence_inputs, map_inputs

    corr = None
    if args.correspondences:
        from ursim_core.correspondences import load_correspondences

        corr = load_correspondences(Path(args.correspondences))
    inputs = [
        args.sketch,
        args.metric,
        args.correspondences,
        *map_inputs(args.sketch),
        *map_inputs(args.metric),
        *correspondence_inputs(args.correspondences, corr),
    ]
    return inputs, corr


def goal_document(goal, *, frame_id: str = "map") -> dict[str, Any]:
    """The PoseStamped-like object ``ursim goal`` prints for one goal."""
    from ursim_core.navigation.nav2_files import pose_stamped

    if goal.pose is not None:
        document = pose_stamped(goal.pose, frame_id=frame_id)
    else:
        document = {"header": {"frame_id": frame_id, "stamp": {"sec": 0, "nanosec": 0}}, "pose": None}
    document["ursim"] = goal.to_dict()
    return document


def write_json(document: Any, output: str | None) -> None:
    """Print ``document`` and, with ``-o``, write it atomically to the file.

    Raises
    ------
    FormatError
        A number in ``document`` is NaN or infinite (JSON has none; a map whose origin and
        resolution overflow puts them in a pose), naming the file and the field; nothing is
        printed or written.
    """
    from ursim_core.correspondences.json_text import finite_json

    text = finite_json(document, output or "<standard output>", indent=2) + "\n"
    if not (output and _is_standard_output(output)):
        sys.stdout.write(text)  # not twice for `-o /dev/stdout | jq .`
    if output:
        from ursim_core.io.atomic import atomic_write_text

        sys.stdout.flush()
        atomic_write_text(Path(output), text)


def _is_standard_output(output: str) -> bool:
    """Whether the file ``output`` is this process's standard output (``/dev/stdout``, or the
    file or pipe it was redirected to)."""
    import os

    try:
        mine, theirs = os.fstat(sys.stdout.fileno()), os.stat(output)
    except (OSError, ValueError, AttributeError):
        return False  # no file behind sys.stdout (captured), or no such output yet
    return (mine.st_dev, mine.st_ino) == (theirs.st_dev, theirs.st_ino)


def cmd_goal(args: argparse.Namespace) -> int:
    import numpy as np

    from ursim_core.navigation.goal import locate

    # The argparse types refuse these; a Namespace built in code gets the same checks.
    if not (math.isfinite(args.tolerance) and args.tolerance >= 0):
        raise ParameterError(f"--tolerance must be a finite number >= 0, got {args.tolerance}")
    if not math.isfinite(args.yaw):
        raise ParameterError(f"--yaw must be a finite number of radians, got {args.yaw}")
    for row, col in args.at:
        if not (math.isfinite(row) and math.isfinite(col)):
            raise ParameterError(f"--at must be two finite numbers, got {row},{col}")
    check_map_options(args)
    inputs, corr = navigation_inputs(args)
    refuse_overwriting_inputs([args.output], inputs)
    nav = prepare_navigation(args, correspondences=corr)
    # A georeference too large overflows to NaN or infinity, which write_json refuses by name:
    # numpy's warnings would only add lines that do not say which file is at fault.
    with np.errstate(over="ignore", invalid="ignore"):
        goals = [
            locate(
                nav.table,
                nav.sketch_seg,
                nav.metric_seg,
                nav.metric_map,
                row,
                col,
                target=args.target,
                tolerance=args.tolerance,
                yaw=args.yaw,
            )
            for row, col in args.at
        ]
    documents = [goal_document(goal) for goal in goals]
    write_json(documents[0] if len(documents) == 1 else documents, args.output)
    if nav.metric_map.resolution is None:
        print(
            f"note: {args.metric} has no resolution (not a map_server YAML): goals are in pixels only (ursim.pixel)",
            file=sys.stderr,
        )
    failures = [goal for goal in goals if not goal.ok]
    for goal in failures:
        print(f"error: {goal.failure_message()}", file=sys.stderr)
    return 1 if failures else 0
