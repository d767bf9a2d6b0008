"""``ursim convert``: correspondences between the original annotators' ``.dat`` files and JSON,
and exports to GeoJSON, labelme JSON and QGIS georeferencer ``.points``."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from ursim_core.cli.common import UsageError, refuse_overwriting_inputs
from ursim_core.cli.inputs import correspondence_inputs, map_inputs
from ursim_core.correspondences import load_correspondence_file
from ursim_core.errors import ParameterError

__all__ = ["convert_correspondences"]

HELP = "Convert correspondences between .dat and JSON, or export them (GeoJSON, labelme, QGIS .points)."
EXAMPLES = """examples:
  ursim convert gt_00_model_simple.dat gt_00.json --sketch 00.png --metric model_simple.png
  ursim convert gt_00.json gt_00.dat
  ursim convert out/correspondences.json regions.geojson            # metric side; world metres for a YAML map
  ursim convert out/correspondences.json sketch.labelme.json --side sketch
  ursim convert out/correspondences.json clicks.points               # QGIS georeferencer control points

Exports are chosen by the output name (.geojson, .labelme.json, .points) or --format."""


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("input", metavar="IN", help=".dat or .json")
    parser.add_argument("output", metavar="OUT", help=".json or .dat")
    parser.add_argument("--sketch", help="sketch map (for .dat -> JSON: stored in the JSON, regions assigned)")
    parser.add_argument("--metric", help="metric map (for .dat -> JSON)")
    parser.add_argument(
        "--format", choices=["geojson", "labelme", "qgis-points"], help="export format (default: from OUT's name)"
    )
    parser.add_argument(
        "--side", choices=["sketch", "metric"], default="metric", help="map side of a GeoJSON / labelme export"
    )


def run(args: argparse.Namespace) -> int:
    if (args.sketch is None) != (args.metric is None):
        raise UsageError("give both --sketch and --metric, or neither")
    target = Path(args.output)
    if target.is_dir():
        raise ParameterError("is a folder; give the file to write", path=target)
    if not target.parent.is_dir():
        raise ParameterError(f"no folder {target.parent} to write into", path=target)
    source = Path(args.input)
    export = args.format is not None or _is_export(target)
    if not export:
        # An unknown file type is named before the input is read.
        _kind(source)
        _kind(target)
    corr = load_correspondence_file(source)
    # Converting a file onto itself in its own format rewrites it in the project's layout (it is
    # read before it is written); in another format, or onto a map, it would lose it. The maps
    # and label images the file names, and the images of YAML maps, are inputs too.
    same_format = not export and target.suffix.lower() == source.suffix.lower()
    inputs = [args.sketch, args.metric, None if same_format else source]
    inputs += [*map_inputs(args.sketch), *map_inputs(args.metric), *correspondence_inputs(source, corr)]
    refuse_overwriting_inputs([target], inputs)
    if export:
        from ursim_core.correspondences.exporters import export_file

        kind = export_file(source, target, format=args.format, side=args.side, loaded=corr)
        print(f"wrote {args.output} ({kind})")
        labels = getattr(corr, args.side).labels_path
        if kind != "qgis-points" and (labels is None or not Path(labels).is_file()):
            # Not an error (points are the file's substance), but a user expecting rooms should know.
            shown = "names no label image" if labels is None else f"names the label image {labels}, which is missing"
            print(f"note: {source} {shown} of the {args.side} map: points only, no region polygons", file=sys.stderr)
        return 0
    convert_correspondences(source, target, sketch=args.sketch, metric=args.metric, loaded=corr)
    print(f"wrote {args.output}")
    return 0


def _is_export(target: Path) -> bool:
    name = target.name.lower()
    return name.endswith((".geojson", ".points", ".labelme.json"))


_KINDS = {".dat": "dat", ".json": "json"}


def _kind(path: Path) -> str:
    try:
        return _KINDS[path.suffix.lower()]
    except KeyError:
        raise ParameterError("unknown correspondence file type (expected .dat or .json)", path=path) from None


def convert_correspondences(
    source: Path,
    target: Path,
    *,
    sketch: str | Path | None = None,
    metric: str | Path | None = None,
    tolerance: int = 10,
    loaded=None,
) -> None:
    """Convert ``source`` (.dat or .json) to ``target`` (.json or .dat).

    For ``.dat -> .json``, ``sketch`` and ``metric`` name the two maps: they are recorded in the JSON
    (path, sha256, size) and, when given, both maps are segmented with the 'default' MAORIS preset
    (the one the original annotators clicked on) so the cliques also carry region ids.
    ``loaded``: ``source`` as the caller has loaded it already (else it is loaded here).

    Examples
    --------
    >>> convert_correspondences(Path("a.dat"), Path("a.txt"))
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: a.txt: unknown correspondence file type (expected .dat or .json)
    """
    from ursim_core.correspondences import (
        MapRef,
        assign_regions,
        load_correspondences,
        load_dat,
        save_correspondences,
        save_dat,
    )

    source_kind, target_kind = _kind(source), _kind(target)
    if loaded is not None:
        corr = loaded
    else:
        corr = load_dat(source) if source_kind == "dat" else load_correspondences(source)
    if target_kind == "dat":
        save_dat(corr, target)
        return
    if (sketch is None) != (metric is None):
        raise UsageError("give both --sketch and --metric, or neither")
    if sketch is not None and metric is not None:
        from ursim_core.io.maps import load_map
        from ursim_core.segmentation import segment

        maps = {"sketch": load_map(sketch), "metric": load_map(metric)}
        segs = {side: segment(m, preset="default") for side, m in maps.items()}
        refs = {
            side: MapRef(
                path=Path(m.path).resolve(),
                sha256=m.sha256,
                size=tuple(m.shape),
                segmentation_method=segs[side].method,
                segmentation_params=dict(segs[side].params),
                labels_path=None,
                extra={},
            )
            for side, m in maps.items()
        }
        corr = dataclasses.replace(corr, sketch=refs["sketch"], metric=refs["metric"])
        corr = assign_regions(corr, segs["sketch"].labels, segs["metric"].labels, tolerance=tolerance)
    save_correspondences(corr, target)
