"""The ``ursim`` entry point (ursim_core.cli.main): one-line errors and exit codes, and what its process loads."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_helpers import run_cli, run_python, two_rooms

from ursim_core.cli import main


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


# `ursim match --reference` on the matrix's files: scores against a ground truth.
def test_match_reference_prints_pair_scores_and_place_accuracy(files, capsys):
    out = files["tmp"] / "m"
    rooms = str(files["rooms"])
    assert main(["match", rooms, rooms, "--m", "0.3", "-o", str(out), "--reference", str(files["dat"])]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "F1 1.000" in line and "place accuracy 1.000" in line and "2 cliques" in line


# Modules the segment path has no use for (numba is left out: it is the kernels' fallback where
# no C compiler builds them). networkx: the regions are written from their table.
NOT_ON_THE_SEGMENT_PATH = (
    "PIL", "tqdm", "scipy", "skimage", "matplotlib", "jsonschema", "multiprocessing", "networkx",
)  # fmt: skip


def test_segment_loads_none_of_the_libraries_it_does_not_need(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    code = (
        "import json, sys; from ursim_core.cli import main; "
        f"code = main(['segment', {str(source)!r}, '--preset', 'default', '-o', {str(tmp_path / 'out')!r}]); "
        f"print(json.dumps([code, sorted(m for m in {NOT_ON_THE_SEGMENT_PATH!r} if m in sys.modules)]))"
    )
    assert run_python(code) == [0, []]


def test_match_writes_and_reads_valid_files_without_importing_jsonschema(tmp_path):
    # The schema's validator is built only to describe a file that the direct checks refuse.
    source = two_rooms(tmp_path / "rooms.png")
    out = tmp_path / "out"
    code = (
        "import json, sys; from ursim_core.cli import main; "
        "from ursim_core.correspondences import load_correspondences; "
        f"code = main(['match', {str(source)!r}, {str(source)!r}, '-o', {str(out)!r}]); "
        f"load_correspondences({str(out / 'correspondences.json')!r}); "
        "print(json.dumps([code, 'jsonschema' in sys.modules]))"
    )
    assert run_python(code) == [0, False]


def test_the_command_line_freezes_the_heap_before_exit_and_a_caller_keeps_collecting(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    args = ["segment", str(source), "--preset", "default", "-o", str(tmp_path / "out")]
    code = (
        "import gc, json, sys; from ursim_core.cli import main; "
        f"sys.argv = ['ursim', *{args!r}]; frozen = {{}}; "
        f"main({args!r}); frozen['argv'] = gc.get_freeze_count(); "
        "main(); frozen['command line'] = gc.get_freeze_count(); print(json.dumps(frozen))"
    )
    frozen = run_python(code)
    assert frozen["argv"] == 0 and frozen["command line"] > 0
    assert (tmp_path / "out" / "rooms.labels.png").is_file()


def test_openblas_threads_are_told_to_sleep_unless_the_user_said_otherwise():
    code = (
        "import json, os; from ursim_core.cli import main; main(['segment', '--preset', 'nope']); "
        "print(json.dumps(os.environ.get('OPENBLAS_THREAD_TIMEOUT')))"
    )
    environment = {key: value for key, value in os.environ.items() if key != "OPENBLAS_THREAD_TIMEOUT"}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environment)
    assert result.stdout.strip().splitlines()[-1] == '"4"'
    assert run_python(code, OPENBLAS_THREAD_TIMEOUT="12") == "12"


def test_a_reader_that_leaves_early_ends_the_command_quietly(files):
    # `ursim match ... | head -1`: the outputs are written, the command ends as a pipe's writer
    # does when its reader leaves (141), without a traceback or an error line.
    out = files["tmp"] / "piped"
    process = subprocess.Popen(
        [sys.executable, "-m", "ursim_core.cli", "match", str(files["rooms"]), str(files["rooms"]), "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    process.stdout.close()  # before the child prints anything: it takes a while to start
    stderr = process.stderr.read().decode()
    assert process.wait() == 141, stderr
    assert stderr == ""
    assert (out / "correspondences.json").is_file() and (out / "matches.png").is_file()


def test_a_broken_pipe_that_is_not_the_output_is_an_error(monkeypatch, files, capsys):
    # A pipe or socket the command itself writes to (a scheduler's, say) is reported as any
    # other file-system error.
    from ursim_core.cli import segment as segment_cli

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe", "tcp://scheduler")

    monkeypatch.setattr(segment_cli, "run", broken)
    assert main(["segment", str(files["rooms"]), "-o", str(files["tmp"] / "o")]) == 1
    assert capsys.readouterr().err == "error: tcp://scheduler: Broken pipe\n"
