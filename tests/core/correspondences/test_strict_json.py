"""Strict JSON reading (ursim_core.correspondences.strict_json): what json.loads lets through is refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from ursim_core.correspondences.strict_json import MAX_DEPTH, check_values, parse_json_object
from ursim_core.errors import FormatError

PATH = Path("pairs.json")


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (b'{"a": 1, "a": 2}', "key 'a' appears twice in one object"),
        (b'{"a": NaN}', "NaN is not a JSON number"),
        (b'{"a": -Infinity}', "-Infinity is not a JSON number"),
        (b'{"a": }', r"not JSON: Expecting value \(line 1, column 7\)"),
        (b"[1, 2]", "expected a JSON object at the top level, got array"),
        (b'{"a": "\xff"}', "not UTF-8 text"),
        (b"[" * 100_000 + b"]" * 100_000, "nested deeper than 64 levels"),
    ],
)
def test_what_json_loads_would_accept_or_crash_on_is_refused_naming_the_file(raw, message):
    with pytest.raises(FormatError, match=message) as raised:
        parse_json_object(raw, PATH)
    assert "pairs.json" in str(raised.value)


def test_a_byte_order_mark_is_allowed_and_numbers_out_of_range_are_refused_by_field():
    assert parse_json_object(b'\xef\xbb\xbf{"a": 1}', PATH) == {"a": 1}
    document = parse_json_object(b'{"extra": {"big": 1e999, "long": ' + b"9" * 5000 + b"}}", PATH)
    with pytest.raises(FormatError) as raised:
        check_values(document, PATH)
    assert raised.value.field in ("extra.long", "extra.big")


def test_nesting_is_counted_outside_the_cliques_known_keys_only():
    deep: list = []
    inner = deep
    for _ in range(MAX_DEPTH):
        inner.append([])
        inner = inner[0]
    with pytest.raises(FormatError, match=f"nested deeper than {MAX_DEPTH} levels") as raised:
        check_values({"extra": deep}, PATH)
    assert raised.value.field.startswith("extra")
    # A clique's known keys are the schema's to check; its unknown keys are walked.
    check_values({"cliques": [{"sketch": deep}]}, PATH, known_clique_keys=frozenset({"sketch"}))
    with pytest.raises(FormatError, match="nested deeper"):
        check_values({"cliques": [{"note": deep}]}, PATH, known_clique_keys=frozenset({"sketch"}))
