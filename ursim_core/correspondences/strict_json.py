"""Strict JSON reading for URSIM's files: what :func:`json.loads` lets through, refused by name.

``json.loads`` keeps the last of two equal keys, accepts ``NaN`` and ``Infinity``, turns
``1e999`` into infinity and raises a bare ``ValueError`` for an integer of thousands of digits.
A hand-edited file would then load with data silently lost or load and fail to save.
:func:`parse_json_object` refuses each with a :class:`~ursim_core.errors.FormatError` naming the
file; :func:`check_values` refuses numbers out of range and nesting too deep for the steps after
parsing, with the field's path.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from ursim_core.correspondences.schema import OutOfRange, field_path, json_type
from ursim_core.errors import FormatError

__all__ = ["MAX_DEPTH", "parse_json_object", "check_values"]


# Deeper than any file URSIM writes (6 levels) by far, shallow enough for every recursive
# step after parsing (schema, encoder) to stay far from Python's recursion limit.
MAX_DEPTH = 64
# 4300 is Python's own limit for int(str); anything this long is garbage for URSIM anyway.
_MAX_INT_DIGITS = 4000


def parse_json_object(raw: bytes, path: Path) -> dict:
    """The JSON object in ``raw`` (UTF-8, a byte-order mark allowed), or a
    :class:`~ursim_core.errors.FormatError` naming ``path`` and what is wrong.

    Numbers out of range (``1e999``, integers of more than 4000 digits) parse to
    :class:`~ursim_core.correspondences.schema.OutOfRange` placeholders, which
    :func:`check_values` or the schema refuse with the field's path.

    Examples
    --------
    >>> parse_json_object(b'{"a": [1, 2.5]}', Path("x.json"))
    {'a': [1, 2.5]}
    >>> parse_json_object(b'{"a": 1, "a": 2}', Path("x.json"))
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: x.json: not valid JSON for URSIM: key 'a' appears twice in one object
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise FormatError(f"not UTF-8 text (byte {error.start}): not a JSON file", path=path) from None
    hooks = {"object_pairs_hook": _reject_duplicate_keys, "parse_constant": _reject_constant}
    try:
        try:
            document = json.loads(text, parse_float=_parse_float, **hooks)
        except ValueError as error:
            if isinstance(error, json.JSONDecodeError) or "digits" not in str(error):
                raise
            # An integer too long for int(): parse again, keeping it as a value with a place.
            document = json.loads(text, parse_float=_parse_float, parse_int=_parse_int, **hooks)
    except json.JSONDecodeError as error:
        raise FormatError(
            f"not valid JSON: {error.msg} at line {error.lineno}, column {error.colno}", path=path
        ) from None
    except _InvalidJsonValue as error:
        raise FormatError(f"not valid JSON for URSIM: {error}", path=path) from None
    except RecursionError:
        raise FormatError(
            f"nested deeper than {MAX_DEPTH} levels (arrays or objects inside each other)", path=path
        ) from None
    if not isinstance(document, dict):
        raise FormatError(f"expected a JSON object at the top level, got {json_type(document)}", path=path)
    return document


def _parse_float(text: str):
    value = float(text)
    return value if math.isfinite(value) else OutOfRange(text)


def _parse_int(text: str):
    return OutOfRange(text) if len(text) > _MAX_INT_DIGITS else int(text)


def check_values(document: dict, path: Path, *, known_clique_keys: frozenset = frozenset()) -> None:
    """Refuse what the schema does not look at: too deep, or numbers out of range.

    Walks everything but the ``known_clique_keys`` of the cliques (the schema checks those),
    with an explicit stack, so depth costs no recursion.
    """
    stack: list[tuple[Any, tuple, int]] = []
    for key, value in document.items():
        if key != "cliques" or type(value) is not list:
            stack.append((value, (key,), 1))
            continue
        for index, clique in enumerate(value):
            if type(clique) is not dict:
                stack.append((clique, ("cliques", index), 2))
                continue
            for name in clique.keys() - known_clique_keys:
                stack.append((clique[name], ("cliques", index, name), 3))
    while stack:
        value, where, depth = stack.pop()
        if type(value) is OutOfRange:
            raise FormatError(value.problem(), path=path, field=field_path(where))
        if isinstance(value, (dict, list)):
            if depth >= MAX_DEPTH:
                raise FormatError(
                    f"nested deeper than {MAX_DEPTH} levels (arrays or objects inside each other)",
                    path=path,
                    field=field_path(where),
                )
            items = value.items() if isinstance(value, dict) else enumerate(value)
            stack.extend((item, (*where, key), depth + 1) for key, item in items)


class _InvalidJsonValue(ValueError):
    pass


def _reject_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict:
    # json.loads silently keeps the last of two equal keys; a hand-edited file
    # would lose data without notice.
    result = dict(pairs)
    if len(result) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                shown = repr(key) if len(key) <= 60 else repr(key[:57]) + "..."
                raise _InvalidJsonValue(f"key {shown} appears twice in one object")
            seen.add(key)
    return result


def _reject_constant(name: str) -> Any:
    raise _InvalidJsonValue(f"{name} is not a JSON number")
