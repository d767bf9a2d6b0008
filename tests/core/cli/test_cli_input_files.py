"""Inputs the commands read besides maps: ``route --points``, the ``match-batch`` manifest and the
learned segmenter's ``--param model=FILE`` go through the safe reader: a named pipe never hangs,
nesting and huge numbers are one-line errors naming the file, a byte-order mark is accepted."""

from __future__ import annotations

import os
import sys
import threading

import pytest
from cli_helpers import two_rooms

from ursim_core.cli import main
from ursim_core.cli import route as route_cli
from ursim_core.cli.match_batch import read_manifest
from ursim_core.errors import FormatError

needs_fifo = pytest.mark.skipif(sys.platform == "win32", reason="named pipes")


def _without_hanging(call, pipe, seconds: float = 20.0):
    """``call()``'s result or exception; a failure (not a hung test run) when it blocks on ``pipe``."""
    outcome: dict = {}

    def target():
        try:
            outcome["value"] = call()
        except BaseException as error:
            outcome["error"] = error

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        # Give the reader blocked in open() a writer and an end of file, so the run can go on.
        os.close(os.open(pipe, os.O_WRONLY | os.O_NONBLOCK))
        thread.join(5)
        pytest.fail(f"blocked reading the named pipe {pipe}")
    return outcome


def _bad_json_files(folder):
    deep = folder / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    huge = folder / "bigint.json"
    huge.write_text('{"points": [[1, ' + "7" * 5000 + "]]}")
    overflow = folder / "bigint2.json"
    overflow.write_text("[[1, " + "7" * 400 + "]]")
    return {deep: "nested deeper than", huge: "5000 digits", overflow: "400 digits"}


# ------------------------------------------------------------------------------------ route --points


@needs_fifo
def test_a_points_pipe_is_refused_without_hanging(tmp_path):
    pipe = tmp_path / "fifo.txt"
    os.mkfifo(pipe)
    outcome = _without_hanging(lambda: route_cli.read_points(pipe), pipe)
    assert isinstance(outcome.get("error"), FormatError)
    assert "named pipe" in str(outcome["error"]) and str(pipe) in str(outcome["error"])


def test_points_json_too_deep_or_with_huge_numbers_is_a_format_error(tmp_path):
    for path, problem in _bad_json_files(tmp_path).items():
        with pytest.raises(FormatError, match=problem) as caught:
            route_cli.read_points(path)
        assert str(path) in str(caught.value)


def test_points_files_with_a_byte_order_mark_are_read(tmp_path):
    (tmp_path / "bom.json").write_bytes(b"\xef\xbb\xbf[[209, 492], [205, 623]]")
    (tmp_path / "bom.txt").write_bytes(b"\xef\xbb\xbf209,492\n205 623\n")
    expected = [(209.0, 492.0), (205.0, 623.0)]
    assert route_cli.read_points(tmp_path / "bom.json") == expected
    assert route_cli.read_points(tmp_path / "bom.txt") == expected


def test_points_that_are_not_finite_are_refused_with_the_line(tmp_path):
    (tmp_path / "nan.txt").write_text("1,2\nnan,3\n")
    with pytest.raises(FormatError, match="line 2: ROW and COL must be finite"):
        route_cli.read_points(tmp_path / "nan.txt")
    (tmp_path / "nan.json").write_text("[[1, 2], [NaN, 3]]")
    with pytest.raises(FormatError, match="NaN"):
        route_cli.read_points(tmp_path / "nan.json")


# ---------------------------------------------------------------------------- match-batch manifest


@needs_fifo
def test_a_manifest_pipe_is_refused_without_hanging(tmp_path, capsys):
    pipe = tmp_path / "pairs.csv"
    os.mkfifo(pipe)
    outcome = _without_hanging(lambda: main(["match-batch", str(pipe), "-o", str(tmp_path / "out")]), pipe)
    assert outcome.get("value") == 1
    assert "named pipe" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_json_manifest_too_deep_or_with_huge_numbers_is_a_format_error(tmp_path):
    for path, problem in _bad_json_files(tmp_path).items():
        with pytest.raises(FormatError, match=problem) as caught:
            read_manifest(path)
        assert str(path) in str(caught.value)


def test_a_csv_manifest_with_a_byte_order_mark_is_read(tmp_path):
    # What Excel saves as "CSV UTF-8".
    (tmp_path / "pairs.csv").write_bytes(b"\xef\xbb\xbfsketch,metric,name\ns.png,m.png,a\n")
    [pair] = read_manifest(tmp_path / "pairs.csv")
    assert pair["name"] == "a" and pair["sketch"] == tmp_path / "s.png"


# ------------------------------------------------------------------------ segment --param model=FILE


@needs_fifo
def test_a_model_pipe_is_refused_without_hanging(tmp_path, capsys):
    rooms = two_rooms(tmp_path / "rooms.png")
    pipe = tmp_path / "model.json"
    os.mkfifo(pipe)
    argv = ["segment", str(rooms), "-o", str(tmp_path / "out"), "--method", "learned", "--param", f"model={pipe}"]
    outcome = _without_hanging(lambda: main(argv), pipe)
    assert outcome.get("value") == 1
    err = capsys.readouterr().err
    assert "named pipe" in err and str(pipe) in err and "Traceback" not in err


def test_a_model_too_deep_or_with_huge_numbers_is_one_error_line(tmp_path, capsys):
    rooms = two_rooms(tmp_path / "rooms.png")
    for path, problem in _bad_json_files(tmp_path).items():
        argv = ["segment", str(rooms), "-o", str(tmp_path / "out"), "--method", "learned", "--param", f"model={path}"]
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert problem in err and str(path) in err and len(err.strip().splitlines()) == 1
