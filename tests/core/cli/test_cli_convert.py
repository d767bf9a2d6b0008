"""``ursim convert`` (ursim_core.cli.convert): .dat <-> JSON and the exports, end to end."""

from __future__ import annotations

import json

import pytest
from cli_helpers import building_pair

from ursim_core.cli import main
from ursim_core.correspondences import load_correspondences, load_dat


@pytest.fixture()
def pair(tmp_path):
    return building_pair(tmp_path)


def test_convert_exports_by_name_and_by_format(tmp_path, capsys):
    from ursim_core.synth import make_pair, save_example

    plan, sketch = make_pair(seed=1)
    save_example(plan, sketch, tmp_path, now="2026-12-01T00:00:00Z")
    source = tmp_path / "ground_truth.json"
    assert main(["convert", str(source), str(tmp_path / "regions.geojson")]) == 0
    geojson = json.loads((tmp_path / "regions.geojson").read_text())
    assert geojson["type"] == "FeatureCollection" and geojson["features"]
    assert main(["convert", str(source), str(tmp_path / "s.labelme.json"), "--side", "sketch"]) == 0
    assert json.loads((tmp_path / "s.labelme.json").read_text())["shapes"]
    assert main(["convert", str(source), str(tmp_path / "gcp.points")]) == 0
    assert (tmp_path / "gcp.points").read_text().splitlines()[1].startswith("mapX,mapY,sourceX,sourceY")
    assert main(["convert", str(source), str(tmp_path / "plain.txt"), "--format", "geojson"]) == 0
    assert "(geojson)" in capsys.readouterr().out
    assert main(["convert", str(source), str(tmp_path / "again.dat")]) == 0  # the two formats still convert


def test_convert_round_trip(tmp_path, pair):
    dat = tmp_path / "gt.dat"
    dat.write_text(
        "# sketch.png metric.png\n# 0match set\n# map1\n30 60\n# map2\n25 50\n\n# 1match set\n# map1\n# map2\n"
    )
    json_path, back = tmp_path / "gt.json", tmp_path / "back.dat"
    assert main(["convert", str(dat), str(json_path), "--sketch", str(pair[0]), "--metric", str(pair[1])]) == 0
    corr = load_correspondences(json_path)
    assert corr.cliques[0].sketch_points == ((30, 60),) and corr.cliques[0].sketch_regions
    assert main(["convert", str(json_path), str(back)]) == 0
    assert [c.sketch_points for c in load_dat(back).cliques] == [c.sketch_points for c in load_dat(dat).cliques]


def test_convert_bad_input(tmp_path, capsys):
    (tmp_path / "bad.json").write_text("{not json")
    assert main(["convert", str(tmp_path / "bad.json"), str(tmp_path / "x.dat")]) == 1
    assert "bad.json" in capsys.readouterr().err
    assert main(["convert", str(tmp_path / "bad.json"), str(tmp_path / "x.txt")]) == 1


def test_an_export_without_the_label_image_says_it_has_points_only(tmp_path, pair, capsys):
    # The GeoJSON held points and no region, silently: a user expecting the rooms was not told why.
    sketch, metric = pair
    assert main(["match", str(sketch), str(metric), "-o", str(tmp_path / "out")]) == 0
    source = tmp_path / "out" / "correspondences.json"
    capsys.readouterr()
    assert main(["convert", str(source), str(tmp_path / "with.geojson")]) == 0
    assert "note:" not in capsys.readouterr().err
    with_kinds = {f["geometry"]["type"] for f in json.loads((tmp_path / "with.geojson").read_text())["features"]}
    (tmp_path / "out" / "metric.labels.png").unlink()
    assert main(["convert", str(source), str(tmp_path / "without.geojson")]) == 0
    err = capsys.readouterr().err
    assert "which is missing" in err and "points only, no region polygons" in err and str(source) in err
    kinds = {f["geometry"]["type"] for f in json.loads((tmp_path / "without.geojson").read_text())["features"]}
    assert kinds < with_kinds and not kinds & {"Polygon", "MultiPolygon"}
