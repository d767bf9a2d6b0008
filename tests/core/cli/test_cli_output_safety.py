"""What the commands write never replaces what they read, and a run that fails leaves no part of its
outputs (ursim_core.cli.common: refuse_overwriting_inputs, check_output_files, staged_folder)."""

from __future__ import annotations

import hashlib
import os
import time

import cv2
import pytest
from cli_helpers import building, correspondences_file, navigation_maps, two_rooms, ursim

from ursim_core.cli import main
from ursim_core.cli.common import refuse_overwriting_inputs, staged_folder
from ursim_core.errors import SaveRefusedError
from ursim_core.io import atomic


def _digests(folder):
    return {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in folder.iterdir() if path.is_file()}


# ------------------------------------------------------------------------------ outputs onto inputs


def test_an_output_onto_an_input_is_refused_naming_both(tmp_path):
    (tmp_path / "sketch.png").write_bytes(b"png")
    (tmp_path / "hard.png").hardlink_to(tmp_path / "sketch.png")
    (tmp_path / "link.png").symlink_to(tmp_path / "sketch.png")
    inputs = [tmp_path / "sketch.png", None]
    for output in ("sketch.png", "hard.png", "link.png", "./sketch.png", "sub/../sketch.png"):
        with pytest.raises(SaveRefusedError, match="onto the input") as caught:
            refuse_overwriting_inputs([tmp_path / output], inputs)
        assert str(tmp_path / "sketch.png") in str(caught.value)
    with pytest.raises(SaveRefusedError, match="two outputs"):
        refuse_overwriting_inputs([tmp_path / "a.json", tmp_path / "." / "a.json"], inputs)
    refuse_overwriting_inputs([tmp_path / "new.json", None], inputs)


def test_route_refuses_to_write_onto_its_map_or_points(tmp_path, capsys):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    points = tmp_path / "route.txt"
    points.write_text("25,20\n25,180\n")
    before = _digests(tmp_path)
    base = ["route", str(sketch), str(metric_yaml), "--points", str(points)]
    for extra in (["--waypoints", str(metric_yaml)], ["-o", str(points)], ["-o", str(sketch)]):
        assert ursim(base + extra) == 1
        assert "refusing to write an output onto the input" in capsys.readouterr().out
    assert _digests(tmp_path) == before


def test_goal_refuses_to_write_onto_its_maps_or_correspondences(tmp_path, capsys):
    sketch, metric_png, _ = navigation_maps(tmp_path)
    corr = correspondences_file(tmp_path, sketch, metric_png)
    before = _digests(tmp_path)
    base = ["goal", str(sketch), str(metric_png), "--at", "25,30", "--correspondences", str(corr)]
    for output in (sketch, metric_png, corr):
        assert ursim(base + ["-o", str(output)]) == 1
        assert "refusing to write an output onto the input" in capsys.readouterr().out
    assert _digests(tmp_path) == before


def test_convert_refuses_another_format_onto_its_input_or_a_map(tmp_path, capsys):
    sketch, metric_png, _ = navigation_maps(tmp_path)
    corr = correspondences_file(tmp_path, sketch, metric_png)
    before = _digests(tmp_path)
    for argv in (
        ["convert", str(corr), str(corr), "--format", "geojson"],
        ["convert", str(corr), str(sketch), "--format", "labelme"],
    ):
        assert main(argv) == 1
        assert "refusing to" in capsys.readouterr().err
    assert _digests(tmp_path) == before
    assert main(["convert", str(corr), str(corr)]) == 0  # in its own format: rewritten in place


def test_match_refuses_to_write_onto_its_inputs(tmp_path, capsys):
    # `ursim match out/matches.png out/metric.labels.png -o out` would overwrite both inputs.
    out = tmp_path / "out"
    out.mkdir()
    cv2.imwrite(str(out / "matches.png"), building(1.3))
    cv2.imwrite(str(out / "metric.labels.png"), building())
    before = _digests(out)
    assert main(["match", str(out / "matches.png"), str(out / "metric.labels.png"), "-o", str(out)]) == 1
    assert "refusing to write an output onto the input" in capsys.readouterr().err
    assert _digests(out) == before and sorted(os.listdir(tmp_path)) == ["out"]


def test_segment_refuses_to_write_onto_a_map_or_its_model(tmp_path, capsys):
    first = two_rooms(tmp_path / "a" / "x.png")
    second = two_rooms(tmp_path / "out" / "x.labels.png")
    model = tmp_path / "out" / "y.labels.png"
    model.write_text("{}")
    before = _digests(tmp_path / "out")
    assert main(["segment", str(first), str(second), "-o", str(tmp_path / "out")]) == 1
    assert "onto the input" in capsys.readouterr().err
    two_rooms(tmp_path / "a" / "y.png")
    argv = ["segment", str(tmp_path / "a" / "y.png"), "-o", str(tmp_path / "out"), "--method", "learned"]
    assert main([*argv, "--param", f"model={model}"]) == 1
    assert "onto the input" in capsys.readouterr().err
    assert _digests(tmp_path / "out") == before


# ---------------------------------------------------------------------------- all outputs or none


