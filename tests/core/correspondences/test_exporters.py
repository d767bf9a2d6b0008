"""Exports of correspondences and regions: GeoJSON, labelme JSON, QGIS georeferencer .points."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences, MapRef, load_correspondences, save_correspondences
from ursim_core.correspondences.exporters import (
    clique_label,
    correspondences_to_geojson,
    correspondences_to_labelme,
    correspondences_to_qgis_points,
    export_correspondences,
    export_format_of,
    region_polygons,
)
from ursim_core.errors import ParameterError
from ursim_core.io.maps import Map, pixel_to_world


def labels_with_hole():
    labels = np.zeros((20, 30), np.int32)
    labels[2:18, 2:14] = 1
    labels[6:10, 6:10] = 0  # a pillar: a hole in region 1
    labels[2:18, 16:28] = 2
    labels[0:2, 16:20] = 2  # still one piece
    return labels


def sample_corr():
    return Correspondences(
        sketch=MapRef(path="sketch.png", size=(20, 30)),
        metric=MapRef(path="metric.yaml", size=(20, 30)),
        cliques=(
            Clique(
                id=1, sketch_points=[(4, 4)], metric_points=[(4, 4)], metric_regions=(1,), extra={"label": "office"}
            ),
            Clique(id=2, sketch_points=[(10, 20), (12, 22)], metric_points=[(10, 20)], metric_regions=(2,)),
            Clique(id=3, sketch_points=[(1, 1)], metric_points=[(15, 25)], status="rejected"),
        ),
    )


def test_labels_survive_a_save_and_load(tmp_path):
    save_correspondences(sample_corr(), tmp_path / "c.json")
    loaded = load_correspondences(tmp_path / "c.json")
    assert [clique_label(c) for c in loaded.cliques] == ["office", None, None]


def test_region_polygons_have_holes_and_enclose_the_region():
    import cv2

    labels = labels_with_hole()
    [rings] = region_polygons(labels, 1)
    assert len(rings) == 2  # outer ring and the pillar
    outer = np.array([[c, r] for r, c in rings[0]], np.int32)
    # Every pixel of the region is inside or on the outer ring.
    for row, col in zip(*np.nonzero(labels == 1)):
        assert cv2.pointPolygonTest(outer, (float(col), float(row)), False) >= 0
    assert region_polygons(labels, 9) == []


def test_geojson_in_pixels_states_the_axis_order():
    document = correspondences_to_geojson(sample_corr(), labels=labels_with_hole())
    assert document["ursim"]["units"] == "pixel"
    regions = [f for f in document["features"] if f["properties"]["kind"] == "region"]
    points = [f for f in document["features"] if f["properties"]["kind"] == "clique_point"]
    assert [f["properties"]["region"] for f in regions] == [1, 2]
    assert regions[0]["properties"]["label"] == "office" and regions[0]["properties"]["cliques"] == [1]
    assert len(regions[0]["geometry"]["coordinates"]) == 2  # exterior + hole
    first = points[0]
    assert first["geometry"]["coordinates"] == [4.5, 4.5] and first["properties"]["label"] == "office"
    assert points[-1]["properties"]["status"] == "rejected"
    json.dumps(document)  # JSON-safe


def test_geojson_in_world_coordinates_when_georeferenced():
    the_map = Map(free=labels_with_hole() > 0, resolution=0.1, origin=(5.0, -3.0, 0.4))
    document = correspondences_to_geojson(sample_corr(), labels=labels_with_hole(), the_map=the_map)
    assert document["ursim"] == {"units": "metre", "axis_order": ["x", "y"], "frame_id": "map"}
    point = next(f for f in document["features"] if f["properties"].get("clique") == 2)
    assert point["geometry"]["coordinates"] == pytest.approx(list(pixel_to_world(the_map, 10, 20)), abs=1e-6)


def test_labelme_points_are_x_y_and_grouped_by_clique():
    document = correspondences_to_labelme(sample_corr(), side="sketch", labels=labels_with_hole())
    assert (document["imageHeight"], document["imageWidth"], document["imagePath"]) == (20, 30, "sketch.png")
    points = [s for s in document["shapes"] if s["shape_type"] == "point"]
    assert [(s["label"], s["group_id"], s["points"]) for s in points[:3]] == [
        ("office", 1, [[4.5, 4.5]]),
        ("clique 2", 2, [[20.5, 10.5]]),
        ("clique 2", 2, [[22.5, 12.5]]),
    ]
    polygons = [s for s in document["shapes"] if s["shape_type"] == "polygon"]
    assert [s["label"] for s in polygons] == ["region 1", "region 2"]  # sketch side: no sketch_regions set


def test_qgis_points_one_per_clique_with_both_sides():
    text = correspondences_to_qgis_points(sample_corr())
    lines = text.splitlines()
    assert lines[0].startswith("#CRS:") and lines[1] == "mapX,mapY,sourceX,sourceY,enable,dX,dY,residual"
    # Clique 2: mean of its two sketch points; clique 3 is rejected.
    assert lines[2:] == ["4.5,-4.5,4.5,-4.5,1,0,0,0", "20.5,-10.5,21.5,-11.5,1,0,0,0"]
    the_map = Map(free=np.ones((20, 30), bool), resolution=0.5, origin=(0.0, 0.0, 0.0))
    world = correspondences_to_qgis_points(sample_corr(), metric_map=the_map).splitlines()[2]
    x, y = pixel_to_world(the_map, 4, 4)
    assert world.startswith(f"{x:g},{y:g},")


def test_export_by_file_name(tmp_path):
    corr = sample_corr()
    assert export_correspondences(corr, tmp_path / "c.geojson", labels=labels_with_hole()) == "geojson"
    assert json.loads((tmp_path / "c.geojson").read_text())["type"] == "FeatureCollection"
    assert export_correspondences(corr, tmp_path / "c.points") == "qgis-points"
    assert export_correspondences(corr, tmp_path / "c.labelme.json", side="sketch") == "labelme"
    assert export_correspondences(corr, tmp_path / "x.json", format="labelme") == "labelme"
    with pytest.raises(ParameterError, match="cannot tell"):
        export_format_of(tmp_path / "c.txt")
    with pytest.raises(ParameterError, match="unknown export format"):
        export_format_of(tmp_path / "c.txt", "kml")
    with pytest.raises(ParameterError, match="side"):
        correspondences_to_geojson(corr, side="both")


def test_export_file_uses_the_referenced_labels_and_yaml_map(tmp_path):
    import cv2

    from ursim_core.correspondences.exporters import export_file
    from ursim_core.io.map_saver import save_map_yaml
    from ursim_core.io.maps import load_map

    labels = labels_with_hole()
    cv2.imwrite(str(tmp_path / "metric.labels.png"), labels.astype(np.uint16))
    save_map_yaml(Map(free=labels > 0), tmp_path / "metric.yaml", resolution=0.1, origin=(1.0, 2.0, 0.0))
    corr = sample_corr()
    corr = Correspondences(
        sketch=corr.sketch,
        metric=MapRef(path=tmp_path / "metric.yaml", size=(20, 30), labels_path=tmp_path / "metric.labels.png"),
        cliques=corr.cliques,
    )
    save_correspondences(corr, tmp_path / "c.json")
    assert export_file(tmp_path / "c.json", tmp_path / "out.geojson") == "geojson"
    document = json.loads((tmp_path / "out.geojson").read_text())
    assert document["ursim"]["units"] == "metre"
    assert sum(f["properties"]["kind"] == "region" for f in document["features"]) == 2
    assert export_file(tmp_path / "c.json", tmp_path / "out.points") == "qgis-points"
    the_map = load_map(tmp_path / "metric.yaml")
    x, y = pixel_to_world(the_map, 4, 4)
    assert (tmp_path / "out.points").read_text().splitlines()[2].startswith(f"{x:g},{y:g},")


def test_every_export_of_one_side_defaults_to_the_metric_map(tmp_path):
    # correspondences_to_labelme defaulted to the sketch while the GeoJSON and the file export
    # defaulted to the metric map: one call gave the other side's points of another.
    from ursim_core.correspondences.exporters import export_correspondences

    corr = sample_corr()
    points = [s["points"] for s in correspondences_to_labelme(corr)["shapes"] if s["shape_type"] == "point"]
    # The three metric points, labelme's (x, y) = (col + 0.5, row + 0.5); the sketch has four.
    assert points == [[[4.5, 4.5]], [[20.5, 10.5]], [[25.5, 15.5]]]
    export_correspondences(corr, tmp_path / "out.labelme.json")
    assert json.loads((tmp_path / "out.labelme.json").read_text()) == correspondences_to_labelme(corr)
