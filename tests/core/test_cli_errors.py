"""The CLI matrix: every bad input gives one line on stderr and exit 1; usage errors exit 2.

Also: outputs of one `ursim segment` never mix (two maps of the same name are numbered), a full
disk leaves no partial output, and `ursim match --reference` scores against a ground truth.
"""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from ursim_core.cli import main


def two_rooms(path: Path, *, door: bool = True) -> Path:
    image = np.zeros((80, 170), np.uint8)
    image[5:75, 5:80] = 255
    image[5:75, 90:165] = 255
    image[35:45, 80:90] = 255 if door else 0
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), image)
    return path


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ursim_core.cli", *args], capture_output=True, text=True)


def _dat(path: Path) -> Path:
    # Room centres of two_rooms, the same on both sides.
    path.write_text(
        "# a.png b.png\n# 0match set\n# map1\n40 40\n# map2\n40 40\n\n# 1match set\n# map1\n40 127\n# map2\n40 127\n\n"
    )
    return path


@pytest.fixture()
def files(tmp_path):
    rooms = two_rooms(tmp_path / "rooms.png")
    closed = two_rooms(tmp_path / "closed.png", door=False)
    white = tmp_path / "white.png"
    cv2.imwrite(str(white), np.full((60, 60), 255, np.uint8))
    black = tmp_path / "black.png"
    cv2.imwrite(str(black), np.zeros((60, 60), np.uint8))
    a_file = tmp_path / "a_file.txt"
    a_file.write_text("not a folder")
    dat = _dat(tmp_path / "gt.dat")
    dataset = tmp_path / "empty_dataset"
    dataset.mkdir()
    return {
        "rooms": rooms,
        "closed": closed,
        "white": white,
        "black": black,
        "file": a_file,
        "dat": dat,
        "dataset": dataset,
        "tmp": tmp_path,
    }


BAD_INPUTS = {
    "segment -o onto a file": (lambda f: ["segment", f["rooms"], "-o", f["file"]], "must be a folder"),
    "segment -o under a file": (lambda f: ["segment", f["rooms"], "-o", f["file"] / "out"], "is a file"),
    "segment all-white map": (lambda f: ["segment", f["white"], "-o", f["tmp"] / "o"], "0 regions"),
    "segment all-black map": (lambda f: ["segment", f["black"], "-o", f["tmp"] / "o"], "no free pixel"),
    "segment two rooms without a door": (
        lambda f: ["segment", f["closed"], "-o", f["tmp"] / "o"],
        "2 separate areas with no opening between them",
    ),
    "match -o onto a file": (lambda f: ["match", f["rooms"], f["rooms"], "-o", f["file"]], "must be a folder"),
    "match --reference of unknown type": (
        lambda f: ["match", f["rooms"], f["rooms"], "-o", f["tmp"] / "m", "--reference", f["file"]],
        "unknown ground-truth file type",
    ),
    "match --reference missing": (
        lambda f: ["match", f["rooms"], f["rooms"], "-o", f["tmp"] / "m", "--reference", f["tmp"] / "no.dat"],
        "no.dat",
    ),
    "match on an all-white sketch": (lambda f: ["match", f["white"], f["rooms"], "-o", f["tmp"] / "m"], "0 regions"),
    "convert to a missing folder": (lambda f: ["convert", f["dat"], f["tmp"] / "nowhere" / "gt.json"], "no folder"),
    "convert onto a folder": (lambda f: ["convert", f["dat"], f["dataset"]], "is a folder"),
    "evaluate -o onto a file": (lambda f: ["evaluate", f["dataset"], "-o", f["file"]], "must be a folder"),
    "evaluate an empty folder": (lambda f: ["evaluate", f["dataset"]], "empty_dataset"),
    "evaluate --augment nonsense": (lambda f: ["evaluate", f["dataset"], "--augment", "sideways"], "augment"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_is_one_line_and_exit_1(files, case):
    make, expected = BAD_INPUTS[case]
    result = run_cli(*map(str, make(files)))
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 1, result.stderr
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], result.stderr
    assert "Traceback" not in result.stderr


USAGE = {
    "segment without MAP": ["segment", "-o", "out"],
    "segment without -o": ["segment", "x.png"],
    "segment --param without =": ["segment", "x.png", "-o", "out", "--param", "threshold"],
    "match without METRIC": ["match", "x.png"],
    "match without -o": ["match", "x.png", "y.png"],
    "convert with only --sketch": ["convert", "a.dat", "a.json", "--sketch", "s.png"],
    "evaluate without DATASET": ["evaluate"],
    "unknown benchmark": ["bench", "nope"],
    "unknown command": ["frobnicate"],
}


@pytest.mark.parametrize("case", sorted(USAGE))
def test_usage_errors_exit_2(case):
    result = run_cli(*USAGE[case])
    assert result.returncode == 2, result.stderr
    assert "usage:" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write anywhere")
def test_unwritable_output_folder_is_one_line(files):
    locked = files["tmp"] / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        result = run_cli("segment", str(files["rooms"]), "-o", str(locked / "out"))
    finally:
        locked.chmod(0o700)
    assert result.returncode == 1 and len(result.stderr.strip().splitlines()) == 1


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


def test_match_reference_prints_pair_scores_and_place_accuracy(files, capsys):
    out = files["tmp"] / "m"
    rooms = str(files["rooms"])
    assert main(["match", rooms, rooms, "--m", "0.3", "-o", str(out), "--reference", str(files["dat"])]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "F1 1.000" in line and "place accuracy 1.000" in line and "2 cliques" in line


def test_first_run_says_the_kernels_are_compiling(tmp_path, monkeypatch, capsys):
    import ursim_core.cli.common as common
    from ursim_core.segmentation.maoris import kernel_cache

    monkeypatch.setattr(common, "_announced", False)
    monkeypatch.setattr(kernel_cache, "kernels_cached", lambda: False)
    rooms = two_rooms(tmp_path / "rooms.png")
    assert main(["segment", str(rooms), str(rooms), "--preset", "default", "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    # Once per process, before the first segmentation.
    assert err.count("Compiling the segmentation kernels (first run only") == 1
