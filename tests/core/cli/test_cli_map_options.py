"""``--threshold`` and ``--max-pixels`` follow the map loader's rules in every command that takes them
(ursim_core.cli.common.check_map_options): refused before any work, in one line naming the option."""

from __future__ import annotations

import os

import pytest
from cli_helpers import building_pair, navigation_maps, two_rooms

from ursim_core.cli import main

BAD_OPTIONS = [
    (["--threshold", "300"], "--threshold must be a number in 0..255, got 300"),
    (["--threshold", "-1"], "--threshold must be a number in 0..255, got -1"),
    (["--max-pixels", "0"], "--max-pixels must be a positive integer, got 0"),
]


def _argv(command, folder):
    """A command line of ``command`` that would write into ``folder / 'out'`` (or ``out.json``)."""
    if command == "match":
        sketch, metric = building_pair(folder)
        return ["match", str(sketch), str(metric), "-o", str(folder / "out")]
    if command == "segment":
        # Two maps: the option is refused once, not once per map.
        first, second = two_rooms(folder / "a.png"), two_rooms(folder / "b.png")
        return ["segment", str(first), str(second), "-o", str(folder / "out")]
    sketch, _, metric_yaml = navigation_maps(folder)
    if command == "goal":
        return ["goal", str(sketch), str(metric_yaml), "--at", "25,30", "-o", str(folder / "out.json")]
    points = folder / "route.txt"
    points.write_text("25,20\n25,180\n")
    return ["route", str(sketch), str(metric_yaml), "--points", str(points), "-o", str(folder / "out.json")]


@pytest.mark.parametrize("command", ["match", "segment", "goal", "route"])
@pytest.mark.parametrize(("options", "message"), BAD_OPTIONS)
def test_a_bad_map_option_is_refused_in_one_line_naming_it(tmp_path, capsys, command, options, message):
    argv = _argv(command, tmp_path)
    before = sorted(os.listdir(tmp_path))
    assert main([*argv, *options]) == 1
    err = capsys.readouterr().err
    assert err == f"error: {message}\n"
    assert sorted(os.listdir(tmp_path)) == before  # no output, no staging folder
