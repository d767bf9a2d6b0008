"""``ursim goal`` (ursim_core.cli.goal): a sketch point as a goal pose, registered by its add_parser function."""

from __future__ import annotations

import json

import pytest
from cli_helpers import correspondences_file, navigation_maps, ursim

from ursim_core.io.maps import load_map, world_to_pixel


@pytest.fixture
def maps(tmp_path):
    return navigation_maps(tmp_path)


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


def test_goal_without_correspondences_matches_as_ursim_match_does(maps):
    # It segmented the sketch with plain segment() (not in its canonical pose, no resamplings)
    # and ignored two YAMLs' scale: another pipeline than ursim match's, and worse on turned
    # sketches (a KTH sketch turned by 45 degrees: place accuracy 0.80 against 1.00).
    import argparse

    from ursim_core.cli.goal import prepare_navigation
    from ursim_core.matching import match_maps

    sketch, _, metric_yaml = maps
    args = argparse.Namespace(
        sketch=str(sketch),
        metric=str(metric_yaml),
        correspondences=None,
        sketch_preset="default",
        metric_preset="default",
        threshold=250,
        nonzero_free=False,
        max_pixels=64_000_000,
        tolerance=10,
    )
    navigation = prepare_navigation(args)
    assert navigation.sketch_seg.params.get("canonical") is True
    found = match_maps(load_map(sketch), load_map(metric_yaml))
    assert navigation.table.pairs == tuple(found.result.pairs)
