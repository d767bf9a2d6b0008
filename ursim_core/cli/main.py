"""The ``ursim`` command line.

Exit codes: 0 success, 1 bad input (one line per error on stderr, never a traceback),
2 usage error (argparse).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ursim_core.errors import ParameterError, UrsimError

EXAMPLES = {
    "segment": """examples:
  ursim segment resources/example/sketch.png -o out/
  ursim segment maps/*.png --preset robot --param threshold=0.4 -o out/
  ursim segment --evaluate GT_DIR MAPS_DIR --preset sketch""",
    "match": """examples:
  ursim match resources/example/sketch.png resources/example/metric.png -o out/
  ursim match sketch.png metric.yaml --m 0.1 --variant T2 --matcher hungarian -o out/""",
    "evaluate": """examples:
  ursim evaluate ../shared/datasets/ursim_kth_sketches -o report/
  ursim evaluate ../shared/datasets/ursim_halmstad_robot_maps/E5 --matchers planar --variants T4""",
    "convert": """examples:
  ursim convert gt_00_model_simple.dat gt_00.json --sketch 00.png --metric model_simple.png
  ursim convert gt_00.json gt_00.dat""",
    "bench": """examples:
  ursim bench segment
  ursim bench all --datasets ../shared/datasets""",
}


class ProgressBar:
    """A one-line progress bar on stderr (plain lines when stderr is not a terminal)."""

    def __init__(self, total: int, *, label: str = "", stream=None, enabled: bool = True):
        self.total = max(total, 1)
        self.label = label
        self.stream = stream or sys.stderr
        self.enabled = enabled and total > 1
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int | None = None, text: str = "") -> None:
        if not self.enabled:
            return
        total = total or self.total
        fraction = min(done / max(total, 1), 1.0)
        bar = "#" * int(30 * fraction)
        elapsed = time.perf_counter() - self.start
        line = f"{self.label} [{bar:<30}] {done}/{total} {elapsed:5.1f}s {text}"
        if self.tty:
            self.stream.write("\r" + line[:120].ljust(120))
            if done >= total:
                self.stream.write("\n")
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def _parse_param(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise ParameterError(f"--param expects NAME=VALUE, got '{text}'")
    name, raw = text.split("=", 1)
    value: Any = raw
    for convert in (int, float):
        try:
            value = convert(raw)
            break
        except ValueError:
            continue
    if raw.lower() in ("true", "false"):
        value = raw.lower() == "true"
    return name.strip(), value


def _add_map_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("map loading")
    group.add_argument(
        "--threshold", type=int, default=250, help="grey value above which a pixel is free (default 250)"
    )
    group.add_argument(
        "--nonzero-free",
        action="store_true",
        help="every non-zero pixel is free (the released URSIM driver's behaviour)",
    )
    group.add_argument(
        "--max-pixels", type=int, default=64_000_000, help="refuse maps larger than this (default 64 Mpx)"
    )


def _load(path: str | Path, args: argparse.Namespace):
    from ursim_core.io.maps import load_map

    return load_map(path, threshold=args.threshold, nonzero_free=args.nonzero_free, max_pixels=args.max_pixels)


def _region_records(segmentation) -> list[dict[str, Any]]:
    graph = segmentation.graph
    return [
        {
            "id": int(region),
            "size": int(data["size"]),
            "centroid": [round(v, 2) for v in data["centroid"]],
            "interior": [int(v) for v in data["interior"]],
            "bbox": [int(v) for v in data["bbox"]],
            "pca_shape": round(float(data["pca_shape"]), 6),
            "neighbours": sorted(int(n) for n in graph.neighbors(region)),
        }
        for region, data in sorted(graph.nodes(data=True))
    ]


def _write_segmentation_outputs(the_map, segmentation, out: Path, *, preset: str | None) -> None:
    from ursim_core.io.atomic import atomic_write_text
    from ursim_core.render.figures import overlay_segmentation, save_png
    from ursim_core.segmentation import save_label_image

    name = the_map.name
    save_label_image(segmentation, out / f"{name}.labels.png")
    save_png(
        out / f"{name}.overlay.png",
        overlay_segmentation(segmentation.labels, segmentation.graph, image=the_map.image, free=the_map.free),
    )
    document = {
        "map": str(the_map.path) if the_map.path else None,
        "sha256": the_map.sha256,
        "size": list(the_map.shape),
        "segmentation": {"method": segmentation.method, "preset": preset, "params": segmentation.params},
        "regions": _region_records(segmentation),
    }
    atomic_write_text(out / f"{name}.regions.json", json.dumps(document, indent=2) + "\n")


def _segmentation_params(args: argparse.Namespace) -> dict[str, Any]:
    return dict(_parse_param(p) for p in args.param or [])


def cmd_segment(args: argparse.Namespace) -> int:
    from ursim_core.segmentation import resolve_params, segment

    params = _segmentation_params(args)
    resolve_params("maoris", args.preset, params)  # fail on a bad option before any work
    if args.evaluate:
        return _segment_evaluate(args, params)
    if not args.maps:
        raise ParameterError("give at least one MAP (or --evaluate GT_DIR MAPS_DIR)")
    if args.output is None:
        raise ParameterError("give an output folder with -o OUT")
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    progress = ProgressBar(len(args.maps), label="segment")
    failures = 0
    for index, path in enumerate(args.maps, start=1):
        try:
            the_map = _load(path, args)
            segmentation = segment(the_map, preset=args.preset, params=params)
            _write_segmentation_outputs(the_map, segmentation, out, preset=args.preset)
            if len(args.maps) == 1 or not progress.tty:
                print(f"{path}: {segmentation.n_regions} regions, {segmentation.graph.number_of_edges()} edges")
        except UrsimError as error:
            failures += 1
            print(f"error: {error}", file=sys.stderr)
        progress(index, text=Path(path).name)
    return 1 if failures else 0


def _segment_evaluate(args: argparse.Namespace, params: dict[str, Any]) -> int:
    from ursim_core.segmentation import segment
    from ursim_core.segmentation.scoring import gt_labels_from_separator_image, score_segmentation

    gt_dir, maps_dir = (Path(p) for p in args.evaluate)
    for folder in (gt_dir, maps_dir):
        if not folder.is_dir():
            raise ParameterError("not a folder", path=folder)
    pairs = [(m, gt_dir / m.name) for m in sorted(maps_dir.iterdir()) if (gt_dir / m.name).is_file()]
    if not pairs:
        raise ParameterError(f"no map in {maps_dir} has a ground truth of the same name in {gt_dir}")
    progress = ProgressBar(len(pairs), label="evaluate")
    rows = []
    for index, (map_path, gt_path) in enumerate(pairs, start=1):
        the_map = _load(map_path, args)
        segmentation = segment(the_map, preset=args.preset, params=params)
        score = score_segmentation(segmentation.labels, gt_labels_from_separator_image(gt_path))
        rows.append((map_path.stem, segmentation.n_regions, score.precision, score.recall, score.f1))
        progress(index, text=map_path.name)
    print(f"{'map':<24} {'regions':>7} {'precision':>9} {'recall':>7} {'F1':>6}")
    for name, n, p, r, f in rows:
        print(f"{name:<24} {n:>7} {p:>9.3f} {r:>7.3f} {f:>6.3f}")
    count = len(rows)
    means = [sum(row[i] for row in rows) / count for i in (2, 3, 4)]
    print(f"{'mean':<24} {'':>7} {means[0]:>9.3f} {means[1]:>7.3f} {means[2]:>6.3f}")
    return 0


def _match_config(args: argparse.Namespace):
    from ursim_core.matching import MatchConfig

    m: Any = args.m
    if m != "auto":
        try:
            m = float(m)
        except ValueError:
            raise ParameterError(f"--m expects 'auto' or a number, got '{args.m}'") from None
    base = MatchConfig.released() if args.released else MatchConfig()
    overrides: dict[str, Any] = {"m": m}
    if args.variant:
        overrides["variant"] = args.variant
    if args.matcher:
        overrides["matcher"] = args.matcher
    return base.replace(**overrides)


def _matcher_record(config, result) -> dict[str, Any]:
    """What produced the automatic cliques, JSON-safe (kept in the file as an unknown key)."""
    import dataclasses
    import math

    def safe(value: Any) -> Any:
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    return {
        "config": json.loads(json.dumps(dataclasses.asdict(config), default=str)),
        "m": safe(float(result.m)) if result.m is not None else None,
        "cost": safe(float(result.cost)) if result.cost is not None else None,
        "anchors": [[int(a), int(b)] for a, b in result.anchors],
        "reason": result.reason or "",
    }


def cmd_match(args: argparse.Namespace) -> int:
    from ursim_core.correspondences.codec import Correspondences, MapRef, from_pairs, save_correspondences
    from ursim_core.matching import match
    from ursim_core.render.figures import save_png, side_by_side_matches
    from ursim_core.segmentation import save_label_image, segment

    config = _match_config(args)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    sketch_map, metric_map = _load(args.sketch, args), _load(args.metric, args)
    params = _segmentation_params(args)
    sketch_seg = segment(sketch_map, preset=args.sketch_preset, params=params)
    metric_seg = segment(metric_map, preset=args.metric_preset, params=params)
    started = time.perf_counter()
    result = match(sketch_seg, metric_seg, config=config)
    elapsed = time.perf_counter() - started
    save_label_image(sketch_seg, out / "sketch.labels.png")
    save_label_image(metric_seg, out / "metric.labels.png")

    def ref(the_map, seg, labels_name):
        return MapRef(
            path=Path(the_map.path).resolve() if the_map.path else None,
            sha256=the_map.sha256,
            size=tuple(the_map.shape),
            segmentation_method=seg.method,
            segmentation_params=dict(seg.params),
            labels_path=(out / labels_name).resolve(),
            extra={},
        )

    cliques = from_pairs(
        result.pairs,
        sketch_points_of=lambda r: sketch_seg.graph.nodes[r]["interior"],
        metric_points_of=lambda r: metric_seg.graph.nodes[r]["interior"],
        source="auto",
    )
    corr = Correspondences(
        sketch=ref(sketch_map, sketch_seg, "sketch.labels.png"),
        metric=ref(metric_map, metric_seg, "metric.labels.png"),
        cliques=cliques,
        extra={"matcher": _matcher_record(config, result)},
    )
    save_correspondences(corr, out / "correspondences.json")
    figure = side_by_side_matches(
        (sketch_seg.labels, sketch_seg.graph, sketch_map.image),
        (metric_seg.labels, metric_seg.graph, metric_map.image),
        result.pairs,
        anchors=result.anchors,
    )
    save_png(out / "matches.png", figure)
    m_text = f"{result.m:.3f}" if isinstance(result.m, (int, float)) else str(result.m)
    print(
        f"{len(result.pairs)} matches ({sketch_seg.n_regions} sketch regions, {metric_seg.n_regions} metric regions), "
        f"m = {m_text}, {elapsed * 1000:.1f} ms" + (f"; {result.reason}" if result.reason else "")
    )
    print(f"wrote {out / 'correspondences.json'}, {out / 'matches.png'}")
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from ursim_core.evaluation.runner import format_tables, run_evaluation, write_report

    progress = ProgressBar(1, label="evaluate")

    def report_progress(done: int, total: int, text: str = "") -> None:
        progress.total, progress.enabled = max(total, 1), total > 1
        progress(done, total, text)

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
        progress=report_progress,
    )
    print(format_tables(result))
    if args.output:
        write_report(result, Path(args.output))
        print(f"report written to {args.output}")
    return 0


def cmd_convert(args: argparse.Namespace) -> int:
    from ursim_core.cli.convert import convert

    convert(Path(args.input), Path(args.output), sketch=args.sketch, metric=args.metric)
    print(f"wrote {args.output}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from ursim_core.bench.runner import run_bench

    return run_bench(args.what, datasets=args.datasets, repeats=args.repeats)


def build_parser() -> argparse.ArgumentParser:
    from ursim_core import __version__
    from ursim_core.matching import MATCH_PRESETS

    parser = argparse.ArgumentParser(
        prog="ursim",
        description="Match hand-drawn sketch maps to metric maps (URSIM): segment, match, evaluate.",
        epilog="Run 'ursim COMMAND --help' for examples. Pixel coordinates are (row, col).",
    )
    parser.add_argument("--version", action="version", version=f"ursim {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def sub(name: str, help_text: str, handler: Callable[[argparse.Namespace], int]) -> argparse.ArgumentParser:
        p = commands.add_parser(
            name,
            help=help_text,
            description=help_text,
            epilog=EXAMPLES.get(name),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        p.set_defaults(handler=handler)
        return p

    seg = sub(
        "segment", "Segment maps into regions (MAORIS) and write labels, overlays and region tables.", cmd_segment
    )
    seg.add_argument("maps", nargs="*", metavar="MAP", help="map images or ROS map YAML files")
    seg.add_argument("-o", "--output", metavar="OUT", help="output folder")
    seg.add_argument(
        "--preset", default="sketch", help="parameter preset: sketch, robot, default, icra, ursim-released"
    )
    seg.add_argument("--param", action="append", metavar="NAME=VALUE", help="override one parameter (repeatable)")
    seg.add_argument(
        "--evaluate",
        nargs=2,
        metavar=("GT_DIR", "MAPS_DIR"),
        help="score the segmentation of MAPS_DIR against separator-line ground truth in GT_DIR",
    )
    _add_map_options(seg)

    mat = sub("match", "Match a sketch map to a metric map and write correspondences and a figure.", cmd_match)
    mat.add_argument("sketch", metavar="SKETCH")
    mat.add_argument("metric", metavar="METRIC")
    mat.add_argument("-o", "--output", metavar="OUT", required=True, help="output folder")
    mat.add_argument("--m", default="auto", help="threshold m on the signature difference, or 'auto' (default)")
    mat.add_argument("--variant", choices=["T1", "T2", "T3", "T4", "baseline"], help="descriptor variant")
    mat.add_argument("--matcher", choices=["planar", "hungarian", "vf2"], help="graph matcher")
    mat.add_argument("--released", action="store_true", help="start from the released C++ code's options")
    mat.add_argument(
        "--sketch-preset",
        default=MATCH_PRESETS["sketch"],
        help=f"segmentation preset for the sketch (default {MATCH_PRESETS['sketch']}, measured best for matching)",
    )
    mat.add_argument(
        "--metric-preset",
        default=MATCH_PRESETS["metric"],
        help=f"segmentation preset for the metric map (default {MATCH_PRESETS['metric']})",
    )
    mat.add_argument(
        "--param", action="append", metavar="NAME=VALUE", help="segmentation parameter override (both maps)"
    )
    _add_map_options(mat)

    ev = sub("evaluate", "Run the paper's experiments on a dataset folder and write a report.", cmd_evaluate)
    ev.add_argument("dataset", metavar="DATASET")
    ev.add_argument("-o", "--output", metavar="REPORT", help="report folder (CSV, plots, summary.md)")
    ev.add_argument(
        "--matchers", nargs="+", default=["planar", "hungarian", "vf2"], choices=["planar", "hungarian", "vf2"]
    )
    ev.add_argument(
        "--variants",
        nargs="+",
        default=["baseline", "T1", "T2", "T3", "T4"],
        choices=["baseline", "T1", "T2", "T3", "T4"],
    )
    ev.add_argument(
        "--legacy-scoring",
        nargs="?",
        const="as-built",
        default="none",
        choices=["none", "as-built", "fnfix"],
        help="reproduce the released scorer: 'as-built' (default when given: false negatives dropped, "
        "explains the paper's figures) or 'fnfix' (its flag initialised)",
    )
    ev.add_argument(
        "--paper",
        action="store_true",
        help="the paper's method (no position term, structural score + substitutions) instead of the default",
    )
    ev.add_argument(
        "--released",
        action="store_true",
        help="every released-code option on (segmentation, binarisation, statistics, weights, rotations)",
    )
    ev.add_argument(
        "--preset", help=f"segmentation preset of the sketches / input maps (default {MATCH_PRESETS['sketch']})"
    )
    ev.add_argument("--metric-preset", help=f"segmentation preset of the model map (default {MATCH_PRESETS['metric']})")
    ev.add_argument("--maps", nargs="+", metavar="NAME", help="only these maps (e.g. 00 03 17)")
    ev.add_argument("--cache", metavar="DIR", help="cache segmentations in DIR between runs")
    ev.add_argument("--workers", type=int, default=2, help="processes (default 2)")

    conv = sub("convert", "Convert correspondences between the original .dat files and JSON.", cmd_convert)
    conv.add_argument("input", metavar="IN", help=".dat or .json")
    conv.add_argument("output", metavar="OUT", help=".json or .dat")
    conv.add_argument("--sketch", help="sketch map (for .dat -> JSON: stored in the JSON, regions assigned)")
    conv.add_argument("--metric", help="metric map (for .dat -> JSON)")

    bench = sub("bench", "Print speed and memory figures.", cmd_bench)
    bench.add_argument("what", choices=["segment", "scale", "match", "all"], nargs="?", default="all")
    bench.add_argument("--datasets", help="datasets folder (default: $URSIM_DATASETS or ../shared/datasets)")
    bench.add_argument("--repeats", type=int, default=5)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except UrsimError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
