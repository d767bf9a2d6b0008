"""The JSON Schema of correspondence files, its compiled validator, and readable schema errors.

The schema ships as ``schemas/correspondences-<version>.schema.json``; :func:`validate` turns
the best-matching violation into one :class:`~ursim_core.errors.FormatError` whose ``field``
names the place (``cliques[2].sketch_points[0]``).
"""

from __future__ import annotations

import functools
import json
import os
import re
from collections.abc import Sequence
from importlib import resources
from typing import Any

from ursim_core.errors import FormatError

__all__ = [
    "FORMAT_NAME",
    "CURRENT_VERSION",
    "correspondences_schema",
    "compiled_validator",
    "validate",
    "json_type",
    "short",
    "OutOfRange",
]

FORMAT_NAME = "ursim-correspondences"
CURRENT_VERSION = 1


@functools.cache
def correspondences_schema(version: int = CURRENT_VERSION) -> dict:
    """The JSON Schema of a correspondence file version, as shipped in the package.

    Examples
    --------
    >>> correspondences_schema()["properties"]["format"]
    {'const': 'ursim-correspondences'}
    """
    resource = resources.files("ursim_core.correspondences").joinpath(
        "schemas", f"correspondences-{version}.schema.json"
    )
    return json.loads(resource.read_text(encoding="utf-8"))


@functools.cache
def compiled_validator(version: int = CURRENT_VERSION):
    """The schema's validator, built once; "integer" means a JSON integer, not ``1.0``.

    JSON Schema counts ``1.0`` as an integer, but a clique id or a point written ``1.0`` is
    a mistake the rest of the code would trip over, so this validator refuses it.
    """
    import jsonschema
    from jsonschema import Draft202012Validator

    def is_integer(checker, instance) -> bool:
        return isinstance(instance, int) and not isinstance(instance, bool)

    def is_number(checker, instance) -> bool:
        return isinstance(instance, (int, float)) and not isinstance(instance, bool)

    type_checker = Draft202012Validator.TYPE_CHECKER.redefine_many({"integer": is_integer, "number": is_number})
    strict = jsonschema.validators.extend(Draft202012Validator, type_checker=type_checker)
    return strict(correspondences_schema(version))


class OutOfRange:
    """A JSON number no Python value can hold exactly: ``1e400`` (no float) or 5000 digits.

    The parser returns these instead of ``inf`` (which could not be written back) or an
    exception without a place, so that the error can name the field.
    """

    __slots__ = ("text",)

    def __init__(self, text: str):
        self.text = text

    def problem(self) -> str:
        if any(char in self.text for char in ".eE"):
            return f"the number {short_text(self.text)} is out of range for a 64-bit float (at most about 1.8e308)"
        return f"an integer of {len(self.text.lstrip('-'))} digits is too large"


