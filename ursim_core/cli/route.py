"""``ursim route``: a polyline drawn on the sketch becomes waypoints for nav2.

Registered by ``ursim_core.cli.main.build_parser`` with ``route.add_parser(commands)``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from ursim_core.cli.goal import add_navigation_options, navigation_inputs, prepare_navigation, write_json
from ursim_core.errors import FormatError, ParameterError

__all__ = ["add_parser", "cmd_route", "read_points"]

EXAMPLES = """examples:
  ursim route sketch.png map.yaml --points route.json
  ursim route sketch.png map.yaml --points route.txt --waypoints route_wps.yaml -o route_out.json

The points file holds the polyline in sketch pixels: JSON ([[row, col], ...] or {"points": [...]})
or text, one "ROW,COL" (or "ROW COL") per line, '#' comments allowed. Prints the route as JSON: the
metric regions, one PoseStamped-like object per waypoint (frame "map") and the details. --waypoints
writes the file nav2's RViz panel loads ("Load WPs") for FollowWaypoints / NavigateThroughPoses."""


HELP = "Turn a route drawn on the sketch into connected metric regions and nav2 waypoints."


def configure(parser: argparse.ArgumentParser) -> None:
    """The options of ``ursim route`` (called by :func:`ursim_core.cli.main.build_parser`)."""
    add_navigation_options(parser)
    parser.add_argument("--points", required=True, metavar="FILE", help="the polyline (JSON or ROW,COL lines)")
    parser.add_argument("--waypoints", metavar="FILE", help="write a nav2 RViz-panel waypoint YAML (needs a YAML map)")
    parser.add_argument(
        "--no-fill", action="store_true", help="do not connect non-adjacent regions along the region graph"
    )


def run(args: argparse.Namespace) -> int:
    return cmd_route(args)


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``route`` to a set of sub-commands (``subparsers`` from ``add_subparsers``), on its own."""
    import sys

    from ursim_core.cli.common import add_subcommand

    return add_subcommand(subparsers, "route", sys.modules[__name__])


#: Largest points file read: a polyline of a million points is about 15 MB of text.
MAX_POINTS_BYTES = 64 * 1024**2


def read_points(path: str | Path) -> list[tuple[float, float]]:
    """The polyline of a points file (see the examples of ``ursim route --help``).

    The file is read as every input is (:func:`ursim_core.io.reading.read_regular_file`: a regular
    file of at most :data:`MAX_POINTS_BYTES`, never a pipe), UTF-8 with or without a byte-order
    mark; JSON too deep, with NaN or numbers out of range is refused.

    Raises :class:`~ursim_core.errors.FormatError` naming the file and the line or item.
    """
    from ursim_core.io.reading import decode_text, parse_json, read_regular_file

    path = Path(path)
    what = "points file"
    raw = read_regular_file(path, max_bytes=MAX_POINTS_BYTES, error=FormatError, what=what)
    text = decode_text(raw, path, error=FormatError, what=what)
    stripped = text.lstrip()
    if stripped.startswith(("[", "{")):
        document = parse_json(text, path, error=FormatError, what=what)
        items = document.get("points") if isinstance(document, dict) else document
        if not isinstance(items, list):
            raise FormatError('expected a list of [row, col] points (or {"points": [...]})', path=path)
        points = []
        for index, item in enumerate(items):
            # parse_json admits only finite numbers that convert to float.
            if (
                not isinstance(item, list)
                or len(item) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in item)
            ):
                raise FormatError(
                    f"expected [row, col], got {json.dumps(item)[:40]}", path=path, field=f"points[{index}]"
                )
            points.append((float(item[0]), float(item[1])))
    else:
        points = []
        for number, line in enumerate(text.splitlines(), start=1):
            content = line.split("#", 1)[0].strip()
            if not content:
                continue
            parts = content.replace(",", " ").split()
            try:
                if len(parts) != 2:
                    raise ValueError
                point = (float(parts[0]), float(parts[1]))
            except ValueError:
                raise FormatError(f"line {number}: expected ROW,COL, got '{content[:40]}'", path=path) from None
            if not all(math.isfinite(v) for v in point):
                raise FormatError(f"line {number}: ROW and COL must be finite numbers, got '{content[:40]}'", path=path)
            points.append(point)
    if not points:
        raise FormatError("no point in the file", path=path)
    return points


def cmd_route(args: argparse.Namespace) -> int:
    from ursim_core.cli.common import check_map_options, refuse_overwriting_inputs
    from ursim_core.navigation.nav2_files import pose_stamped, save_waypoints_yaml
    from ursim_core.navigation.route import plan_route

    if args.tolerance < 0:
        raise ParameterError(f"--tolerance must be >= 0, got {args.tolerance}")
    check_map_options(args)
    inputs, corr = navigation_inputs(args)
    refuse_overwriting_inputs([args.output, args.waypoints], [*inputs, args.points])
    points = read_points(args.points)
    nav = prepare_navigation(args, correspondences=corr)
    if args.waypoints and nav.metric_map.resolution is None:
        raise ParameterError(
            f"--waypoints needs a georeferenced map (map_server YAML), {args.metric} has no resolution"
        )
    route = plan_route(
        nav.table,
        nav.sketch_seg,
        nav.metric_seg,
        nav.metric_map,
        points,
        tolerance=args.tolerance,
        fill_gaps=not args.no_fill,
    )
    document = {
        "header": {"frame_id": "map", "stamp": {"sec": 0, "nanosec": 0}},
        "poses": [pose_stamped(w.pose) for w in route.waypoints if w.pose is not None],
        "ursim": route.to_dict(),
    }
    write_json(document, args.output)
    if not route.waypoints:
        print(
            f"error: the route crosses no matched sketch region (crossed: {list(route.sketch_regions) or 'none'})",
            file=sys.stderr,
        )
        return 1
    if args.waypoints:
        save_waypoints_yaml([w.pose for w in route.waypoints], args.waypoints)
        print(f"wrote {args.waypoints} ({len(route.waypoints)} waypoints)", file=sys.stderr)
    if route.skipped:
        print(f"note: unmatched sketch regions left out of the route: {list(route.skipped)}", file=sys.stderr)
    if route.gaps:
        print(f"note: no path in the region graph between {[list(g) for g in route.gaps]}", file=sys.stderr)
    return 0
