"""``ursim match-batch`` refuses, before any pair runs, what every pair (or the summary) would fail on:
bad pair names, bad matching or map options, a malformed scheduler address."""

from __future__ import annotations

import json

import cv2
import pytest
from cli_helpers import building

from ursim_core.cli import main
from ursim_core.cli.match_batch import _encoded, _summary_csv, read_manifest
from ursim_core.errors import FormatError


def _manifest(folder, names, *, suffix=".json"):
    path = folder / f"pairs{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps([{"sketch": "s.png", "metric": "m.png", "name": name} for name in names]))
    else:
        path.write_text("sketch,metric,name\n" + "".join(f"s.png,m.png,{name}\n" for name in names))
    return path


@pytest.mark.parametrize(
    ("names", "problem"),
    [
        (["a\u0000b"], "control character"),
        (["a\nb"], "control character"),
        (["a\udc80b"], "lone surrogates"),
        (["a/b"], "path separator"),
        (["a\\b"], "path separator"),
        ([".."], "starts with '.'"),
        ([".hidden"], "starts with '.'"),
        (["summary.csv"], "name of the summary"),
        (["Summary.CSV"], "name of the summary"),
        (["x", "x"], "taken by pair 1"),
        (["A", "a"], "taken by pair 1"),
        (["n" * 300], "too long"),
        ([["a"]], "'name' must be a text"),
    ],
)
def test_bad_names_are_refused_naming_the_manifest_and_the_pair(tmp_path, names, problem):
    path = _manifest(tmp_path, names)
    with pytest.raises(FormatError, match=problem) as caught:
        read_manifest(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and f"pair {len(names)}" in message and "\n" not in message


def test_a_csv_name_of_the_summary_is_refused_before_any_pair_runs(tmp_path, capsys):
    path = _manifest(tmp_path, ["summary.csv"], suffix=".csv")
    assert main(["match-batch", str(path), "-o", str(tmp_path / "out"), "--workers", "1"]) == 1
    assert "name of the summary" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_names_as_given_and_numbered_still_work(tmp_path):
    path = _manifest(tmp_path, ["room 1", "Ünïcode", 7, ""])
    assert [pair["name"] for pair in read_manifest(path)] == ["room 1", "Ünïcode", "7", "004-s"]


def test_a_path_with_a_nul_character_is_refused(tmp_path):
    (tmp_path / "pairs.json").write_text(json.dumps([{"sketch": "s\u0000.png", "metric": "m.png"}]))
    with pytest.raises(FormatError, match="pair 1: 'sketch' contains a NUL"):
        read_manifest(tmp_path / "pairs.json")


def test_the_summary_keeps_the_bytes_of_undecodable_file_names():
    # A JSON manifest may name a file whose name is not UTF-8 (as os.fsdecode keeps it).
    text = _summary_csv([{"name": "a", "sketch": "s\udc80.png", "metric": "m.png", "status": "ok"}])
    assert b"s\x80.png" in _encoded(text)
    assert b"\\ud800" in _encoded("\ud800")


@pytest.mark.parametrize(
    ("options", "problem"),
    [
        (["--m", "abc"], "--m expects"),
        (["--set", "nope=1"], "unknown matching option 'nope'"),
        (["--set", "vote_orientations=bogus"], "vote_orientations"),
        (["--threshold", "999"], "--threshold must be a number in 0..255, got 999"),
        (["--max-pixels", "0"], "--max-pixels must be a positive integer, got 0"),
        (["--sketch-preset", "bogus"], "--sketch-preset: unknown preset 'bogus'"),
        (["--metric-preset", "bogus"], "--metric-preset: unknown preset 'bogus'"),
        (["--param", "nope=3"], "nope"),
        (["--scheduler", "not a url"], "'not a url' is not a Dask scheduler address"),
        (["--scheduler", "http://x:y"], "'http://x:y' is not a Dask scheduler address"),
    ],
)
def test_bad_options_fail_before_any_pair_runs(tmp_path, capsys, options, problem):
    if "--scheduler" in options:
        pytest.importorskip("distributed")
    cv2.imwrite(str(tmp_path / "m.png"), building())
    cv2.imwrite(str(tmp_path / "s.png"), building(1.3))
    path = _manifest(tmp_path, ["a", "b"], suffix=".csv")
    out = tmp_path / "out"
    assert main(["match-batch", str(path), "-o", str(out), "--workers", "1", *options]) == 1
    err = capsys.readouterr().err
    assert problem in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    # No pair ran: no pair folder, no summary.
    assert not out.exists() or not any(child.name in ("a", "b", "summary.csv") for child in out.iterdir())
