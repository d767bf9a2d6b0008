"""Correspondences and regions out to other tools: GeoJSON, labelme JSON, QGIS georeferencer points.

Coordinates, stated in every file:

- **GeoJSON** positions are ``[x, y]``. For a map with a resolution (a map_server YAML) they are
  world metres in the map frame (:func:`~ursim_core.io.maps.pixel_to_world`); otherwise pixels,
  ``x = col + 0.5``, ``y = row + 0.5`` (pixel centres, y pointing *down*, as image viewers). The
  top-level member ``"ursim"`` says which (``units``, ``axis_order``, ``frame_id``); RFC 7946
  allows such foreign members (it has no ``crs`` member any more).
- **labelme** points are ``[x, y] = [col + 0.5, row + 0.5]``: labelme's image coordinates.
- **QGIS georeferencer** ``.points``: source (the sketch raster) in QGIS's raster coordinates of
  an ungeoreferenced image, ``(col + 0.5, -(row + 0.5))``; destination the metric map's world
  coordinates when it has a resolution, else its raster coordinates the same way.

Region polygons trace the centres of each region's border pixels (OpenCV contours), holes
included; a region in several pieces is a MultiPolygon. A clique's semantic label (room name /
type) is ``clique.extra["label"]`` and is carried into every format.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.correspondences.json_text import NON_FINITE_CAUSE, finite_json
from ursim_core.errors import FormatError, ParameterError
from ursim_core.io.atomic import atomic_write_text

__all__ = [
    "EXPORT_FORMATS",
    "LABEL_KEY",
    "clique_label",
    "with_clique_label",
    "region_polygons",
    "correspondences_to_geojson",
    "correspondences_to_labelme",
    "correspondences_to_qgis_points",
    "export_correspondences",
    "export_format_of",
    "export_file",
]

#: Formats of :func:`export_correspondences`, by name.
EXPORT_FORMATS = ("geojson", "labelme", "qgis-points")
#: Key of a clique's semantic label in its unknown keys (``Clique.extra``).
LABEL_KEY = "label"
_SIDES = ("sketch", "metric")
_LABELME_VERSION = "5.5.0"


def clique_label(clique) -> str | None:
    """The semantic label of a clique (``clique.extra["label"]``: room name / type), or None.

    Kept through the codec's unknown keys until the codec has a ``label`` field of its own.

    >>> from ursim_core.correspondences import Clique
    >>> clique_label(Clique(id=1, extra={"label": "kitchen"}))
    'kitchen'
    """
    value = getattr(clique, "extra", {}).get(LABEL_KEY)
    return value if isinstance(value, str) and value.strip() else None


def with_clique_label(clique, label: str | None):
    """A copy of ``clique`` with its semantic label set (None or blank removes it).

    What the GUI's label editor calls; the label is kept in the JSON under ``"label"``.

    >>> from ursim_core.correspondences import Clique
    >>> clique_label(with_clique_label(Clique(id=1), "  corridor "))
    'corridor'
    >>> with_clique_label(Clique(id=1, extra={"label": "x"}), "").extra
    {}
    """
    import dataclasses

    extra = {key: value for key, value in clique.extra.items() if key != LABEL_KEY}
    if label is not None and label.strip():
        extra[LABEL_KEY] = label.strip()
    return dataclasses.replace(clique, extra=extra)


def region_polygons(labels: np.ndarray, region: int) -> list[list[list[tuple[float, float]]]]:
    """The polygons of one region: a list of polygons, each ``[outer ring, hole, ...]``.

    Rings are closed lists of ``(row, col)`` pixel centres in OpenCV's tracing order (no
    winding order is promised).

    Examples
    --------
    >>> labels = np.zeros((5, 6), np.int32); labels[1:4, 1:5] = 3
    >>> region_polygons(labels, 3)
    [[[(1.0, 1.0), (3.0, 1.0), (3.0, 4.0), (1.0, 4.0), (1.0, 1.0)]]]
    """
    import cv2

    mask = (np.asarray(labels) == region).astype(np.uint8)
    if not mask.any():
        return []
    contours, hierarchy = cv2.findContours(np.pad(mask, 1), cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    if hierarchy is None:
        return []
    hierarchy = hierarchy[0]

    def ring(contour) -> list[tuple[float, float]]:
        points = [(float(y - 1), float(x - 1)) for x, y in contour.reshape(-1, 2)]
        return points + points[:1]

    polygons = []
    for index, contour in enumerate(contours):
        if hierarchy[index][3] != -1:
            continue  # a hole, added to its outer ring below
        rings = [ring(contour)]
        child = hierarchy[index][2]
        while child != -1:
            rings.append(ring(contours[child]))
            child = hierarchy[child][0]
        polygons.append(rings)
    return polygons


def _coordinate_system(the_map) -> tuple[dict[str, Any], Any]:
    """The ``ursim`` member describing the coordinates, and a (rows, cols) -> [[x, y]] function."""
    georeferenced = the_map is not None and getattr(the_map, "resolution", None) is not None
    if georeferenced:
        from ursim_core.io.maps import pixel_to_world

        def convert(rows, cols):
            # An overflowing georeference is refused by name when written (finite_json), not warned of.
            with np.errstate(over="ignore", invalid="ignore"):
                xs, ys = pixel_to_world(the_map, np.asarray(rows, float), np.asarray(cols, float))
            return [[round(float(x), 6), round(float(y), 6)] for x, y in zip(np.atleast_1d(xs), np.atleast_1d(ys))]

        system = {"units": "metre", "axis_order": ["x", "y"], "frame_id": "map"}
    else:

        def convert(rows, cols):
            return [[float(c) + 0.5, float(r) + 0.5] for r, c in zip(rows, cols)]

        system = {
            "units": "pixel",
            "axis_order": ["x = col + 0.5", "y = row + 0.5 (down)"],
            "frame_id": None,
        }
    return system, convert


def _clique_regions(corr, side: str) -> dict[int, list]:
    regions: dict[int, list] = {}
    for clique in corr.cliques:
        for region in getattr(clique, f"{side}_regions"):
            regions.setdefault(int(region), []).append(clique)
    return regions


def _check_side(side: str) -> None:
    if side not in _SIDES:
        raise ParameterError(f"side must be 'sketch' or 'metric', got {side!r}", field="side")


def correspondences_to_geojson(corr, *, side: str = "metric", labels=None, the_map=None) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of one side: region polygons and clique points.

    Parameters
    ----------
    corr : Correspondences
    side : {"sketch", "metric"}, keyword-only
    labels : ndarray, keyword-only
        The label image of that side; without it only the points are exported.
    the_map : Map, keyword-only
        That side's map; with a resolution the coordinates are world metres.

    Examples
    --------
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> corr = Correspondences(cliques=(Clique(id=1, metric_points=[(2, 3)], extra={"label": "hall"}),))
    >>> feature = correspondences_to_geojson(corr)["features"][0]
    >>> feature["geometry"], feature["properties"]["label"]
    ({'type': 'Point', 'coordinates': [3.5, 2.5]}, 'hall')
    """
    _check_side(side)
    system, convert = _coordinate_system(the_map)
    features = []
    if labels is not None:
        in_cliques = _clique_regions(corr, side)
        for region in (int(r) for r in np.unique(labels) if r != 0):
            polygons = [
                [convert([p[0] for p in ring], [p[1] for p in ring]) for ring in rings]
                for rings in region_polygons(labels, region)
            ]
            cliques = in_cliques.get(region, [])
            geometry = (
                {"type": "Polygon", "coordinates": polygons[0]}
                if len(polygons) == 1
                else {"type": "MultiPolygon", "coordinates": polygons}
            )
            features.append(
                {
                    "type": "Feature",
                    "geometry": geometry,
                    "properties": {
                        "kind": "region",
                        "side": side,
                        "region": region,
                        "cliques": [c.id for c in cliques],
                        "label": next((clique_label(c) for c in cliques if clique_label(c)), None),
                    },
                }
            )
    for clique in corr.cliques:
        points = getattr(clique, f"{side}_points")
        if not points:
            continue
        for index, position in enumerate(convert([p[0] for p in points], [p[1] for p in points])):
            features.append(
                {
                    "type": "Feature",
                    "geometry": {"type": "Point", "coordinates": position},
                    "properties": {
                        "kind": "clique_point",
                        "side": side,
                        "clique": clique.id,
                        "point": index,
                        "pixel": list(points[index]),
                        "label": clique_label(clique),
                        "source": clique.source,
                        "status": clique.effective_status,
                    },
                }
            )
    return {"type": "FeatureCollection", "ursim": system, "features": features}


