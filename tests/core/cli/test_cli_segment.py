"""``ursim segment`` (ursim_core.cli.segment): outputs, exit codes, one-line errors, outputs that never mix."""

from __future__ import annotations

import errno
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_helpers import run_cli, two_rooms

from ursim_core.cli import main


def write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def test_segment_writes_labels_overlay_and_regions(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    out = tmp_path / "out"
    assert main(["segment", str(source), "--preset", "default", "-o", str(out)]) == 0
    labels = cv2.imread(str(out / "rooms.labels.png"), cv2.IMREAD_UNCHANGED)
    assert labels.dtype == np.uint16 and labels.shape == (80, 170)
    document = json.loads((out / "rooms.regions.json").read_text())
    ids = sorted(region["id"] for region in document["regions"])
    assert ids == sorted(int(v) for v in np.unique(labels) if v)
    assert len(ids) == 2
    assert document["regions"][0]["neighbours"] == [ids[1]]
    assert document["segmentation"]["params"]["threshold"] == pytest.approx(0.25)
    assert len(document["sha256"]) == 64
    overlay = cv2.imread(str(out / "rooms.overlay.png"))
    assert overlay.shape == (80, 170, 3)


def test_segment_param_override_is_recorded(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    assert main(["segment", str(source), "--param", "doors=55", "-o", str(tmp_path)]) == 0
    document = json.loads((tmp_path / "rooms.regions.json").read_text())
    assert document["segmentation"]["params"]["doors"] == 55


@pytest.mark.parametrize(
    "make, expected",
    [
        (lambda d: d / "missing.png", "missing.png"),
        (lambda d: write(d / "text.png", b"not an image"), "text.png"),
        (lambda d: write(d / "empty.png", b""), "empty.png"),
        (lambda d: cv2.imwrite(str(d / "black.png"), np.zeros((10, 10), np.uint8)) and d / "black.png", "black.png"),
    ],
)
def test_bad_maps_give_one_line_and_exit_1(tmp_path, make, expected):
    path = make(tmp_path)
    result = run_cli("segment", str(path), "-o", str(tmp_path / "out"))
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], result.stderr
    assert "Traceback" not in result.stderr


def test_truncated_png_is_reported(tmp_path):
    good = two_rooms(tmp_path / "good.png").read_bytes()
    (tmp_path / "cut.png").write_bytes(good[: len(good) // 2])
    result = run_cli("segment", str(tmp_path / "cut.png"), "-o", str(tmp_path / "out"))
    assert result.returncode == 1 and "cut.png" in result.stderr and "Traceback" not in result.stderr


def test_pixel_limit_is_reported(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    result = run_cli("segment", str(source), "--max-pixels", "1000", "-o", str(tmp_path / "out"))
    assert result.returncode == 1 and "rooms.png" in result.stderr


def test_bad_yaml_is_reported(tmp_path):
    (tmp_path / "map.yaml").write_text("image: map.pgm\nresolution: -1\norigin: [0, 0, 0]\n")
    result = run_cli("segment", str(tmp_path / "map.yaml"), "-o", str(tmp_path / "out"))
    assert result.returncode == 1 and "map.yaml" in result.stderr and "Traceback" not in result.stderr


def test_unknown_preset_and_bad_param(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    assert run_cli("segment", str(source), "--preset", "nope", "-o", str(tmp_path)).returncode == 1
    result = run_cli("segment", str(source), "--param", "threshold=-3", "-o", str(tmp_path))
    assert result.returncode == 1 and "threshold" in result.stderr


def test_usage_errors_exit_2():
    assert run_cli("segment", "--no-such-option").returncode == 2
    assert run_cli().returncode == 2


def test_help_shows_examples():
    result = run_cli("segment", "--help")
    assert result.returncode == 0 and "examples:" in result.stdout


def test_multi_file_run_keeps_going_after_a_bad_file(tmp_path):
    good = two_rooms(tmp_path / "good.png")
    result = run_cli("segment", str(tmp_path / "missing.png"), str(good), "-o", str(tmp_path / "out"))
    assert result.returncode == 1
    assert (tmp_path / "out" / "good.labels.png").is_file()
    assert "missing.png" in result.stderr


def test_segment_picks_the_watershed_for_a_ros_map_unless_told(tmp_path, capsys):
    source = two_rooms(tmp_path / "rooms.png")
    (tmp_path / "rooms.yaml").write_text(
        "image: rooms.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    cases = [([str(tmp_path / "rooms.yaml")], ("watershed", "robot")), ([str(source)], ("maoris", "sketch"))]
    cases.append(([str(tmp_path / "rooms.yaml"), "--method", "maoris"], ("maoris", "sketch")))
    cases.append(([str(tmp_path / "rooms.yaml"), "--preset", "robot"], ("maoris", "robot")))
    cases.append(([str(source), "--method", "watershed"], ("watershed", "robot")))
    for index, (args, (method, preset)) in enumerate(cases):
        out = tmp_path / f"out{index}"
        assert main(["segment", *args, "-o", str(out)]) == 0
        document = json.loads(next(out.glob("*.regions.json")).read_text())
        assert (document["segmentation"]["method"], document["segmentation"]["preset"]) == (method, preset), args
    assert "ROS occupancy map" in capsys.readouterr().err


def test_two_maps_with_the_same_name_are_numbered(tmp_path, capsys):
    a = two_rooms(tmp_path / "a" / "map.png")
    b = two_rooms(tmp_path / "b" / "map.png")
    out = tmp_path / "out"
    assert main(["segment", str(a), str(b), "--preset", "default", "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        f"{stem}.{kind}" for stem in ("map", "map-2") for kind in ("labels.png", "overlay.png", "regions.json")
    )
    assert "written as map-2.*" in capsys.readouterr().err


def test_a_full_disk_leaves_no_partial_output(tmp_path, monkeypatch, capsys):
    import ursim_core.render.figures as figures

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(args[0]))

    monkeypatch.setattr(figures, "save_png", full)
    rooms = two_rooms(tmp_path / "rooms.png")
    out = tmp_path / "out"
    assert main(["segment", str(rooms), "--preset", "default", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "No space left on device" in err[0]
    # Neither the label image written before the failure nor a temporary folder is left.
    assert not out.exists() or not any(out.iterdir())
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
