"""The exact text of a correspondence JSON file: json.dumps(indent=2), short number lists on one line.

:func:`cliques_text` writes the ``"cliques"`` member, nearly all of a big file, byte for byte
as ``json.dumps(indent=2, ensure_ascii=False)`` followed by :func:`collapse_number_lists` would,
about ten times faster (a fuzz test compares the two). :func:`escape_lone_surrogates` writes
the strings UTF-8 cannot hold as ``\\uXXXX`` escapes. :func:`finite_json` is ``json.dumps`` for
the exports and goals, refusing NaN and infinity by field.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ursim_core.correspondences.schema import field_path
from ursim_core.correspondences.values import Clique
from ursim_core.errors import FormatError

__all__ = [
    "EMPTY_CLIQUES",
    "NON_FINITE_CAUSE",
    "cliques_text",
    "collapse_number_lists",
    "escape_lone_surrogates",
    "finite_json",
]

#: Why an exported number can be NaN or infinite (refused when written: JSON and QGIS have none).
NON_FINITE_CAUSE = "a map's origin or resolution too large for its coordinates gives them"

# json.dumps(indent=2) writes the top-level key at two spaces; strings hold no raw newline,
# so this text occurs once, where the cliques go.
EMPTY_CLIQUES = '\n  "cliques": []'
_ITEM = ",\n        "
_encode_string = json.encoder.encode_basestring  # the C encoder json.dumps uses (non-ASCII kept)


def cliques_text(values: Sequence[Clique]) -> str:
    """The ``"cliques"`` member exactly as ``json.dumps(indent=2)`` + number-list collapsing writes it."""
    if not values:
        return EMPTY_CLIQUES
    parts = []
    for clique in values:
        lines = [f'      "id": {int.__repr__(clique.id)}']
        for name in ("sketch_points", "metric_points"):
            points = getattr(clique, name)
            if points:
                body = _ITEM.join(f"[{int.__repr__(row)}, {int.__repr__(col)}]" for row, col in points)
                lines.append(f'      "{name}": [\n        {body}\n      ]')
            else:
                lines.append(f'      "{name}": []')
        for name in ("sketch_regions", "metric_regions"):
            regions = getattr(clique, name)
            lines.append(f'      "{name}": [{", ".join(map(int.__repr__, regions))}]')
        lines.append(f'      "source": {_encode_string(clique.source)}')
        if clique.score is not None:
            lines.append(f'      "score": {_number_text(clique.score)}')
        if clique.note:
            lines.append(f'      "note": {_encode_string(clique.note)}')
        if clique.status is not None:
            lines.append(f'      "status": {_encode_string(clique.status)}')
        for key, value in clique.extra.items():
            dumped = json.dumps(value, indent=2, ensure_ascii=False, allow_nan=False)
            lines.append(f"      {_encode_string(key)}: " + collapse_number_lists(dumped.replace("\n", "\n      ")))
        parts.append("    {\n" + ",\n".join(lines) + "\n    }")
    return '\n  "cliques": [\n' + ",\n".join(parts) + "\n  ]"


def _number_text(value: float) -> str:
    if not math.isfinite(value):
        raise ValueError(f"Out of range float values are not JSON compliant: {value!r}")
    return float.__repr__(value)


_LONE_SURROGATE = re.compile("[\ud800-\udfff]")


def escape_lone_surrogates(text: str) -> str:
    """``text`` with every lone surrogate written as a JSON ``\\uXXXX`` escape.

    Lone surrogates (half of a pair, or a byte of a non-UTF-8 file name as ``os.fsdecode``
    keeps it) have no UTF-8 form; escaped, they read back as the same string. Only valid in
    JSON text, where such characters can occur only inside strings.

    Examples
    --------
    >>> escape_lone_surrogates('"a\\udce9"')
    '"a\\\\udce9"'
    """
    return _LONE_SURROGATE.sub(_escape_surrogate, text)


def _escape_surrogate(match: re.Match) -> str:
    return f"\\u{ord(match.group()):04x}"


# A JSON array holding only numbers, as json.dumps(indent=...) spreads it over
# several lines. Raw newlines never occur inside JSON strings (they are escaped),
# so requiring them keeps this from touching string content.
_NUMBER = r"-?[0-9]+(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?"
_NUMBER_LIST = re.compile(r"\[\n\s*(" + _NUMBER + r"(?:,\n\s*" + _NUMBER + r")*)\n\s*\]")


def collapse_number_lists(text: str) -> str:
    # [row, col] points and region lists on one line each: a file a person can read.
    return _NUMBER_LIST.sub(lambda match: "[" + ", ".join(re.split(r",\n\s*", match.group(1))) + "]", text)


def finite_json(document: Any, path: str | Path, *, indent: int | None = None) -> str:
    """``json.dumps(document, indent=indent)``; NaN or infinity (JSON has none) is a FormatError
    naming ``path`` (the file it is for) and the first field holding one.

    Examples
    --------
    >>> finite_json({"x": [1.5]}, "a.json")
    '{"x": [1.5]}'
    >>> finite_json({"pose": {"x": float("nan")}}, "a.json")
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: a.json: field 'pose.x': cannot be written as JSON: nan is not ...
    """
    try:
        return json.dumps(document, indent=indent, allow_nan=False)
    except ValueError as error:
        found = _non_finite(document)  # json.dumps says only "Out of range float values..."
        if found is None:
            raise FormatError(f"cannot be written as JSON: {error}", path=path) from None
        problem = f"cannot be written as JSON: {found[1]!r} is not a finite number (JSON has none; {NON_FINITE_CAUSE})"
        raise FormatError(problem, path=path, field=field_path(found[0]) or "(the document)") from None


def _non_finite(value: Any, where: tuple = ()) -> tuple[tuple, float] | None:
    """``(location, value)`` of the first float in ``value`` that is NaN or infinite, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where, value
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, (list, tuple)) else ()
    for key, item in items:
        found = _non_finite(item, (*where, key))
        if found is not None:
            return found
    return None