def correspondences_to_labelme(
    corr, *, side: str = "metric", labels=None, image_path: str | None = None, image_size=None
) -> dict[str, Any]:
    """A labelme annotation of one side (the metric map's by default, as every export): a point
    shape per clique point, a polygon per region.

    Shapes of one clique share its id as ``group_id``; their ``label`` is the clique's semantic
    label, else ``"clique N"``. Region polygons are labelled ``"region N"`` (with the clique's
    label after a colon when the region belongs to a labelled clique).

    Examples
    --------
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> corr = Correspondences(cliques=(Clique(id=2, sketch_points=[(10, 4)]),))
    >>> shape = correspondences_to_labelme(corr, side="sketch", image_size=(20, 30))["shapes"][0]
    >>> shape["label"], shape["points"], shape["group_id"], shape["shape_type"]
    ('clique 2', [[4.5, 10.5]], 2, 'point')
    """
    _check_side(side)
    ref = getattr(corr, side)
    size = tuple(image_size) if image_size is not None else (ref.size or (None, None))
    if labels is not None:
        size = tuple(np.shape(labels))
    shapes = []
    for clique in corr.cliques:
        name = clique_label(clique) or f"clique {clique.id}"
        for row, col in getattr(clique, f"{side}_points"):
            shapes.append(_labelme_shape(name, [[col + 0.5, row + 0.5]], clique.id, "point"))
    if labels is not None:
        in_cliques = _clique_regions(corr, side)
        for region in (int(r) for r in np.unique(labels) if r != 0):
            cliques = in_cliques.get(region, [])
            label = next((clique_label(c) for c in cliques if clique_label(c)), None)
            name = f"region {region}" + (f": {label}" if label else "")
            for rings in region_polygons(labels, region):
                outer = rings[0][:-1]  # labelme polygons are implicitly closed and have no holes
                if len(outer) >= 3:
                    points = [[c + 0.5, r + 0.5] for r, c in outer]
                    shapes.append(_labelme_shape(name, points, cliques[0].id if cliques else None, "polygon"))
    if image_path is None and ref.path is not None:
        image_path = ref.path.name
    return {
        "version": _LABELME_VERSION,
        "flags": {},
        "shapes": shapes,
        "imagePath": image_path,
        "imageData": None,
        "imageHeight": size[0],
        "imageWidth": size[1],
    }


