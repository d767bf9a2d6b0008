"""``ursim goal`` with numbers that are not finite (ursim_core.cli.goal): usage errors, and a goal
that would hold NaN (a georeference that overflows) refused by name, never printed or written."""

from __future__ import annotations

import argparse
import json

import pytest
from cli_helpers import correspondences_file, navigation_maps, ursim

from ursim_core.cli.goal import cmd_goal, write_json
from ursim_core.errors import FormatError, ParameterError


@pytest.fixture
def maps(tmp_path):
    return navigation_maps(tmp_path)


@pytest.mark.parametrize(
    "options",
    [
        ["--at", "nan,nan"],
        ["--at", "inf,5"],
        ["--at", "1e400,1"],
        ["--at", "1e300,1"],
        ["--at", "20,30", "--yaw", "inf"],
        ["--at", "20,30", "--yaw", "nan"],
        ["--at", "20,30", "--tolerance", "nan"],
        ["--at", "20,30", "--tolerance", "inf"],
        ["--at", "20,30", "--tolerance", "-1"],
    ],
)
def test_a_number_that_is_not_finite_is_a_usage_error(maps, capsys, options):
    sketch, _, metric_yaml = maps
    with pytest.raises(SystemExit) as exit_info:
        ursim(["goal", str(sketch), str(metric_yaml), *options])
    captured = capsys.readouterr()
    assert exit_info.value.code == 2 and captured.out == ""
    assert f"argument {options[-2]}" in captured.err and "Traceback" not in captured.err


def test_a_finite_yaw_still_gives_a_goal(tmp_path, maps, capsys):
    sketch, _, metric_yaml = maps
    corr = correspondences_file(tmp_path, sketch, metric_yaml)
    code = ursim(
        ["goal", str(sketch), str(metric_yaml), "--at", "20,100", "--correspondences", str(corr), "--yaw", "1e300"]
    )
    document = json.loads(capsys.readouterr().out)
    assert code == 0 and all(abs(v) <= 1 for v in document["pose"]["orientation"].values())


def test_a_namespace_built_in_code_is_checked_too(maps):
    sketch, _, metric_yaml = maps
    args = argparse.Namespace(sketch=str(sketch), metric=str(metric_yaml), at=[(20.0, 30.0)], tolerance=10, yaw=0.0)
    for changes in ({"tolerance": float("nan")}, {"yaw": float("inf")}, {"at": [(float("nan"), 1.0)]}):
        with pytest.raises(ParameterError):
            cmd_goal(argparse.Namespace(**{**vars(args), **changes}))


def _overflowing_yaml(folder, metric_png):
    path = folder / "overflow.yaml"
    path.write_text(f"image: {metric_png.name}\nresolution: 1.0e+306\norigin: [1.7e+308, 1.7e+308, 0.0]\n")
    return path


def test_a_georeference_that_would_give_nan_is_refused_when_the_map_loads(tmp_path, maps, capsys):
    sketch, metric_png, _ = maps
    metric = _overflowing_yaml(tmp_path, metric_png)
    corr = correspondences_file(tmp_path, sketch, metric)
    out = tmp_path / "goal.json"
    code = ursim(["goal", str(sketch), str(metric), "--at", "20,100", "--correspondences", str(corr), "-o", str(out)])
    captured = capsys.readouterr()
    assert code == 1 and not out.exists()
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {metric}: field 'origin': ")
    assert "from the world origin" in lines[0] and "nan" not in captured.out.lower()


def test_write_json_refuses_nan_before_printing(tmp_path, capsys):
    out = tmp_path / "x.json"
    with pytest.raises(FormatError) as raised:
        write_json([{"pose": {"z": 1.0}}, {"pose": {"z": float("inf")}}], str(out))
    assert raised.value.field == "[1].pose.z" and raised.value.path == out
    assert capsys.readouterr().out == "" and not out.exists()
    write_json({"z": 1.5}, str(out))
    assert json.loads(out.read_text()) == {"z": 1.5}
