"""``ursim route``: a polyline drawn on the sketch becomes waypoints for nav2.

Registered by ``ursim_core.cli.main.build_parser`` with ``route.add_parser(commands)``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ursim_core.cli.goal import add_navigation_options, prepare_navigation, write_json
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


def read_points(path: str | Path) -> list[tuple[float, float]]:
    """The polyline of a points file (see the examples of ``ursim route --help``).

    Raises :class:`~ursim_core.errors.FormatError` naming the file and the line or item.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise FormatError(f"cannot read the points file: {error}", path=path) from None
    stripped = text.lstrip()
    if stripped.startswith(("[", "{")):
        try:
            document = json.loads(text)
        except json.JSONDecodeError as error:
            raise FormatError(f"not valid JSON: {error}", path=path) from None
        items = document.get("points") if isinstance(document, dict) else document
        if not isinstance(items, list):
            raise FormatError('expected a list of [row, col] points (or {"points": [...]})', path=path)
        points = []
        for index, item in enumerate(items):
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
                points.append((float(parts[0]), float(parts[1])))
            except ValueError:
                raise FormatError(f"line {number}: expected ROW,COL, got '{content[:40]}'", path=path) from None
    if not points:
        raise FormatError("no point in the file", path=path)
    return points


def cmd_route(args: argparse.Namespace) -> int:
    from ursim_core.navigation.nav2_files import pose_stamped, save_waypoints_yaml
    from ursim_core.navigation.route import plan_route

    if args.tolerance < 0:
        raise ParameterError(f"--tolerance must be >= 0, got {args.tolerance}")
    points = read_points(args.points)
    nav = prepare_navigation(args)
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