def short_text(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


_POINT_SIDES = ("sketch_points", "metric_points")
_REGION_SIDES = ("sketch_regions", "metric_regions")
_SOURCES = frozenset(("manual", "auto"))
_STATUSES = frozenset(("accepted", "rejected", "pending"))


def _clique_is_valid(item: Any) -> bool:
    """The schema's ``clique`` definition, checked directly: the fast path for big files.

    Must accept exactly what the validator accepts (a test compares them on random input);
    anything it refuses is described by the validator itself.
    """
    if type(item) is not dict:
        return False
    clique_id = item.get("id")
    if type(clique_id) is not int or clique_id < 1:
        return False
    for name in _POINT_SIDES:
        points = item.get(name)
        if type(points) is not list:
            return False
        for point in points:
            if type(point) is not list or len(point) != 2:
                return False
            row, col = point
            if type(row) is not int or type(col) is not int or row < 0 or col < 0:
                return False
    for name in _REGION_SIDES:
        if name in item:
            regions = item[name]
            if type(regions) is not list:
                return False
            for region in regions:
                if type(region) is not int or region < 1:
                    return False
    if "source" in item and (type(item["source"]) is not str or item["source"] not in _SOURCES):
        return False
    if "score" in item and item["score"] is not None and type(item["score"]) not in (int, float):
        return False
    if "note" in item and type(item["note"]) is not str:
        return False
    if "status" in item:
        status = item["status"]
        if status is not None and (type(status) is not str or status not in _STATUSES):
            return False
    return True


@functools.cache
def _pattern(*keys: str) -> re.Pattern:
    """The schema's ``pattern`` at ``$defs`` / ``keys``, compiled; matched as jsonschema does (``search``)."""
    node = correspondences_schema()["$defs"]
    for key in keys:
        node = node[key]
    return re.compile(node["pattern"])


def _is_text_or_none(value: Any, *, non_empty: bool = False) -> bool:
    return value is None or (type(value) is str and (len(value) >= 1 or not non_empty))


def _map_is_valid(item: Any) -> bool:
    """The schema's ``map`` definition, checked directly (see :func:`_head_is_valid`)."""
    if type(item) is not dict or "path" not in item or not _is_text_or_none(item["path"], non_empty=True):
        return False
    digest = item.get("sha256")
    if digest is not None and (
        type(digest) is not str or _pattern("map", "properties", "sha256").search(digest) is None
    ):
        return False
    size = item.get("size")
    if size is not None:
        if type(size) is not list or len(size) != 2:
            return False
        if not all(type(side) is int and side >= 1 for side in size):
            return False
    segmentation = item.get("segmentation")
    if segmentation is not None:
        if type(segmentation) is not dict:
            return False
        if "method" in segmentation and not _is_text_or_none(segmentation["method"]):
            return False
        if "params" in segmentation and type(segmentation["params"]) is not dict:
            return False
        if "labels" in segmentation and not _is_text_or_none(segmentation["labels"], non_empty=True):
            return False
    return True


def _head_is_valid(document: Any) -> bool:
    """Everything of the schema but the cliques, checked directly: no jsonschema import.

    Importing jsonschema and building its validator is about a tenth of a whole ``ursim match``
    process, and a valid file (nearly every one) needs neither. May refuse more than the
    validator (a refused document is then checked by the validator itself), never less; a
    test compares them on random input.
    """
    if type(document) is not dict:
        return False
    if document.get("format") != FORMAT_NAME or type(document.get("version")) is not int:
        return False
    if document["version"] != CURRENT_VERSION or type(document.get("cliques")) is not list:
        return False
    if "annotator" in document and type(document["annotator"]) is not str:
        return False
    for name in ("created", "modified"):
        if name in document:
            stamp = document[name]
            if type(stamp) is not str or _pattern("timestamp").search(stamp) is None:
                return False
    maps = document.get("maps")
    if type(maps) is not dict or "sketch" not in maps or "metric" not in maps:
        return False
    return _map_is_valid(maps["sketch"]) and _map_is_valid(maps["metric"])


def validate(document: Any, path: str | os.PathLike | None) -> None:
    """Check ``document`` against the schema; a FormatError describing the best-matching problem.

    The cliques, which are nearly all of a big file, are checked by :func:`_clique_is_valid`
    and everything else by the schema validator; only an invalid document goes through the
    validator whole, to describe its problems exactly.
    """
    if _head_is_valid(document) and all(map(_clique_is_valid, document["cliques"])):
        return
    _validate_slowly(document, path)


def _validate_slowly(document: Any, path: str | os.PathLike | None) -> None:
    from jsonschema.exceptions import best_match

    errors = list(compiled_validator().iter_errors(document))
    if not errors:
        return
    error = best_match(errors)
    field_name, problem = describe_schema_error(error)
    others = len(errors) - 1
    if others:
        problem += f" (and {others} more problem{'s' if others > 1 else ''})"
    raise FormatError(problem, path=path, field=field_name)


def describe_schema_error(error) -> tuple[str | None, str]:
    location = list(error.absolute_path)
    schema = error.schema if isinstance(error.schema, dict) else {}
    title = schema.get("title")
    instance = error.instance
    kind = error.validator
    value = error.validator_value
    if isinstance(instance, OutOfRange):
        return field_path(location), instance.problem()
    if kind == "required":
        missing = next((name for name in value if name not in instance), value[0])
        return field_path([*location, missing]), "required field is missing"
    if kind == "type":
        types = [value] if isinstance(value, str) else list(value)
        expected = title or " or ".join(types)
        got = f"{json_type(instance)} {short(instance)}"
    elif kind == "const":
        expected, got = short(value), short(instance)
    elif kind == "enum":
        expected = "one of " + ", ".join(short(option) for option in value)
        got = short(instance)
    elif kind in ("minItems", "maxItems"):
        if schema.get("minItems") == schema.get("maxItems"):
            count = f"exactly {value} items"
        else:
            count = f"{'at least' if kind == 'minItems' else 'at most'} {value} items"
        expected = f"{title} ({count})" if title else count
        got = f"{len(instance)} item{'' if len(instance) == 1 else 's'} {short(instance)}"
    elif kind == "minimum":
        expected = title or f"a number >= {value}"
        got = short(instance)
    elif kind == "minLength":
        expected = title or "a non-empty string"
        got = short(instance)
    elif kind == "pattern":
        expected = title or f"a string matching {value}"
        got = short(instance)
    else:
        return field_path(location), error.message
    return field_path(location), f"expected {expected}, got {got}"


def field_path(location: Sequence) -> str | None:
    text = ""
    for part in location:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text or None


def json_type(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    if isinstance(value, dict):
        return "object"
    if isinstance(value, OutOfRange):
        return "number"
    return type(value).__name__


def short(value: Any, limit: int = 60) -> str:
    if isinstance(value, OutOfRange):
        return short_text(value.text, limit)
    try:
        text = json.dumps(value, ensure_ascii=False)
    except (TypeError, ValueError, RecursionError):
        text = f"a {json_type(value)}"
    return text if len(text) <= limit else text[: limit - 3] + "..."