def test_match_with_a_folder_in_the_place_of_its_json_writes_nothing(tmp_path, capsys):
    cv2.imwrite(str(tmp_path / "m.png"), building())
    cv2.imwrite(str(tmp_path / "s.png"), building(1.3))
    out = tmp_path / "p"
    (out / "correspondences.json").mkdir(parents=True)
    assert main(["match", str(tmp_path / "s.png"), str(tmp_path / "m.png"), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{out / 'correspondences.json'}: is a folder" in err
    assert os.listdir(out) == ["correspondences.json"]
    assert not [name for name in os.listdir(tmp_path) if name.endswith(".tmp")]


def test_match_stages_its_json_with_the_images(tmp_path, monkeypatch):
    # The JSON failing last (here: its save raises) must leave none of the images either.
    import ursim_core.cli.match as match_cli

    cv2.imwrite(str(tmp_path / "m.png"), building())
    cv2.imwrite(str(tmp_path / "s.png"), building(1.3))

    def failing(corr, staging, out):
        raise OSError(28, "No space left on device", str(staging / "correspondences.json"))

    monkeypatch.setattr(match_cli, "save_staged_correspondences", failing)
    out = tmp_path / "out"
    argv = ["match", str(tmp_path / "s.png"), str(tmp_path / "m.png"), "-o", str(out)]
    with pytest.raises(OSError) as caught:
        match_cli.match_pair(tmp_path / "s.png", tmp_path / "m.png", out, _options(argv))
    # Named after where the file was to appear, not the hidden staging folder.
    assert caught.value.filename == str(out / "correspondences.json")
    assert sorted(os.listdir(tmp_path)) == ["m.png", "s.png"]


def _options(argv):
    from ursim_core.cli.main import build_parser
    from ursim_core.cli.match_options import options_of

    return options_of(build_parser("match").parse_args(argv))


def test_match_writes_json_whose_paths_lead_to_its_images(tmp_path):
    import json

    cv2.imwrite(str(tmp_path / "m.png"), building())
    cv2.imwrite(str(tmp_path / "s.png"), building(1.3))
    out = tmp_path / "out"
    assert main(["match", str(tmp_path / "s.png"), str(tmp_path / "m.png"), "-o", str(out)]) == 0
    document = json.loads((out / "correspondences.json").read_text())
    sketch = document["maps"]["sketch"]
    assert sketch["path"] == "../s.png" and sketch["segmentation"]["labels"] == "sketch.labels.png"
    assert sorted(os.listdir(tmp_path)) == ["m.png", "out", "s.png"]


def test_segment_with_a_folder_in_the_place_of_an_output_moves_nothing(tmp_path, capsys):
    rooms = two_rooms(tmp_path / "metric.png")
    out = tmp_path / "s"
    (out / "metric.overlay.png").mkdir(parents=True)
    assert main(["segment", str(rooms), "-o", str(out)]) == 1
    assert f"{out / 'metric.overlay.png'}: is a folder" in capsys.readouterr().err
    assert os.listdir(out) == ["metric.overlay.png"]


def test_a_staged_folder_checks_every_destination_before_moving_any(tmp_path):
    out = tmp_path / "out"
    (out / "b.png").mkdir(parents=True)
    with pytest.raises(SaveRefusedError, match="is a folder"), staged_folder(out) as staging:
        for name in ("a.png", "b.png", "c.json"):
            atomic.atomic_write_bytes(staging / name, name.encode())
    assert os.listdir(out) == ["b.png"]
    assert sorted(os.listdir(tmp_path)) == ["out"]


def test_a_staged_folder_names_the_final_path_in_errors(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(OSError) as caught, staged_folder(out) as staging:
        raise OSError(27, "File too large", str(staging / "matches.png"))
    assert caught.value.filename == str(out / "matches.png")


def test_stale_staging_folders_of_dead_runs_are_removed(tmp_path):
    out = tmp_path / "out"
    old = time.time() - atomic.STALE_TEMP_SECONDS - 60
    stale = tmp_path / ".out.ab_cd123.tmp"  # a killed run's
    recent = tmp_path / ".out.zz_cd123.tmp"  # maybe a run still starting
    other = tmp_path / ".other.ab_cd123.tmp"  # another output folder's
    unlike = tmp_path / ".out.notours.tmp"
    for folder in (stale, recent, other, unlike):
        folder.mkdir()
        (folder / "matches.png").write_bytes(b"partial")
    for folder in (stale, other, unlike):
        os.utime(folder, (old, old))
    with staged_folder(out) as staging:
        atomic.atomic_write_bytes(staging / "a.png", b"a")
    assert sorted(os.listdir(tmp_path)) == sorted(["out", recent.name, other.name, unlike.name])


def test_a_live_runs_staging_folder_is_kept(tmp_path):
    pytest.importorskip("fcntl")
    out = tmp_path / "out"
    old = time.time() - atomic.STALE_TEMP_SECONDS - 60
    with staged_folder(out) as first:
        os.utime(first, (old, old))  # a long match: nothing written into it for minutes
        with staged_folder(out) as second:
            atomic.atomic_write_bytes(second / "b.png", b"b")
        assert first.is_dir()
        atomic.atomic_write_bytes(first / "a.png", b"a")
    assert sorted(os.listdir(out)) == ["a.png", "b.png"]


def test_goal_and_route_correspondences_still_work(tmp_path):
    # The checks leave an ordinary run alone.
    sketch, metric_png, metric_yaml = navigation_maps(tmp_path)
    corr = correspondences_file(tmp_path, sketch, metric_png)
    points = tmp_path / "route.txt"
    points.write_text("25,20\n25,180\n")
    argv = ["route", str(sketch), str(metric_yaml), "--points", str(points), "--correspondences", str(corr)]
    assert ursim([*argv, "-o", str(tmp_path / "r.json"), "--waypoints", str(tmp_path / "w.yaml")]) == 0
    assert (tmp_path / "r.json").is_file() and (tmp_path / "w.yaml").is_file()
