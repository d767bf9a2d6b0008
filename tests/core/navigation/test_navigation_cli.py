"""`ursim goal` and `ursim route` (their add_parser functions, registered by the main parser)."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest
import yaml
from PIL import Image

from ursim_core.cli import goal as goal_cli
from ursim_core.cli import route as route_cli
from ursim_core.correspondences import Clique, Correspondences, MapRef, save_correspondences
from ursim_core.errors import FormatError, UrsimError
from ursim_core.io.maps import load_map, world_to_pixel
from ursim_core.io.occupancy_grid import save_map_yaml
from ursim_core.navigation import load_waypoints_yaml


def ursim(argv) -> int:
    """What `ursim` does once the lead registers the two commands: parse, run, one-line errors."""
    parser = argparse.ArgumentParser(prog="ursim")
    commands = parser.add_subparsers(dest="command", required=True)
    goal_cli.add_parser(commands)
    route_cli.add_parser(commands)
    args = parser.parse_args(argv)
    try:
        return args.handler(args)
    except UrsimError as error:
        print(f"error: {error}")
        return 1


def rooms_image(n_rooms=3, width=60, height=50, door=10):
    """White rooms in a row on black, joined by doors, so MAORIS finds n regions."""
    grey = np.zeros((height + 2, n_rooms * (width + 4) + 2), np.uint8)
    for room in range(n_rooms):
        left = 1 + room * (width + 4)
        grey[1 : height + 1, left : left + width] = 255
        if room:
            middle = height // 2
            grey[middle - door // 2 : middle + door // 2, left - 4 : left] = 255
    return grey


@pytest.fixture
def maps(tmp_path):
    sketch = tmp_path / "sketch.png"
    Image.fromarray(rooms_image()).save(sketch)
    metric_png = tmp_path / "metric.png"
    big = rooms_image(width=90, height=70)
    Image.fromarray(big).save(metric_png)
    metric_yaml = tmp_path / "metric.yaml"
    save_map_yaml(load_map(metric_png), metric_yaml, resolution=0.05, origin=(-1.0, 2.0, 0.0))
    return sketch, metric_png, metric_yaml


def correspondences_file(tmp_path, sketch, metric):
    # Rooms matched in order, by clicked points; the middle room carries a label.
    corr = Correspondences(
        sketch=MapRef(path=sketch),
        metric=MapRef(path=metric),
        cliques=(
            Clique(id=1, sketch_points=[(25, 30)], metric_points=[(35, 45)]),
            Clique(id=2, sketch_points=[(25, 95)], metric_points=[(35, 140)], extra={"label": "lab"}),
            Clique(id=3, sketch_points=[(25, 160)], metric_points=[(35, 235)]),
        ),
    )
    save_correspondences(corr, tmp_path / "corr.json")
    return tmp_path / "corr.json"


def test_goal_prints_a_pose_stamped_in_the_map_frame(tmp_path, maps, capsys):
    sketch, _, metric_yaml = maps
    corr = correspondences_file(tmp_path, sketch, metric_yaml)
    code = ursim(["goal", str(sketch), str(metric_yaml), "--at", "20,100", "--correspondences", str(corr)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    document = json.loads(captured.out)
    assert document["header"]["frame_id"] == "map"
    assert document["ursim"]["clique"] == 2 and document["ursim"]["label"] == "lab"
    position = document["pose"]["position"]
    row, col = world_to_pixel(load_map(metric_yaml), position["x"], position["y"])
    assert (round(row), round(col)) == tuple(document["ursim"]["pixel"])
    assert 95 <= col <= 185  # inside the middle metric room


def test_goal_on_an_image_gives_pixels_and_a_note(maps, capsys, tmp_path):
    sketch, metric_png, _ = maps
    out = tmp_path / "goal.json"
    code = ursim(["goal", str(sketch), str(metric_png), "--at", "20,30", "-o", str(out)])
    captured = capsys.readouterr()
    assert code == 0
    assert json.loads(out.read_text()) == json.loads(captured.out)
    assert json.loads(captured.out)["pose"] is None
    assert "no resolution" in captured.err


def test_goal_off_every_region_says_why_and_offers_the_nearest(tmp_path, maps, capsys):
    sketch, _, metric_yaml = maps
    corr = correspondences_file(tmp_path, sketch, metric_yaml)
    code = ursim(["goal", str(sketch), str(metric_yaml), "--at", "200,5", "--correspondences", str(corr)])
    captured = capsys.readouterr()
    assert code == 1
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: sketch point (200, 5): no sketch region")
    assert "nearest matched region" in lines[0]


def test_goal_with_several_points_prints_a_list(tmp_path, maps, capsys):
    sketch, _, metric_yaml = maps
    corr = correspondences_file(tmp_path, sketch, metric_yaml)
    code = ursim(["goal", str(sketch), str(metric_yaml), "--correspondences", str(corr), "--at=20,30", "--at=20,160"])
    documents = json.loads(capsys.readouterr().out)
    assert code == 0 and [d["ursim"]["clique"] for d in documents] == [1, 3]


def test_bad_point_is_a_usage_error(maps, capsys):
    sketch, _, metric_yaml = maps
    with pytest.raises(SystemExit) as exit_info:
        ursim(["goal", str(sketch), str(metric_yaml), "--at", "12"])
    assert exit_info.value.code == 2
    assert "ROW,COL" in capsys.readouterr().err


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