def _labelme_shape(label: str, points, group_id, shape_type: str) -> dict[str, Any]:
    return {
        "label": label,
        "points": points,
        "group_id": group_id,
        "description": "",
        "shape_type": shape_type,
        "flags": {},
        "mask": None,
    }


def correspondences_to_qgis_points(corr, *, metric_map=None, crs_wkt: str = "") -> str:
    """The QGIS georeferencer ``.points`` text: one control point per clique with points on both sides.

    The control point of a clique is the mean of its sketch points (source) and the mean of its
    metric points (destination); rejected cliques are left out.

    Examples
    --------
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(10, 20)], metric_points=[(5, 7)]),))
    >>> print(correspondences_to_qgis_points(corr), end="")
    #CRS:
    mapX,mapY,sourceX,sourceY,enable,dX,dY,residual
    7.5,-5.5,20.5,-10.5,1,0,0,0
    """
    georeferenced = metric_map is not None and getattr(metric_map, "resolution", None) is not None
    lines = [f"#CRS: {crs_wkt}", "mapX,mapY,sourceX,sourceY,enable,dX,dY,residual"]
    for clique in corr.cliques:
        if not clique.sketch_points or not clique.metric_points or clique.effective_status == "rejected":
            continue
        sketch_row, sketch_col = np.mean(np.asarray(clique.sketch_points, float), axis=0)
        metric_row, metric_col = np.mean(np.asarray(clique.metric_points, float), axis=0)
        if georeferenced:
            from ursim_core.io.maps import pixel_to_world

            with np.errstate(over="ignore", invalid="ignore"):  # refused below, by name
                map_x, map_y = pixel_to_world(metric_map, metric_row, metric_col)
        else:
            map_x, map_y = metric_col + 0.5, -(metric_row + 0.5)
        values = [map_x, map_y, sketch_col + 0.5, -(sketch_row + 0.5)]
        for name, value in zip(("mapX", "mapY", "sourceX", "sourceY"), values):
            if not math.isfinite(value):  # "nan" would not read back as a coordinate in QGIS
                problem = f"{name} of clique {clique.id} is not a finite number ({float(value)!r}; {NON_FINITE_CAUSE})"
                raise FormatError(f"cannot be written: {problem}")
        lines.append(",".join(_number(v) for v in values) + ",1,0,0,0")
    return "\n".join(lines) + "\n"


