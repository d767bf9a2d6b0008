"""The exact text of a correspondence JSON file: json.dumps(indent=2), short number lists on one line.

:func:`cliques_text` writes the ``"cliques"`` member, nearly all of a big file, byte for byte
as ``json.dumps(indent=2, ensure_ascii=False)`` followed by :func:`collapse_number_lists` would,
about ten times faster (a fuzz test compares the two). :func:`escape_lone_surrogates` writes
the strings UTF-8 cannot hold as ``\\uXXXX`` escapes.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence

from ursim_core.correspondences.values import Clique

__all__ = ["EMPTY_CLIQUES", "cliques_text", "collapse_number_lists", "escape_lone_surrogates"]

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
