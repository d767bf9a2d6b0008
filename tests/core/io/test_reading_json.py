"""Guarded JSON and text reading (ursim_core.io.reading: decode_text, parse_json, read_json_file):
nesting, huge numbers, NaN and byte-order marks give one-line errors naming the file."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from ursim_core.errors import FormatError, SegmentationError
from ursim_core.io.reading import MAX_JSON_DEPTH, decode_text, parse_json, read_json_file

PATH = Path("in.json")


def _parse(text):
    return parse_json(text.encode(), PATH, error=FormatError, what="points file")


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested deeper than"),
        ("[" * (MAX_JSON_DEPTH + 1) + "]" * (MAX_JSON_DEPTH + 1), "nested deeper than"),
        ('{"a": ' * 5000 + "1" + "}" * 5000, "nested deeper than"),
        ("[" + "7" * 5000 + "]", "integer of 5000 digits"),
        ("[" + "7" * 400 + "]", "integer of 400 digits"),
        ("[-" + "7" * 400 + "]", "integer of 400 digits"),
        ("[1e999]", "out of range"),
        ("[NaN]", "NaN is not a JSON number"),
        ("[-Infinity]", "-Infinity is not a JSON number"),
        ("[1, 2", "not JSON"),
        # json.loads would keep the second value and lose the first without a word.
        ('{"points": [[1, 2]], "points": []}', "key 'points' appears twice in one object"),
        ('[{"a": {"b": 1, "b": 1}}]', "key 'b' appears twice"),
    ],
)
def test_bad_json_is_one_error_naming_the_file(text, problem):
    with pytest.raises(FormatError, match=problem) as caught:
        _parse(text)
    assert str(caught.value).startswith("in.json: ")
    assert "\n" not in str(caught.value)


def test_good_json_parses_with_or_without_a_byte_order_mark():
    assert _parse("[[1, 2.5], [3, 4]]") == [[1, 2.5], [3, 4]]
    assert _parse('\ufeff{"points": []}') == {"points": []}
    assert parse_json("\ufeff[1]", PATH, error=FormatError, what="x") == [1]
    # Every integer accepted converts to a float (what its reader does next).
    assert float(_parse("[" + "9" * 308 + "]")[0]) > 1e307
    assert _parse("[" * MAX_JSON_DEPTH + "]" * MAX_JSON_DEPTH) is not None


def test_text_drops_a_byte_order_mark_and_names_bad_bytes():
    assert decode_text(b"\xef\xbb\xbfsketch,metric\n", PATH, error=FormatError, what="manifest") == "sketch,metric\n"
    with pytest.raises(FormatError, match=r"in.json: line 2: not UTF-8"):
        decode_text(b"a\n\xff", PATH, error=FormatError, what="manifest")


@pytest.mark.skipif(sys.platform == "win32", reason="named pipes")
def test_a_named_pipe_is_refused_without_opening_it(tmp_path):
    pipe = tmp_path / "model.json"
    os.mkfifo(pipe)
    with pytest.raises(SegmentationError, match="named pipe"):
        read_json_file(pipe, max_bytes=1000, error=SegmentationError, what="merge model file")


def test_files_too_large_or_empty_are_refused(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("[" + "1, " * 1000 + "1]")
    with pytest.raises(FormatError, match="more than the 100 bytes"):
        read_json_file(path, max_bytes=100, error=FormatError, what="points file")
    path.write_text("")
    with pytest.raises(FormatError, match="empty file"):
        read_json_file(path, max_bytes=100, error=FormatError, what="points file")