def _number(value: float) -> str:
    text = f"{float(value):.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def export_format_of(path: str | Path, format: str | None = None) -> str:
    """The export format named by ``format`` or by the file name (``.geojson``, ``.points``,
    ``.labelme.json``); :class:`~ursim_core.errors.ParameterError` when neither says.

    Examples
    --------
    >>> export_format_of("rooms.geojson"), export_format_of("pair.points"), export_format_of("a.txt", "labelme")
    ('geojson', 'qgis-points', 'labelme')
    >>> export_format_of("rooms.json")
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: rooms.json: cannot tell the export format from the name (use ...)
    """
    if format is not None:
        if format not in EXPORT_FORMATS:
            raise ParameterError(f"unknown export format '{format}' (known: {', '.join(EXPORT_FORMATS)})")
        return format
    name = Path(path).name.lower()
    if name.endswith(".geojson"):
        return "geojson"
    if name.endswith(".points"):
        return "qgis-points"
    if name.endswith(".labelme.json"):
        return "labelme"
    raise ParameterError(
        "cannot tell the export format from the name (use .geojson, .points or .labelme.json)", path=path
    )


def export_correspondences(
    corr,
    path: str | Path,
    *,
    format: str | None = None,
    side: str = "metric",
    labels=None,
    the_map=None,
    metric_map=None,
) -> str:
    """Write ``corr`` to ``path`` in one of :data:`EXPORT_FORMATS`, atomically; returns the format.

    ``side`` with its ``labels`` and ``the_map`` select what GeoJSON and labelme export (one
    side per file); ``metric_map`` georeferences the QGIS points (which hold both sides). A
    coordinate that is not a finite number is a :class:`~ursim_core.errors.FormatError` naming
    ``path`` and the field, and nothing is written.

    Examples
    --------
    >>> import json, tempfile
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(10, 20)], metric_points=[(5, 7)]),))
    >>> target = Path(tempfile.mkdtemp()) / "pair.geojson"
    >>> export_correspondences(corr, target)  # the format from the name; the metric side
    'geojson'
    >>> json.loads(target.read_text())["features"][0]["geometry"]  # [x, y] = [col + 0.5, row + 0.5]
    {'type': 'Point', 'coordinates': [7.5, 5.5]}
    """
    kind = export_format_of(path, format)
    if kind == "geojson":
        text = finite_json(correspondences_to_geojson(corr, side=side, labels=labels, the_map=the_map), path, indent=1)
    elif kind == "labelme":
        text = finite_json(correspondences_to_labelme(corr, side=side, labels=labels), path, indent=1)
    else:
        try:
            text = correspondences_to_qgis_points(corr, metric_map=metric_map)
        except FormatError as error:
            raise FormatError(error.problem, path=path, field=error.field) from None
    atomic_write_text(Path(path), text if text.endswith("\n") else text + "\n")
    return kind


