"""Inputs named on the command line: two maps opened, segmented and matched; --correspondences opens a document."""

from __future__ import annotations

import pytest

from ursim_gui.app import parse_args
from ursim_gui.window.main_window import MainWindow


def test_command_line_maps_are_opened_segmented_and_matched(empty_window, map_files):
    args = parse_args([str(map_files["sketch"]), str(map_files["metric"])])
    assert empty_window.open_inputs(*args.maps, wait=True)
    session = empty_window.session
    assert session.segmentation("sketch") is not None and session.segmentation("metric") is not None
    assert session.last_match is not None
    with pytest.raises(SystemExit):
        parse_args(["only_one_map.png"])


def test_command_line_correspondences_option(window, tmp_path, qtbot):
    window.session.link([2], [2])
    saved = tmp_path / "cli.json"
    window.session.save(saved)
    fresh = MainWindow(data_dir=tmp_path / "cli-data")
    qtbot.addWidget(fresh)
    args = parse_args(["--correspondences", str(saved)])
    assert fresh.open_inputs(correspondences=args.correspondences)
    assert fresh.session.path == saved and fresh.session.correspondences.cliques[0].sketch_regions == (2,)
