"""``ursim match``: match a sketch map to a metric map, write correspondences and a figure.

With ``--reference FILE`` (a ground-truth .dat or correspondence JSON of the same pair) the result
is also scored: precision, recall, F1 (:func:`ursim_core.evaluation.scoring.score_matches`) and
place accuracy (:func:`ursim_core.evaluation.place.place_accuracy`, places in the MAORIS
``default`` segmentation of the metric map).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from ursim_core.cli.common import (
    check_map_options,
    check_output_files,
    check_output_folder,
    keep_freed_memory,
    load,
    refuse_overwriting_inputs,
    segmentation_params,
    staged_folder,
)
from ursim_core.cli.inputs import map_inputs
from ursim_core.cli.match_options import add_pair_options, match_config, options_of
from ursim_core.errors import ParameterError

HELP = "Match a sketch map to a metric map and write correspondences and a figure."
EXAMPLES = """examples:
  ursim match resources/example/sketch.png resources/example/metric.png -o out/
  ursim match sketch.png metric.yaml --m 0.1 --variant T2 --matcher hungarian -o out/
  ursim match 00.png model_simple.png -o out/ --reference gt_00_model_simple.dat"""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("sketch", metavar="SKETCH")
    parser.add_argument("metric", metavar="METRIC")
    parser.add_argument("-o", "--output", metavar="OUT", required=True, help="output folder")
    parser.add_argument(
        "--reference",
        metavar="FILE",
        help="ground truth of this pair (.dat or .json): print precision, recall, F1 and place accuracy",
    )
    parser.add_argument(
        "--review",
        metavar="FILE",
        help="a reviewed correspondence file of this pair (.json or .dat): its manual and accepted cliques "
        "are kept and in the answer, its rejected pairs are never proposed; pending automatic cliques "
        "are matched again",
    )
    add_pair_options(parser)


def load_reference(path: str | Path):
    """A ground-truth file of either format, by its suffix."""
    from ursim_core.correspondences import load_correspondence_file

    path = Path(path)
    if path.suffix.lower() not in (".dat", ".json"):
        raise ParameterError("unknown ground-truth file type (expected .dat or .json)", path=path)
    return load_correspondence_file(path)


def reviewed_cliques(review, sketch_seg, metric_seg):
    """The reviewed cliques of a correspondence file, on this run's regions, and their constraints.

    A clique a person made or reviewed (manual, accepted, rejected) keeps its points; its regions
    are those under the points in these segmentations. Pending automatic cliques are dropped:
    this run's answer replaces them. Returns ``([], None)`` without a file.
    """
    from ursim_core.correspondences import assign_regions
    from ursim_core.matching import constraints_from_cliques

    if review is None:
        return [], None
    review = assign_regions(review, sketch_seg.labels, metric_seg.labels, tolerance=10)
    kept = [c for c in review.cliques if c.is_reviewed]
    sizes = {
        "sketch": dict(sketch_seg.graph.nodes(data="size", default=0)),
        "metric": dict(metric_seg.graph.nodes(data="size", default=0)),
    }
    return kept, constraints_from_cliques(kept, sizes=sizes) or None


def load_and_segment(sketch, metric, args, config, *, params: dict[str, Any], constrained: bool = False):
    """Both maps loaded on two threads, then segmented for matching
    (:func:`ursim_core.matching.segment_pair`, two threads again); the configuration with two
    georeferenced maps' scale.

    The decoders, OpenCV and the MAORIS kernels release the GIL, so two building-sized maps take
    about the time of the larger one (8000 px: about 13 s instead of 23 s, peak resident memory
    3.0 GB instead of 2.0 GB for this step). The results are those of one step after the other;
    the sketch's error, when both fail, is the one raised, and no segmentation starts before both
    maps have loaded.
    """
    from concurrent.futures import ThreadPoolExecutor

    from ursim_core.cli.common import announce_kernel_compilation
    from ursim_core.matching import segment_pair

    announce_kernel_compilation()
    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="ursim-match") as pool:
        sketch_load, metric_load = pool.submit(load, sketch, args), pool.submit(load, metric, args)
        sketch_map, metric_map = sketch_load.result(), metric_load.result()
    # Two georeferenced maps (ROS YAML): the scale is known, metric pixels per input pixel.
    config = config.with_resolutions(sketch_map.resolution, metric_map.resolution)
    sketch_seg, metric_seg = segment_pair(
        sketch_map,
        metric_map,
        config=config,
        sketch_preset=args.sketch_preset,
        metric_preset=args.metric_preset,
        params=params,
        constrained=constrained,
    )
    _return_freed_memory()
    return sketch_map, metric_map, sketch_seg, metric_seg, config


def _return_freed_memory() -> None:
    """Give the memory the segmentations freed back to the system (glibc only; else nothing).

    glibc keeps what a thread freed in that thread's arena; the matcher's own large arrays are
    then taken from fresh pages, and the process peaks higher than with one thread.
    """
    import ctypes

    # The process's own symbols include the C library's: ctypes.util.find_library("c") would
    # run ``ldconfig -p`` in a subprocess to name it (10 ms of every ``ursim match``).
    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError, TypeError):
        pass


#: The files ``ursim match`` writes into its output folder.
OUTPUT_NAMES = ("sketch.labels.png", "metric.labels.png", "matches.png", "correspondences.json")


def save_staged_correspondences(corr, staging: Path, out: Path) -> None:
    """What :func:`~ursim_core.correspondences.save_correspondences` writes to ``out``, written
    to ``staging`` (paths relative to ``out``), so it appears with the images or not at all."""
    import dataclasses

    from ursim_core.correspondences import correspondences_to_json, utc_timestamp
    from ursim_core.correspondences.files import paused_garbage_collection, write_guarded

    stamp = utc_timestamp()
    corr = dataclasses.replace(corr, created=corr.created or stamp, modified=stamp)
    with paused_garbage_collection():
        text = correspondences_to_json(corr, folder=out, path=out / "correspondences.json")
    write_guarded(corr, staging / "correspondences.json", text.encode(), expected_sha256=None, what="correspondences")


def match_pair(
    sketch, metric, out: Path, options: dict[str, Any], *, reference_path=None, review_path=None
) -> dict[str, Any]:
    """Match one pair and write its outputs into ``out``; a record of what was done.

    The record has the counts, m, time and, with ``reference_path``, precision, recall, F1 and
    place accuracy against that ground truth. Errors propagate (the caller decides).
    ``review_path``: a correspondence file of the pair whose reviewed cliques constrain the
    answer and are written back with it (:func:`reviewed_cliques`).
    """
    from types import SimpleNamespace

    from ursim_core.correspondences import check_maps
    from ursim_core.matching import CONSTRAINED_MATCHERS, MapsMatch, match
    from ursim_core.matching.results import laid_by, next_reading_record
    from ursim_core.render.figures import save_png, side_by_side_matches
    from ursim_core.segmentation import save_label_image

    args = SimpleNamespace(**options)
    config = match_config(args)
    check_map_options(args)
    out = check_output_folder(out)
    # Before any work: no output may replace an input (a YAML map's image too), nor land where a
    # folder or device is.
    refuse_overwriting_inputs(
        [out / name for name in OUTPUT_NAMES],
        [sketch, metric, reference_path, review_path, *map_inputs(sketch), *map_inputs(metric)],
    )
    check_output_files(out, OUTPUT_NAMES)
    # A bad ground-truth file is reported before any work.
    reference = None if reference_path is None else load_reference(reference_path)
    review = None if review_path is None else load_reference(review_path)
    params = segmentation_params(args)
    # A review's pairs fix region ids of one segmentation: no resamplings to vote over then.
    sketch_map, metric_map, sketch_seg, metric_seg, config = load_and_segment(
        sketch, metric, args, config, params=params, constrained=review is not None
    )
    for loaded, loaded_path in ((reference, reference_path), (review, review_path)):
        if loaded is not None:
            # A file of another pair is named as such, not by its label image's size.
            check_maps(loaded, sketch_map, metric_map, loaded_path)
    # The images and the JSON that names them are staged and moved in together, so a failure
    # leaves none of them; the JSON's paths are made relative to OUT, where it ends up.
    # The two label images are encoded on two threads while the maps are matched (OpenCV
    # releases the GIL, the matcher holds it most of the time; 8000 px labels take about half a
    # second each); errors are raised in the order of the steps (match, labels, figure).
    from concurrent.futures import ThreadPoolExecutor

    with staged_folder(out) as staging, ThreadPoolExecutor(max_workers=2, thread_name_prefix="ursim-save") as pool:
        jobs = [
            pool.submit(save_label_image, sketch_seg, staging / "sketch.labels.png"),
            pool.submit(save_label_image, metric_seg, staging / "metric.labels.png"),
        ]
        kept, constraints = reviewed_cliques(review, sketch_seg, metric_seg)
        if constraints is not None and config.resolved().matcher not in CONSTRAINED_MATCHERS:
            print(
                f"note: the {config.resolved().matcher} matcher does not take the review's pairs; "
                "its reviewed cliques are kept as they are",
                file=sys.stderr,
            )
            constraints = None
        started = time.perf_counter()
        result = match(sketch_seg, metric_seg, config=config, constraints=constraints)
        elapsed = time.perf_counter() - started
        for job in jobs:
            job.result()
        corr = MapsMatch(sketch_map, metric_map, sketch_seg, metric_seg, result, config).correspondences(
            sketch_labels_path=out / "sketch.labels.png", metric_labels_path=out / "metric.labels.png", reviewed=kept
        )
        figure = side_by_side_matches(
            (sketch_seg.labels, sketch_seg.graph, sketch_map.image),
            (metric_seg.labels, metric_seg.graph, metric_map.image),
            result.pairs,
            anchors=result.anchors,
        )
        save_png(staging / "matches.png", figure)
        save_staged_correspondences(corr, staging, out)

    record: dict[str, Any] = {
        "n_matches": len(result.pairs),
        "n_sketch_regions": sketch_seg.n_regions,
        "n_metric_regions": metric_seg.n_regions,
        "m": result.m,
        "match_ms": elapsed * 1000,
        "reason": result.reason or "",
        "orientation": result.orientation,
        "resampling_votes": result.resampling_votes,
        "laid": result.laid,
        "laid_by": laid_by(result),
        **next_reading_record(result),
        "out": out,
    }
    if reference is not None:
        from ursim_core.evaluation import score_against_reference

        scores = score_against_reference(result.pairs, reference, sketch_seg, metric_seg, metric_map)
        pair_score, place = scores.pairs, scores.place
        record.update(
            precision=pair_score.precision,
            recall=pair_score.recall,
            f1=pair_score.f1,
            tp=pair_score.tp,
            fp=pair_score.fp,
            fn=pair_score.fn,
            place_accuracy=place.accuracy,
            place_points=f"{place.successes}/{place.n_points}",
            place_cliques=place.n_cliques,
        )
    return record


def run(args: argparse.Namespace) -> int:
    from ursim_core.matching.orientation import describe_gap

    keep_freed_memory()
    record = match_pair(
        args.sketch,
        args.metric,
        Path(args.output),
        options_of(args),
        reference_path=args.reference,
        review_path=args.review,
    )
    out = record["out"]
    m = record["m"]
    m_text = f"{m:.3f}" if isinstance(m, (int, float)) else str(m)
    print(
        f"{record['n_matches']} matches ({record['n_sketch_regions']} sketch regions, "
        f"{record['n_metric_regions']} metric regions), m = {m_text}, sketch turned "
        f"{record['orientation'][0]:.1f} deg{' mirrored' if record['orientation'][1] else ''}"
        + (f", voted over {record['resampling_votes']} resamplings" if record["resampling_votes"] else "")
        + (", pairs from the sketch laid and bent onto the map" if record["laid"] else "")
        + (" where the graph answer puts it" if record["laid_by"] == "answer" else "")
        + (" on the part of the map it resembles most" if record["laid_by"] == "window" else "")
        + f", {record['match_ms']:.1f} ms"
        + (f"; {record['reason']}" if record["reason"] else "")
    )
    runner_up = record.get("next_reading")
    if runner_up is not None:
        # How close the matcher came to reading the sketch otherwise: a small gap asks for a look.
        print(
            f"next best reading: turned {runner_up['degrees']:.1f} deg{' mirrored' if runner_up['mirrored'] else ''}, "
            f"{describe_gap(runner_up['ranked_worse_by'])} (--orientation and --mirrored tell the matcher)"
        )
    print(f"wrote {out / 'correspondences.json'}, {out / 'matches.png'}")
    if args.reference is not None:
        place = record["place_accuracy"]
        place_text = "-" if place != place else f"{place:.3f}"
        print(
            f"against {args.reference}: precision {record['precision']:.3f}, recall {record['recall']:.3f}, "
            f"F1 {record['f1']:.3f} (tp {record['tp']}, fp {record['fp']}, fn {record['fn']}); "
            f"place accuracy {place_text} ({record['place_points']} points, {record['place_cliques']} cliques)"
        )
    return 0
