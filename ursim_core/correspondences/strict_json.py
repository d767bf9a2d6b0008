"""Strict JSON reading of correspondence files, with the field's path in every refusal.

:func:`parse_json_object` reads through :func:`ursim_core.io.reading.parse_json` (duplicate
keys, ``NaN``, nesting that would crash ``json.loads`` refused, naming the file), keeping numbers
out of range as placeholders; :func:`check_values` then refuses those placeholders and nesting
too deep, naming the field (``extra.long``), in what the schema does not look at.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ursim_core.correspondences.schema import OutOfRange, field_path, json_type
from ursim_core.errors import FormatError
from ursim_core.io.reading import MAX_JSON_DEPTH, parse_json

__all__ = ["MAX_DEPTH", "parse_json_object", "check_values"]


MAX_DEPTH = MAX_JSON_DEPTH
_WHAT = "correspondence file"


def parse_json_object(raw: bytes, path: Path) -> dict:
    """The JSON object in ``raw`` (UTF-8, a byte-order mark allowed), or a
    :class:`~ursim_core.errors.FormatError` naming ``path`` and what is wrong
    (:func:`ursim_core.io.reading.parse_json`, the project's one strict JSON reader).

    Numbers out of range (``1e999``, integers too long for ``int()``) parse to
    :class:`~ursim_core.correspondences.schema.OutOfRange` placeholders, which
    :func:`check_values` or the schema refuse with the field's path.

    Examples
    --------
    >>> parse_json_object(b'{"a": [1, 2.5]}', Path("x.json"))
    {'a': [1, 2.5]}
    >>> parse_json_object(b'{"a": 1, "a": 2}', Path("x.json"))
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: x.json: not JSON for a correspondence file: key 'a' appears twice in one object
    """
    document = parse_json(raw, path, error=FormatError, what=_WHAT, max_depth=None, out_of_range=OutOfRange)
    if not isinstance(document, dict):
        raise FormatError(f"expected a JSON object at the top level, got {json_type(document)}", path=path)
    return document


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
