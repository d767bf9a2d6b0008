"""``ursim match``: match a sketch map to a metric map, write correspondences and a figure.

With ``--reference FILE`` (a ground-truth .dat or correspondence JSON of the same pair) the result
is also scored: precision, recall, F1 (:func:`ursim_core.evaluation.scoring.score_matches`) and
place accuracy (:func:`ursim_core.evaluation.scoring.place_accuracy`, places in the MAORIS
``default`` segmentation of the metric map).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from ursim_core.cli.common import (
    add_map_options,
    check_output_folder,
    load,
    segmentation_params,
    staged_folder,
)
from ursim_core.errors import ParameterError

HELP = "Match a sketch map to a metric map and write correspondences and a figure."
EXAMPLES = """examples:
  ursim match resources/example/sketch.png resources/example/metric.png -o out/
  ursim match sketch.png metric.yaml --m 0.1 --variant T2 --matcher hungarian -o out/
  ursim match 00.png model_simple.png -o out/ --reference gt_00_model_simple.dat"""


def configure(parser: argparse.ArgumentParser) -> None:
    # The presets' defaults come from the matching pipeline, imported only for this subcommand.
    from ursim_core.matching.pipeline import MATCH_PRESETS

    parser.add_argument("sketch", metavar="SKETCH")
    parser.add_argument("metric", metavar="METRIC")
    parser.add_argument("-o", "--output", metavar="OUT", required=True, help="output folder")
    parser.add_argument("--m", default="auto", help="threshold m on the signature difference, or 'auto' (default)")
    parser.add_argument("--variant", choices=["T1", "T2", "T3", "T4", "baseline"], help="descriptor variant")
    parser.add_argument("--matcher", choices=["planar", "hungarian", "vf2"], help="graph matcher")
    parser.add_argument("--released", action="store_true", help="start from the released C++ code's options")
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
    parser.add_argument(
        "--param", action="append", metavar="NAME=VALUE", help="segmentation parameter override (both maps)"
    )
    parser.add_argument(
        "--reference",
        metavar="FILE",
        help="ground truth of this pair (.dat or .json): print precision, recall, F1 and place accuracy",
    )
    add_map_options(parser)


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
    if args.variant:
        overrides["variant"] = args.variant
    if args.matcher:
        overrides["matcher"] = args.matcher
    return base.replace(**overrides)


def matcher_record(config, result) -> dict[str, Any]:
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


def load_reference(path: str | Path):
    """A ground-truth file of either format, by its suffix."""
    from ursim_core.correspondences.codec import load_correspondences, load_dat

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".dat":
        return load_dat(path)
    if suffix == ".json":
        return load_correspondences(path)
    raise ParameterError("unknown ground-truth file type (expected .dat or .json)", path=path)


def reference_scores(pairs, reference, sketch_seg, metric_seg, metric_map, *, metric_preset: str, params: dict):
    """Pair score and place score of ``pairs`` against a ground truth with points."""
    from ursim_core.correspondences.codec import assign_regions
    from ursim_core.evaluation.scoring import PLACE_REFERENCE_PRESET, place_accuracy, score_matches

    assigned = assign_regions(reference, sketch_seg.labels, metric_seg.labels, tolerance=10)
    pair_score = score_matches(pairs, assigned)
    if metric_preset == PLACE_REFERENCE_PRESET and not params:
        place_labels = metric_seg.labels
    else:
        from ursim_core.cli.segment import segment_checked

        place_labels = segment_checked(metric_map, preset=PLACE_REFERENCE_PRESET, params={}).labels
    place = place_accuracy(
        pairs, reference, sketch_seg.labels, metric_seg.labels, place_labels, metric_seg.graph, tolerance=10
    )
    return pair_score, place


def run(args: argparse.Namespace) -> int:
    from ursim_core.cli.segment import segment_checked
    from ursim_core.correspondences.codec import Correspondences, MapRef, from_pairs, save_correspondences
    from ursim_core.matching import match
    from ursim_core.render.figures import save_png, side_by_side_matches
    from ursim_core.segmentation import save_label_image

    config = match_config(args)
    out = check_output_folder(args.output)
    # A bad ground-truth file is reported before any work.
    reference = None if args.reference is None else load_reference(args.reference)
    sketch_map, metric_map = load(args.sketch, args), load(args.metric, args)
    params = segmentation_params(args)
    sketch_seg = segment_checked(sketch_map, preset=args.sketch_preset, params=params)
    metric_seg = segment_checked(metric_map, preset=args.metric_preset, params=params)
    started = time.perf_counter()
    result = match(sketch_seg, metric_seg, config=config)
    elapsed = time.perf_counter() - started

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
        extra={"matcher": matcher_record(config, result)},
    )
    figure = side_by_side_matches(
        (sketch_seg.labels, sketch_seg.graph, sketch_map.image),
        (metric_seg.labels, metric_seg.graph, metric_map.image),
        result.pairs,
        anchors=result.anchors,
    )
    # The images are staged and moved in together; the JSON, which names them, is written last
    # (atomically, in place, so the paths it stores are relative to its own folder).
    with staged_folder(out) as staging:
        save_label_image(sketch_seg, staging / "sketch.labels.png")
        save_label_image(metric_seg, staging / "metric.labels.png")
        save_png(staging / "matches.png", figure)
    save_correspondences(corr, out / "correspondences.json")
    m_text = f"{result.m:.3f}" if isinstance(result.m, (int, float)) else str(result.m)
    print(
        f"{len(result.pairs)} matches ({sketch_seg.n_regions} sketch regions, {metric_seg.n_regions} metric regions), "
        f"m = {m_text}, {elapsed * 1000:.1f} ms" + (f"; {result.reason}" if result.reason else "")
    )
    print(f"wrote {out / 'correspondences.json'}, {out / 'matches.png'}")
    if reference is not None:
        pair_score, place = reference_scores(
            result.pairs, reference, sketch_seg, metric_seg, metric_map, metric_preset=args.metric_preset, params=params
        )
        place_text = "-" if place.accuracy != place.accuracy else f"{place.accuracy:.3f}"
        print(
            f"against {args.reference}: precision {pair_score.precision:.3f}, recall {pair_score.recall:.3f}, "
            f"F1 {pair_score.f1:.3f} (tp {pair_score.tp}, fp {pair_score.fp}, fn {pair_score.fn}); "
            f"place accuracy {place_text} ({place.successes}/{place.n_points} points, {place.n_cliques} cliques)"
        )
    return 0
