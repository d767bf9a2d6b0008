"""``ursim route`` (ursim_core.cli.route): a polyline on the sketch as nav2 waypoints, registered by add_parser."""

from __future__ import annotations

import json
import math

import pytest
import yaml
from cli_helpers import correspondences_file, navigation_maps, ursim

from ursim_core.cli import route as route_cli
from ursim_core.errors import FormatError
from ursim_core.navigation import load_waypoints_yaml


@pytest.fixture
def maps(tmp_path):
    return navigation_maps(tmp_path)


def test_route_writes_waypoints_nav2_can_load(tmp_path, maps, capsys):
    sketch, _, metric_yaml = maps
    corr = correspondences_file(tmp_path, sketch, metric_yaml)
    points = tmp_path / "route.txt"
    points.write_text("# left room to right room\n25,20\n25,180\n")
    wps = tmp_path / "wps.yaml"
    code = ursim(
        ["route", str(sketch), str(metric_yaml), "--points", str(points), "--correspondences", str(corr)]
        + ["--waypoints", str(wps)]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    document = json.loads(captured.out)
    assert len(document["poses"]) == 3 == len(document["ursim"]["metric_regions"])
    loaded = load_waypoints_yaml(wps)
    assert [p[:2] for p in loaded] == [
        pytest.approx([d["pose"]["position"]["x"], d["pose"]["position"]["y"]]) for d in document["poses"]
    ]
    assert all(math.isclose(p[2], 0.0, abs_tol=1e-9) for p in loaded)  # heading east, along +x
    assert "waypoints" in yaml.safe_load(wps.read_text())


def test_route_points_file_forms_and_errors(tmp_path):
    (tmp_path / "a.json").write_text('{"points": [[1, 2], [3.5, 4]]}')
    assert route_cli.read_points(tmp_path / "a.json") == [(1.0, 2.0), (3.5, 4.0)]
    (tmp_path / "b.json").write_text("[[1, 2], [3]]")
    with pytest.raises(FormatError, match=r"points\[1\]"):
        route_cli.read_points(tmp_path / "b.json")
    (tmp_path / "c.txt").write_text("1 2\nthree,4\n")
    with pytest.raises(FormatError, match="line 2"):
        route_cli.read_points(tmp_path / "c.txt")
    (tmp_path / "d.txt").write_text("# nothing\n")
    with pytest.raises(FormatError, match="no point"):
        route_cli.read_points(tmp_path / "d.txt")


def test_route_waypoints_need_a_georeferenced_map(tmp_path, maps, capsys):
    sketch, metric_png, _ = maps
    (tmp_path / "r.txt").write_text("25,20\n25,180\n")
    code = ursim(["route", str(sketch), str(metric_png), "--points", str(tmp_path / "r.txt"), "--waypoints", "x.yaml"])
    assert code == 1 and "georeferenced" in capsys.readouterr().out
