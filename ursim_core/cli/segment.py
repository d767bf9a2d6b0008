"""``ursim segment``: segment maps into regions and write label images, overlays and region tables."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ursim_core.cli.common import (
    UsageError,
    add_map_options,
    announce_kernel_compilation,
    check_map_options,
    check_output_files,
    check_output_folder,
    load,
    progress_bar,
    refuse_overwriting_inputs,
    segmentation_params,
    staged_folder,
)
from ursim_core.cli.inputs import map_inputs
from ursim_core.errors import ParameterError, SegmentationError, UrsimError

HELP = "Segment maps into regions (MAORIS) and write labels, overlays and region tables."
EXAMPLES = """examples:
  ursim segment resources/example/sketch.png -o out/
  ursim segment maps/*.png --preset robot --param threshold=0.4 -o out/
  ursim segment --evaluate GT_DIR MAPS_DIR --preset sketch

Two maps with the same file name (a/map.png b/map.png) are written as map.* and map-2.*
(a note on stderr says so). Outputs of a map appear in OUT only when all of them are written."""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("maps", nargs="*", metavar="MAP", help="map images or ROS map YAML files")
    parser.add_argument("-o", "--output", metavar="OUT", help="output folder")
    parser.add_argument(
        "--method",
        choices=["maoris", "watershed", "learned"],
        help="segmenter: maoris (sketches and images) or watershed (clearance watershed with saddle-ratio doors, "
        "the default for ROS occupancy maps (.yaml): presets default, robot) or learned (MAORIS and watershed "
        "pieces merged by a classifier trained on sketches: presets default, sketch)",
    )
    parser.add_argument(
        "--preset",
        help="parameter preset: maoris: sketch (default), robot, default, icra, ursim-released; watershed: "
        "robot (default), default; learned: sketch (default), default",
    )
    parser.add_argument("--param", action="append", metavar="NAME=VALUE", help="override one parameter (repeatable)")
    parser.add_argument(
        "--evaluate",
        nargs=2,
        metavar=("GT_DIR", "MAPS_DIR"),
        help="score the segmentation of MAPS_DIR against separator-line ground truth in GT_DIR",
    )
    add_map_options(parser)


def output_names(paths: list[str]) -> list[str]:
    """The output name of each map: its file name without extension, numbered when taken.

    Examples
    --------
    >>> output_names(["a/map.png", "b/map.png", "c.png", "d/map.yaml"])
    ['map', 'map-2', 'c', 'map-3']
    """
    names: list[str] = []
    taken: set[str] = set()
    for path in paths:
        stem = Path(path).stem
        name, number = stem, 1
        while name in taken:
            number += 1
            name = f"{stem}-{number}"
        taken.add(name)
        names.append(name)
    return names


def region_records(segmentation) -> list[dict[str, Any]]:
    regions = segmentation.regions
    neighbours = regions.neighbours()
    return [
        {
            "id": int(region),
            "size": int(data["size"]),
            "centroid": [round(v, 2) for v in data["centroid"]],
            "interior": [int(v) for v in data["interior"]],
            "bbox": [int(v) for v in data["bbox"]],
            "pca_shape": round(float(data["pca_shape"]), 6),
            "neighbours": [int(n) for n in neighbours[region]],
        }
        for region, data in sorted(regions.nodes.items())
    ]


def output_files(name: str) -> tuple[str, str, str]:
    """The files :func:`write_segmentation_outputs` writes for the map of output name ``name``."""
    return f"{name}.labels.png", f"{name}.overlay.png", f"{name}.regions.json"


def write_segmentation_outputs(the_map, segmentation, out: Path, *, name: str, preset: str | None) -> None:
    from ursim_core.io.atomic import atomic_write_text
    from ursim_core.render.figures import overlay_segmentation, save_png
    from ursim_core.segmentation import save_label_image

    labels_name, overlay_name, regions_name = output_files(name)
    save_label_image(segmentation, out / labels_name)
    save_png(
        out / overlay_name,
        overlay_segmentation(segmentation.labels, segmentation.regions, image=the_map.image, free=the_map.free),
    )
    document = {
        "map": str(the_map.path) if the_map.path else None,
        "sha256": the_map.sha256,
        "size": list(the_map.shape),
        "segmentation": {"method": segmentation.method, "preset": preset, "params": segmentation.params},
        "regions": region_records(segmentation),
    }
    atomic_write_text(out / regions_name, json.dumps(document, indent=2) + "\n")


def segment_checked(
    the_map,
    *,
    preset: str,
    params: dict[str, Any],
    canonical: bool = False,
    method: str = "maoris",
    resampled: bool = False,
):
    """Segment a map; a segmentation with no region is an error that names the map.

    ``canonical``: in the map's canonical pose (:mod:`ursim_core.segmentation.canonical`), for a
    sketch whose orientation the matcher does not assume; ``resampled`` (with ``canonical``): also
    in the other resamplings of a map turned onto its wall axes, for the planar matcher's vote.
    """
    from ursim_core.segmentation import segment, segment_canonical, why_no_region

    announce_kernel_compilation()
    if canonical:
        segmentation = segment_canonical(the_map, method=method, preset=preset, params=params, resampled=resampled)
    else:
        segmentation = segment(the_map, method=method, preset=preset, params=params)
    if segmentation.n_regions == 0:
        raise SegmentationError(f"0 regions: {why_no_region(the_map.free, method=method)}", path=the_map.path)
    return segmentation


#: The preset of each method when only the method is given.
_METHOD_PRESETS = {"maoris": "sketch", "watershed": "robot", "learned": "sketch"}


def _by_kind(args: argparse.Namespace) -> bool:
    """No segmenter option given: each map gets the default of its kind."""
    return args.method is None and args.preset is None and not getattr(args, "param", None)


def segmenter_of(args: argparse.Namespace, the_map=None) -> tuple[str, str]:
    """``(method, preset)`` for a map: as given, else the default of its kind.

    With none of ``--method``, ``--preset`` and ``--param`` (parameters belong to one method), a ROS
    occupancy map (one with a resolution) gets
    the robot-map default (:data:`ursim_core.segmentation.DEFAULT_SEGMENTERS`: the watershed,
    leave-one-map-out F1 0.954 on the robot maps against MAORIS's 0.927) and anything else the
    sketch default (MAORIS ``sketch``). ``--preset`` alone keeps MAORIS, as before.
    """
    from ursim_core.segmentation import DEFAULT_SEGMENTERS

    if _by_kind(args):
        robot = the_map is not None and getattr(the_map, "resolution", None) is not None
        return DEFAULT_SEGMENTERS["robot" if robot else "sketch"]
    method = args.method or "maoris"
    return method, args.preset or _METHOD_PRESETS[method]


def run(args: argparse.Namespace) -> int:
    from ursim_core.segmentation import DEFAULT_SEGMENTERS, resolve_params

    params = segmentation_params(args)
    # Fail on a bad option before any work (with no option given, both defaults are checked).
    check_map_options(args)
    choices = set(DEFAULT_SEGMENTERS.values()) if _by_kind(args) else {segmenter_of(args)}
    for method, preset in choices:
        resolve_params(method, preset, params)
    if args.evaluate:
        return _evaluate(args, params)
    if not args.maps:
        raise UsageError("give at least one MAP (or --evaluate GT_DIR MAPS_DIR)")
    if args.output is None:
        raise UsageError("give an output folder with -o OUT")
    out = check_output_folder(args.output)
    names = output_names(args.maps)
    # No output may replace a map still to be read (nor a YAML map's image), nor the merge model
    # of --method learned.
    model = params.get("model")
    refuse_overwriting_inputs(
        [out / file for name in names for file in output_files(name)],
        [
            *args.maps,
            *(image for path in args.maps for image in map_inputs(path)),
            model if isinstance(model, str) and model != "default" else None,
        ],
    )
    for path, name in zip(args.maps, names):
        if name != Path(path).stem:
            print(f"note: {path} is written as {name}.* (another map has the same name)", file=sys.stderr)
    progress = progress_bar(len(args.maps), "segment")
    failures = 0
    for index, (path, name) in enumerate(zip(args.maps, names), start=1):
        try:
            check_output_files(out, output_files(name))
            the_map = load(path, args)
            method, preset = segmenter_of(args, the_map)
            if _by_kind(args) and method != "maoris":
                print(
                    f"note: {path} is a ROS occupancy map: segmented with {method} {preset} (--method maoris for MAORIS)",
                    file=sys.stderr,
                )
            segmentation = segment_checked(the_map, method=method, preset=preset, params=params)
            with staged_folder(out) as staging:
                write_segmentation_outputs(the_map, segmentation, staging, name=name, preset=preset)
            print(f"{path}: {segmentation.n_regions} regions, {segmentation.regions.number_of_edges()} edges")
        except UrsimError as error:
            failures += 1
            print(f"error: {error}", file=sys.stderr)
        progress(index, text=Path(path).name)
    return 1 if failures else 0


def _evaluate(args: argparse.Namespace, params: dict[str, Any]) -> int:
    from ursim_core.bench.quality import cross_validate_rule, data_chosen_rule
    from ursim_core.segmentation.presets_cv import BenchmarkMap
    from ursim_core.segmentation.scoring import gt_labels_from_separator_image, score_segmentation

    method, preset = segmenter_of(args)
    gt_dir, maps_dir = (Path(p) for p in args.evaluate)
    for folder in (gt_dir, maps_dir):
        if not folder.is_dir():
            raise ParameterError("not a folder", path=folder)
    pairs = [(m, gt_dir / m.name) for m in sorted(maps_dir.iterdir()) if (gt_dir / m.name).is_file()]
    if not pairs:
        raise ParameterError(f"no map in {maps_dir} has a ground truth of the same name in {gt_dir}")
    progress = progress_bar(len(pairs), "evaluate")
    rows, benchmark = [], []
    for index, (map_path, gt_path) in enumerate(pairs, start=1):
        the_map = load(map_path, args)
        segmentation = segment_checked(the_map, method=method, preset=preset, params=params)
        truth = gt_labels_from_separator_image(gt_path)
        score = score_segmentation(segmentation.labels, truth)
        rows.append((map_path.stem, segmentation.n_regions, score.precision, score.recall, score.f1))
        benchmark.append(BenchmarkMap(map_path.stem, the_map.free, {gt_dir.name: truth}))
        progress(index, text=map_path.name)
    # A preset chosen on data is also scored the honest way: chosen (or trained) without the map.
    cv = None if params or len(pairs) < 2 else cross_validate_rule(benchmark, method, preset)
    cv_f1 = {} if cv is None else {row["map"]: row["cv_f1"] for row in cv.rows}
    print(f"{'map':<24} {'regions':>7} {'precision':>9} {'recall':>7} {'F1':>6}" + (f" {'CV F1':>6}" if cv_f1 else ""))
    for name, n, p, r, f in rows:
        extra = f" {cv_f1[name]:>6.3f}" if cv_f1 else ""
        print(f"{name:<24} {n:>7} {p:>9.3f} {r:>7.3f} {f:>6.3f}{extra}")
    count = len(rows)
    means = [sum(row[i] for row in rows) / count for i in (2, 3, 4)]
    extra = f" {sum(cv_f1.values()) / len(cv_f1):>6.3f}" if cv_f1 else ""
    print(f"{'mean':<24} {'':>7} {means[0]:>9.3f} {means[1]:>7.3f} {means[2]:>6.3f}{extra}")
    if cv_f1:
        print(
            f"F1: the preset as shipped (chosen on maoris_segmentation); CV F1: its rule "
            f"({data_chosen_rule(method, preset)}) chosen, or trained, without the map scored, on these maps"
        )
    elif not params and data_chosen_rule(method, preset) is None:
        print(f"preset {preset!r} of {method} was not chosen on data: no cross-validated column is needed")
    return 0
