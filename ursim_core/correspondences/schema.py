"""The JSON Schema of correspondence files, its compiled validator, and readable schema errors.

The schema ships as ``schemas/correspondences-<version>.schema.json``; :func:`validate` turns
the best-matching violation into one :class:`~ursim_core.errors.FormatError` whose ``field``
names the place (``cliques[2].sketch_points[0]``).
"""

from __future__ import annotations

import functools
import json
import os
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
    import jsonschema

    return jsonschema.Draft202012Validator(correspondences_schema(version))


def validate(document: Any, path: str | os.PathLike | None) -> None:
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
    return type(value).__name__


def short(value: Any, limit: int = 60) -> str:
    try:
        text = json.dumps(value, ensure_ascii=False)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."