def export_file(
    source: str | Path,
    target: str | Path,
    *,
    format: str | None = None,
    side: str = "metric",
    loaded=None,
) -> str:
    """Export a correspondence file (.json or .dat) to ``target``; what ``ursim convert`` calls.

    The maps and label images the file references are used when they exist: the label image
    of ``side`` gives the region polygons (GeoJSON, labelme), a map_server YAML map gives world
    coordinates (GeoJSON of that side; the metric side of QGIS points). Returns the format.
    ``loaded``: ``source`` as the caller has loaded it already (else it is loaded here).

    Raises
    ------
    ParameterError
        Unknown format or side. FormatError / MapError / SegmentationError for unreadable
        inputs, naming the file.

    Examples
    --------
    >>> import json, tempfile
    >>> from ursim_core.correspondences import Clique, Correspondences, save_correspondences
    >>> folder = Path(tempfile.mkdtemp())
    >>> hall = Clique(id=1, sketch_points=[(10, 20)], extra={"label": "hall"})
    >>> _ = save_correspondences(Correspondences(cliques=(hall,)), folder / "pair.json")
    >>> export_file(folder / "pair.json", folder / "pair.labelme.json", side="sketch")
    'labelme'
    >>> json.loads((folder / "pair.labelme.json").read_text())["shapes"][0]["points"]  # [x, y]
    [[20.5, 10.5]]
    """
    from ursim_core.correspondences import load_correspondence_file

    _check_side(side)
    kind = export_format_of(target, format)
    source = Path(source)
    corr = loaded if loaded is not None else load_correspondence_file(source)
    _check_not_an_input(corr, source, Path(target))
    ref = getattr(corr, side)
    labels = _read_labels(ref.labels_path, ref.size) if ref.labels_path is not None else None
    the_map, metric_map = _georeferenced_map(ref.path), _georeferenced_map(corr.metric.path)
    return export_correspondences(
        corr, target, format=kind, side=side, labels=labels, the_map=the_map, metric_map=metric_map
    )


def _check_not_an_input(corr, source: Path, target: Path) -> None:
    """An export never replaces the file it exports, nor a map or label image that file names."""
    from ursim_core.correspondences.files import _check_not_a_map, _real
    from ursim_core.errors import SaveRefusedError

    if _real(source) == _real(target):
        raise SaveRefusedError(
            f"refusing to export onto the file exported ({source}): choose another file name", path=target
        )
    _check_not_a_map(corr, target)


def _georeferenced_map(path: Path | None):
    if path is None or path.suffix.lower() not in (".yaml", ".yml") or not path.is_file():
        return None
    from ursim_core.io.maps import load_map

    return load_map(path)


def _read_labels(path: Path, size) -> np.ndarray | None:
    """The label image at ``path`` as the app and the loaders read it (None when there is no
    file), which must be ``size``."""
    from ursim_core.errors import SegmentationError
    from ursim_core.io.maps import DEFAULT_MAX_PIXELS
    from ursim_core.io.unchanged import read_label_array

    path = Path(path)
    if not path.is_file():
        return None
    # A map loaded with a higher limit than the default has label images as large as itself.
    limit = DEFAULT_MAX_PIXELS if size is None else max(DEFAULT_MAX_PIXELS, int(size[0]) * int(size[1]))
    labels = read_label_array(path, max_pixels=limit)
    if size is not None and tuple(labels.shape) != tuple(size):
        raise SegmentationError(
            f"label image is {labels.shape[0]}x{labels.shape[1]} but the map is {size[0]}x{size[1]}", path=path
        )
    return labels
