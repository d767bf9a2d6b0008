"""Region correspondences between a sketch map and a metric map, and their files.

A correspondence is a *clique*: a group of sketch regions that corresponds to a
group of metric regions (the two segmentations rarely cut a place the same way).
Each clique is anchored by clicked points, which are authoritative: region ids
are derived from them with :func:`regions_at_points` and can be recomputed after
re-segmenting (:func:`assign_regions`).

Two file formats:

- ``.json`` (``"format": "ursim-correspondences"``, versioned, validated on load
  with the JSON Schema shipped in ``ursim_core/schemas/``). Unknown keys are
  preserved on re-save. See the "Correspondence format" section of README.md.
- ``.dat``, the original annotators' text format (points only), kept for the
  published ground truth. Read with :func:`load_dat`, written with :func:`save_dat`.

All values are frozen dataclasses; edit them with :func:`dataclasses.replace`
and the ``with_*`` helpers, which makes undo a matter of keeping old values.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import operator
import os
import re
import urllib.parse
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path, PurePath
from typing import Any

import numpy as np
from scipy import ndimage

from ursim_core.errors import FormatError, SegmentationError
from ursim_core.io.atomic import atomic_write_text

__all__ = [
    "FORMAT_NAME",
    "CURRENT_VERSION",
    "SUPPORTED_VERSIONS",
    "SOURCES",
    "STATUSES",
    "MapRef",
    "Clique",
    "Correspondences",
    "load_correspondences",
    "save_correspondences",
    "correspondences_to_json",
    "correspondences_schema",
    "load_dat",
    "save_dat",
    "regions_at_points",
    "assign_regions",
    "from_pairs",
    "utc_timestamp",
]

FORMAT_NAME = "ursim-correspondences"
CURRENT_VERSION = 1
SOURCES = ("manual", "auto")
STATUSES = ("accepted", "rejected", "pending")

# version n -> function turning a version-n document (a dict) into a version n+1
# document. Version 1 is the first, so there is nothing to migrate yet; a
# version 2 adds `_MIGRATIONS[1] = _migrate_1_to_2`, bumps CURRENT_VERSION and
# ships correspondences-2.schema.json, and every old file keeps loading.
_MIGRATIONS: dict[int, Callable[[dict], dict]] = {}
SUPPORTED_VERSIONS = tuple(sorted({CURRENT_VERSION, *_MIGRATIONS}))

_SHA256_PATTERN = re.compile(r"^[0-9a-fA-F]{64}$")

_MAP_KEYS = ("path", "sha256", "size", "segmentation")
_SEGMENTATION_KEYS = ("method", "params", "labels")
_CLIQUE_KEYS = (
    "id",
    "sketch_points",
    "metric_points",
    "sketch_regions",
    "metric_regions",
    "source",
    "score",
    "note",
    "status",
)
_TOP_KEYS = ("format", "version", "annotator", "created", "modified", "maps", "cliques")
_MAPS_KEYS = ("sketch", "metric")


# --------------------------------------------------------------------------- values


@dataclass(frozen=True)
class MapRef:
    """Which map (and which segmentation of it) one side of a correspondence file refers to.

    Parameters
    ----------
    path : Path or None
        The map image. Absolute after :func:`load_correspondences`; as written in
        the header after :func:`load_dat`.
    sha256 : str or None
        Hex SHA-256 of the map file, to notice a changed map.
    size : (int, int) or None
        ``(rows, cols)`` of the map image.
    segmentation_method : str or None
        Name of the segmenter whose labels the region ids refer to (e.g. ``"maoris"``).
    segmentation_params : dict
        Its parameters, as given to the segmenter.
    labels_path : Path or None
        A saved label image of that segmentation, if any.
    segmentation_extra : dict
        Unknown keys of the file's ``segmentation`` object, written back unchanged.
    extra : dict
        Unknown keys of the file's map object, written back unchanged.

    Examples
    --------
    >>> ref = MapRef(path="maps/sketch.png", size=(120, 80), segmentation_method="maoris")
    >>> ref.path.name, ref.size
    ('sketch.png', (120, 80))
    """

    # Dict fields are left out of the hash (equality still compares them), so
    # these values can be set members and dictionary keys.
    path: Path | None = None
    sha256: str | None = None
    size: tuple[int, int] | None = None
    segmentation_method: str | None = None
    segmentation_params: dict = field(default_factory=dict, hash=False)
    labels_path: Path | None = None
    segmentation_extra: dict = field(default_factory=dict, hash=False)
    extra: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        _set(self, "path", None if self.path is None else Path(self.path))
        _set(self, "labels_path", None if self.labels_path is None else Path(self.labels_path))
        if self.sha256 is not None and not _SHA256_PATTERN.match(str(self.sha256)):
            raise ValueError(f"sha256 must be 64 hexadecimal digits, got {self.sha256!r}")
        if self.size is not None:
            rows, cols = (operator.index(value) for value in self.size)
            if rows < 1 or cols < 1:
                raise ValueError(f"size must be two positive integers (rows, cols), got {self.size!r}")
            _set(self, "size", (rows, cols))
        _set(self, "segmentation_params", dict(self.segmentation_params))
        _set(self, "segmentation_extra", _checked_extra(self.segmentation_extra, _SEGMENTATION_KEYS))
        _set(self, "extra", _checked_extra(self.extra, _MAP_KEYS))


@dataclass(frozen=True)
class Clique:
    """One correspondence: sketch regions that correspond to metric regions.

    Parameters
    ----------
    id : int
        Identifier >= 1, unique within a :class:`Correspondences`.
    sketch_points, metric_points : tuple of (int, int)
        Clicked ``(row, col)`` points; authoritative.
    sketch_regions, metric_regions : tuple of int
        Region ids (labels >= 1) under the points in the referenced segmentations.
    source : {"manual", "auto"}
        Drawn by a person or proposed by a matcher.
    score : float or None
        Matcher score, if any (lower or higher is better depending on the matcher).
    note : str
        Free text.
    status : {"accepted", "rejected", "pending"} or None
        Review state; None means the default for the source (see :attr:`effective_status`).
    extra : dict
        Unknown keys of the file's clique object, written back unchanged.

    Examples
    --------
    >>> clique = Clique(id=1, sketch_points=[(10, 20)], metric_points=[(5, 7), (6, 9)])
    >>> clique.metric_points
    ((5, 7), (6, 9))
    >>> clique.effective_status
    'accepted'
    """

    id: int
    sketch_points: tuple[tuple[int, int], ...] = ()
    metric_points: tuple[tuple[int, int], ...] = ()
    sketch_regions: tuple[int, ...] = ()
    metric_regions: tuple[int, ...] = ()
    source: str = "manual"
    score: float | None = None
    note: str = ""
    status: str | None = None
    extra: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        clique_id = operator.index(self.id)
        if clique_id < 1:
            raise ValueError(f"clique id must be >= 1, got {clique_id}")
        _set(self, "id", clique_id)
        for name in ("sketch_points", "metric_points"):
            _set(self, name, _as_points(getattr(self, name), name))
        for name in ("sketch_regions", "metric_regions"):
            _set(self, name, _as_regions(getattr(self, name), name))
        if self.source not in SOURCES:
            raise ValueError(f"source must be one of {SOURCES}, got {self.source!r}")
        if self.status is not None and self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES} or None, got {self.status!r}")
        if self.score is not None:
            score = float(self.score)
            if not math.isfinite(score):
                raise ValueError(f"score must be a finite number or None, got {self.score!r}")
            _set(self, "score", score)
        if not isinstance(self.note, str):
            raise ValueError(f"note must be a string, got {self.note!r}")
        _set(self, "extra", _checked_extra(self.extra, _CLIQUE_KEYS))

    @property
    def effective_status(self) -> str:
        """The status, with the default filled in: pending for auto, accepted for manual."""
        if self.status is not None:
            return self.status
        return "pending" if self.source == "auto" else "accepted"

    @property
    def is_empty(self) -> bool:
        """True when the clique has no point and no region on either side."""
        return not (self.sketch_points or self.metric_points or self.sketch_regions or self.metric_regions)


@dataclass(frozen=True)
class Correspondences:
    """A whole correspondence file: the two maps and the cliques between them.

    Parameters
    ----------
    sketch, metric : MapRef
        The two maps (for .dat files: map1 and map2).
    cliques : tuple of Clique
        In file order; ids are unique.
    annotator : str
        Who made the manual cliques.
    created, modified : str
        ISO-8601 UTC timestamps; empty until first saved.
    extra : dict
        Unknown top-level keys, written back unchanged.
    maps_extra : dict
        Unknown keys of the ``maps`` object (beside ``sketch`` and ``metric``).

    Examples
    --------
    >>> corr = Correspondences(cliques=(Clique(id=1), Clique(id=4)))
    >>> corr.next_clique_id()
    5
    >>> [clique.id for clique in corr.with_clique(Clique(id=2)).cliques]
    [1, 4, 2]
    """

    sketch: MapRef = field(default_factory=MapRef)
    metric: MapRef = field(default_factory=MapRef)
    cliques: tuple[Clique, ...] = ()
    annotator: str = ""
    created: str = ""
    modified: str = ""
    extra: dict = field(default_factory=dict, hash=False)
    maps_extra: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        cliques = tuple(self.cliques)
        seen: set[int] = set()
        for clique in cliques:
            if not isinstance(clique, Clique):
                raise TypeError(f"cliques must be Clique values, got {type(clique).__name__}")
            if clique.id in seen:
                raise ValueError(f"duplicate clique id {clique.id}")
            seen.add(clique.id)
        _set(self, "cliques", cliques)
        _set(self, "extra", _checked_extra(self.extra, _TOP_KEYS))
        _set(self, "maps_extra", _checked_extra(self.maps_extra, _MAPS_KEYS))

    def next_clique_id(self) -> int:
        """The smallest id larger than every id in use (1 when there is none)."""
        return max((clique.id for clique in self.cliques), default=0) + 1

    def clique(self, clique_id: int) -> Clique:
        """The clique with this id; KeyError if there is none."""
        for clique in self.cliques:
            if clique.id == clique_id:
                return clique
        raise KeyError(clique_id)

    def with_cliques(self, cliques: Iterable[Clique]) -> Correspondences:
        """A copy with the cliques replaced by ``cliques``."""
        return dataclasses.replace(self, cliques=tuple(cliques))

    def with_clique(self, clique: Clique) -> Correspondences:
        """A copy where ``clique`` replaces the clique with its id, or is appended."""
        cliques = list(self.cliques)
        for index, existing in enumerate(cliques):
            if existing.id == clique.id:
                cliques[index] = clique
                break
        else:
            cliques.append(clique)
        return self.with_cliques(cliques)

    def without_clique(self, clique_id: int) -> Correspondences:
        """A copy without the clique with this id; KeyError if there is none."""
        self.clique(clique_id)
        return self.with_cliques(clique for clique in self.cliques if clique.id != clique_id)


def _set(instance: Any, name: str, value: Any) -> None:
    # Normalising fields of a frozen dataclass in __post_init__.
    object.__setattr__(instance, name, value)


def _checked_extra(extra: Mapping, known: Sequence[str]) -> dict:
    extra = dict(extra)
    clashes = sorted(key for key in extra if key in known)
    if clashes:
        raise ValueError(f"extra keys {clashes} clash with known fields; set the fields instead")
    for key in extra:
        if not isinstance(key, str):
            raise ValueError(f"extra keys must be strings, got {key!r}")
    return extra


def _as_points(points: Iterable, name: str) -> tuple[tuple[int, int], ...]:
    result = []
    for point in points:
        coordinates = tuple(point)
        if len(coordinates) != 2:
            raise ValueError(f"{name}: a point is (row, col), got {point!r}")
        row, col = (operator.index(value) for value in coordinates)
        if row < 0 or col < 0:
            raise ValueError(f"{name}: point coordinates must be >= 0, got {point!r}")
        result.append((row, col))
    return tuple(result)


def _as_regions(regions: Iterable, name: str) -> tuple[int, ...]:
    result = tuple(operator.index(region) for region in regions)
    if any(region < 1 for region in result):
        raise ValueError(f"{name}: region ids are labels >= 1, got {result!r}")
    return result


def utc_timestamp(moment: datetime | None = None) -> str:
    """ISO-8601 UTC timestamp with second precision, e.g. ``2024-05-01T12:00:00Z``.

    Examples
    --------
    >>> utc_timestamp(datetime(2024, 5, 1, 12, 0, tzinfo=UTC))
    '2024-05-01T12:00:00Z'
    """
    moment = datetime.now(UTC) if moment is None else moment.astimezone(UTC)
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")


# --------------------------------------------------------------------------- JSON


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
def _validator(version: int = CURRENT_VERSION):
    import jsonschema

    return jsonschema.Draft202012Validator(correspondences_schema(version))


def load_correspondences(path: str | os.PathLike) -> Correspondences:
    """Read and validate a correspondence JSON file.

    Map and label paths, stored relative to the file's folder, come back absolute.

    Parameters
    ----------
    path : str or path-like
        The ``.json`` file.

    Returns
    -------
    Correspondences

    Raises
    ------
    FormatError
        The file is missing or unreadable, not JSON (the message gives line and
        column), not an object, not a URSIM correspondence file, of an
        unsupported version, violates the schema (the error's ``field`` names the
        place, e.g. ``cliques[2].sketch_points[0]``) or repeats a clique id.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "pair.json"
    >>> save_correspondences(Correspondences(cliques=(Clique(id=1, sketch_points=[(1, 2)]),)), target)
    >>> load_correspondences(target).cliques[0].sketch_points
    ((1, 2),)
    """
    path = Path(path)
    document = _read_json_object(path)
    document = _upgrade(document, path)
    _validate(document, path)
    _check_unique_ids(document, path)
    folder = Path(os.path.abspath(path)).parent
    return _from_document(document, folder)


def save_correspondences(corr: Correspondences, path: str | os.PathLike, *, now: str | None = None) -> None:
    """Write ``corr`` as a version-1 correspondence JSON file, atomically.

    ``modified`` is set to the current time (and ``created`` too if it is
    empty). Paths are stored relative to the file's folder (absolute when that
    is impossible, e.g. another Windows drive). Keys are written in a fixed
    order, then the unknown keys in their original order; the text is indented
    by 2 with short number lists kept on one line. The document is validated
    against the schema first, so an invalid file is never written.

    Parameters
    ----------
    corr : Correspondences
        What to write.
    path : str or path-like
        Destination ``.json`` file; its folder must exist.
    now : str, optional
        Timestamp to record instead of the current time (reproducible output).

    Raises
    ------
    FormatError
        The content cannot be represented (e.g. a non-JSON value in ``extra``).
    OSError
        Writing failed; an existing file is left unchanged.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "pair.json"
    >>> save_correspondences(Correspondences(annotator="ana"), target, now="2024-05-01T12:00:00Z")
    >>> load_correspondences(target).modified
    '2024-05-01T12:00:00Z'
    """
    path = Path(path)
    timestamp = utc_timestamp() if now is None else now
    stamped = dataclasses.replace(corr, created=corr.created or timestamp, modified=timestamp)
    text = correspondences_to_json(stamped, folder=Path(os.path.abspath(path)).parent, path=path)
    atomic_write_text(path, text)


def correspondences_to_json(
    corr: Correspondences, *, folder: str | os.PathLike | None = None, path: str | os.PathLike | None = None
) -> str:
    """The JSON text :func:`save_correspondences` writes (timestamps as they are in ``corr``).

    Parameters
    ----------
    corr : Correspondences
        What to serialise.
    folder : str or path-like, optional
        Folder that stored paths are made relative to; the current directory by default.
    path : str or path-like, optional
        File named in error messages.

    Raises
    ------
    FormatError
        The document would not be a valid version-1 file.

    Examples
    --------
    >>> print(correspondences_to_json(Correspondences()).splitlines()[1])
      "format": "ursim-correspondences",
    """
    folder = Path(os.path.abspath(os.getcwd() if folder is None else folder))
    document = _to_document(corr, folder)
    try:
        text = json.dumps(document, indent=2, ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as error:
        raise FormatError(f"cannot be written as JSON: {error}", path=path) from None
    # Round-trip through the parser so the schema sees exactly what a reader will.
    _validate(json.loads(text), path)
    return _collapse_number_lists(text) + "\n"


def _read_bytes(path: Path, *, what: str) -> bytes:
    """The file's bytes, or a FormatError naming the file and why it cannot be read."""
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise FormatError("file not found", path=path) from None
    except IsADirectoryError:
        raise FormatError(f"is a folder, not {what}", path=path) from None
    except OSError as error:
        raise FormatError(f"cannot read file: {error.strerror or error}", path=path) from None


def _read_json_object(path: Path) -> dict:
    raw = _read_bytes(path, what="a correspondence file")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise FormatError(f"not UTF-8 text (byte {error.start}): not a JSON file", path=path) from None
    try:
        document = json.loads(text, object_pairs_hook=_reject_duplicate_keys, parse_constant=_reject_constant)
    except json.JSONDecodeError as error:
        raise FormatError(
            f"not valid JSON: {error.msg} at line {error.lineno}, column {error.colno}", path=path
        ) from None
    except _InvalidJsonValue as error:
        raise FormatError(f"not valid JSON for URSIM: {error}", path=path) from None
    if not isinstance(document, dict):
        raise FormatError(f"expected a JSON object at the top level, got {_json_type(document)}", path=path)
    return document


class _InvalidJsonValue(ValueError):
    pass


def _reject_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict:
    # json.loads silently keeps the last of two equal keys; a hand-edited file
    # would lose data without notice.
    result: dict = {}
    for key, value in pairs:
        if key in result:
            raise _InvalidJsonValue(f"key {key!r} appears twice in one object")
        result[key] = value
    return result


def _reject_constant(name: str) -> Any:
    raise _InvalidJsonValue(f"{name} is not a JSON number")


def _upgrade(document: dict, path: Path) -> dict:
    if "format" not in document:
        raise FormatError("required field is missing; not a URSIM correspondence file", path=path, field="format")
    if document["format"] != FORMAT_NAME:
        raise FormatError(
            f"expected {FORMAT_NAME!r}, got {_short(document['format'])}: not a URSIM correspondence file",
            path=path,
            field="format",
        )
    if "version" not in document:
        raise FormatError("required field is missing", path=path, field="version")
    version = document["version"]
    if isinstance(version, bool) or not isinstance(version, int):
        raise FormatError(f"expected an integer, got {_short(version)}", path=path, field="version")
    supported = ", ".join(str(number) for number in SUPPORTED_VERSIONS)
    while version != CURRENT_VERSION:
        migrate = _MIGRATIONS.get(version)
        if migrate is None:
            newer = " (written by a newer URSIM Studio?)" if version > CURRENT_VERSION else ""
            raise FormatError(
                f"unsupported version {version}{newer}; this URSIM Studio reads version(s) {supported}",
                path=path,
                field="version",
            )
        document = migrate(document)
        version = document["version"]
    return document


def _validate(document: Any, path: str | os.PathLike | None) -> None:
    from jsonschema.exceptions import best_match

    errors = list(_validator().iter_errors(document))
    if not errors:
        return
    error = best_match(errors)
    field_name, problem = _describe_schema_error(error)
    others = len(errors) - 1
    if others:
        problem += f" (and {others} more problem{'s' if others > 1 else ''})"
    raise FormatError(problem, path=path, field=field_name)


def _describe_schema_error(error) -> tuple[str | None, str]:
    location = list(error.absolute_path)
    schema = error.schema if isinstance(error.schema, dict) else {}
    title = schema.get("title")
    instance = error.instance
    kind = error.validator
    value = error.validator_value
    if kind == "required":
        missing = next((name for name in value if name not in instance), value[0])
        return _field_path([*location, missing]), "required field is missing"
    if kind == "type":
        types = [value] if isinstance(value, str) else list(value)
        expected = title or " or ".join(types)
        got = f"{_json_type(instance)} {_short(instance)}"
    elif kind == "const":
        expected, got = _short(value), _short(instance)
    elif kind == "enum":
        expected = "one of " + ", ".join(_short(option) for option in value)
        got = _short(instance)
    elif kind in ("minItems", "maxItems"):
        if schema.get("minItems") == schema.get("maxItems"):
            count = f"exactly {value} items"
        else:
            count = f"{'at least' if kind == 'minItems' else 'at most'} {value} items"
        expected = f"{title} ({count})" if title else count
        got = f"{len(instance)} item{'' if len(instance) == 1 else 's'} {_short(instance)}"
    elif kind == "minimum":
        expected = title or f"a number >= {value}"
        got = _short(instance)
    elif kind == "minLength":
        expected = title or "a non-empty string"
        got = _short(instance)
    elif kind == "pattern":
        expected = title or f"a string matching {value}"
        got = _short(instance)
    else:
        return _field_path(location), error.message
    return _field_path(location), f"expected {expected}, got {got}"


def _field_path(location: Sequence) -> str | None:
    text = ""
    for part in location:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text or None


def _json_type(value: Any) -> str:
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


def _short(value: Any, limit: int = 60) -> str:
    try:
        text = json.dumps(value, ensure_ascii=False)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _check_unique_ids(document: dict, path: Path) -> None:
    first_index: dict[int, int] = {}
    for index, clique in enumerate(document["cliques"]):
        clique_id = clique["id"]
        if clique_id in first_index:
            raise FormatError(
                f"duplicate clique id {clique_id} (also used by cliques[{first_index[clique_id]}])",
                path=path,
                field=f"cliques[{index}].id",
            )
        first_index[clique_id] = index


def _from_document(document: dict, folder: Path) -> Correspondences:
    maps = document["maps"]
    return Correspondences(
        sketch=_map_from_json(maps["sketch"], folder),
        metric=_map_from_json(maps["metric"], folder),
        cliques=tuple(_clique_from_json(clique) for clique in document["cliques"]),
        annotator=document.get("annotator", ""),
        created=document.get("created", ""),
        modified=document.get("modified", ""),
        extra=_unknown(document, _TOP_KEYS),
        maps_extra=_unknown(maps, _MAPS_KEYS),
    )


def _map_from_json(item: dict, folder: Path) -> MapRef:
    segmentation = item.get("segmentation") or {}
    size = item.get("size")
    return MapRef(
        path=_resolve(item.get("path"), folder),
        sha256=item.get("sha256"),
        size=None if size is None else tuple(size),
        segmentation_method=segmentation.get("method"),
        segmentation_params=segmentation.get("params", {}),
        labels_path=_resolve(segmentation.get("labels"), folder),
        segmentation_extra=_unknown(segmentation, _SEGMENTATION_KEYS),
        extra=_unknown(item, _MAP_KEYS),
    )


def _clique_from_json(item: dict) -> Clique:
    return Clique(
        id=item["id"],
        sketch_points=item["sketch_points"],
        metric_points=item["metric_points"],
        sketch_regions=item.get("sketch_regions", ()),
        metric_regions=item.get("metric_regions", ()),
        source=item.get("source", "manual"),
        score=item.get("score"),
        note=item.get("note", ""),
        status=item.get("status"),
        extra=_unknown(item, _CLIQUE_KEYS),
    )


def _unknown(item: dict, known: Sequence[str]) -> dict:
    return {key: value for key, value in item.items() if key not in known}


def _resolve(text: str | None, folder: Path) -> Path | None:
    if text is None:
        return None
    candidate = Path(text)
    if not candidate.is_absolute():
        candidate = folder / candidate
    return Path(os.path.normpath(candidate))


def _relative(path: Path | None, folder: Path) -> str | None:
    if path is None:
        return None
    absolute = os.path.abspath(path)
    try:
        relative = os.path.relpath(absolute, folder)
    except ValueError:
        # Another drive on Windows: no relative path exists.
        return PurePath(absolute).as_posix()
    # Forward slashes read back on every platform.
    return PurePath(relative).as_posix()


def _to_document(corr: Correspondences, folder: Path) -> dict:
    maps = {
        "sketch": _map_to_json(corr.sketch, folder),
        "metric": _map_to_json(corr.metric, folder),
        **corr.maps_extra,
    }
    return {
        "format": FORMAT_NAME,
        "version": CURRENT_VERSION,
        "annotator": corr.annotator,
        "created": corr.created,
        "modified": corr.modified,
        "maps": maps,
        "cliques": [_clique_to_json(clique) for clique in corr.cliques],
        **corr.extra,
    }


def _map_to_json(ref: MapRef, folder: Path) -> dict:
    return {
        "path": _relative(ref.path, folder),
        "sha256": ref.sha256,
        "size": None if ref.size is None else list(ref.size),
        "segmentation": {
            "method": ref.segmentation_method,
            "params": ref.segmentation_params,
            "labels": _relative(ref.labels_path, folder),
            **ref.segmentation_extra,
        },
        **ref.extra,
    }


def _clique_to_json(clique: Clique) -> dict:
    item: dict[str, Any] = {
        "id": clique.id,
        "sketch_points": [list(point) for point in clique.sketch_points],
        "metric_points": [list(point) for point in clique.metric_points],
        "sketch_regions": list(clique.sketch_regions),
        "metric_regions": list(clique.metric_regions),
        "source": clique.source,
    }
    # Optional keys are written only when set, which keeps files short and diffs small.
    if clique.score is not None:
        item["score"] = clique.score
    if clique.note:
        item["note"] = clique.note
    if clique.status is not None:
        item["status"] = clique.status
    item.update(clique.extra)
    return item


# A JSON array holding only numbers, as json.dumps(indent=...) spreads it over
# several lines. Raw newlines never occur inside JSON strings (they are escaped),
# so requiring them keeps this from touching string content.
_NUMBER = r"-?[0-9]+(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?"
_NUMBER_LIST = re.compile(r"\[\n\s*(" + _NUMBER + r"(?:,\n\s*" + _NUMBER + r")*)\n\s*\]")


def _collapse_number_lists(text: str) -> str:
    # [row, col] points and region lists on one line each: a file a person can read.
    return _NUMBER_LIST.sub(lambda match: "[" + ", ".join(re.split(r",\n\s*", match.group(1))) + "]", text)


# --------------------------------------------------------------------------- .dat

_DAT_SET = re.compile(r"^#\s*(\d+)\s*match set$")
_DAT_SIDE = re.compile(r"^#\s*map([12])$")
_DAT_POINT = re.compile(r"^(\d+)\s+(\d+)$")
_DAT_NO_PATH = "-"


def load_dat(path: str | os.PathLike, *, drop_empty: bool = False) -> Correspondences:
    """Read a ground-truth file in the original annotators' ``.dat`` format.

    The layout is a header ``# <map1 path> <map2 path>`` then match sets, each
    ``# Kmatch set``, ``# map1``, ``ROW COL`` lines, ``# map2``, ``ROW COL`` lines;
    blank lines are ignored. map1 is the sketch, map2 the metric map. Clique ids
    are 1, 2, ... in file order (the ``K`` numbers are not kept). The header's
    paths are kept as written: in ``MapRef.path`` (not resolved; ``-`` means
    none) and verbatim in ``MapRef.extra["dat_path"]``.

    Parameters
    ----------
    path : str or path-like
        The ``.dat`` file.
    drop_empty : bool, optional
        Drop match sets without any point. False by default because the legacy
        scorer counts the trailing empty set of the published files.

    Returns
    -------
    Correspondences
        Cliques with points only (``source="manual"``); fill the regions with
        :func:`assign_regions`.

    Raises
    ------
    FormatError
        Missing or unreadable file, or a malformed line (the message gives its number).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "gt.dat"
    >>> _ = target.write_text("# a.png b.png\\n# 0match set\\n# map1\\n228 302\\n# map2\\n166 308\\n\\n")
    >>> corr = load_dat(target)
    >>> corr.sketch.path.name, corr.cliques[0].sketch_points, corr.cliques[0].metric_points
    ('a.png', ((228, 302),), ((166, 308),))
    """
    path = Path(path)
    lines = _read_dat_lines(path)
    if not lines:
        raise FormatError("empty file; expected a '# <map1 path> <map2 path>' header", path=path)
    sketch_ref, metric_ref = _parse_dat_header(lines[0], path)

    sets: list[dict] = []
    current: dict | None = None
    for number, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        if _DAT_SET.match(line):
            _finish_dat_set(current, number, path)
            current = {"line": number, "side": None, "points": {"1": [], "2": []}}
            sets.append(current)
            continue
        side = _DAT_SIDE.match(line)
        if side:
            if current is None:
                raise FormatError(f"line {number}: {line!r} before the first '# Kmatch set' line", path=path)
            if current["side"] == "2":
                raise FormatError(f"line {number}: {line!r} after '# map2' in the same match set", path=path)
            expected = "1" if current["side"] is None else "2"
            if side.group(1) != expected:
                raise FormatError(f"line {number}: expected '# map{expected}', got {line!r}", path=path)
            current["side"] = expected
            continue
        point = _DAT_POINT.match(line)
        if point:
            if current is None or current["side"] is None:
                raise FormatError(f"line {number}: point {line!r} before '# map1' or '# map2'", path=path)
            current["points"][current["side"]].append((int(point.group(1)), int(point.group(2))))
            continue
        raise FormatError(
            f"line {number}: expected 'ROW COL' (two non-negative integers), '# Kmatch set', "
            f"'# map1' or '# map2', got {raw.strip()!r}",
            path=path,
        )
    _finish_dat_set(current, len(lines) + 1, path)

    cliques = []
    for match_set in sets:
        sketch_points, metric_points = match_set["points"]["1"], match_set["points"]["2"]
        if drop_empty and not sketch_points and not metric_points:
            continue
        cliques.append(Clique(id=len(cliques) + 1, sketch_points=sketch_points, metric_points=metric_points))
    return Correspondences(sketch=sketch_ref, metric=metric_ref, cliques=tuple(cliques))


def save_dat(corr: Correspondences, path: str | os.PathLike) -> None:
    """Write ``corr`` in the original annotators' ``.dat`` format, atomically.

    Only points are written (the format has nothing else); match sets are
    numbered 0, 1, ... in clique order and each is followed by a blank line, as
    in the published files. Header paths are ``MapRef.extra["dat_path"]`` when it
    still names ``MapRef.path``, else the path itself, ``-`` for none;
    white space and ``%`` inside a path are %-escaped so the two-token header
    stays readable (:func:`load_dat` decodes them).

    Parameters
    ----------
    corr : Correspondences
        What to write.
    path : str or path-like
        Destination ``.dat`` file.

    Raises
    ------
    OSError
        Writing failed; an existing file is left unchanged.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "gt.dat"
    >>> corr = Correspondences(MapRef(path="a.png"), MapRef(path="b.png"),
    ...                        cliques=(Clique(id=1, sketch_points=[(1, 2)], metric_points=[(3, 4)]),))
    >>> save_dat(corr, target)
    >>> print(target.read_text(), end="")
    # a.png b.png
    # 0match set
    # map1
    1 2
    # map2
    3 4
    <BLANKLINE>
    """
    lines = [f"# {_dat_header_token(corr.sketch)} {_dat_header_token(corr.metric)}"]
    for index, clique in enumerate(corr.cliques):
        lines.append(f"# {index}match set")
        lines.append("# map1")
        lines.extend(f"{row} {col}" for row, col in clique.sketch_points)
        lines.append("# map2")
        lines.extend(f"{row} {col}" for row, col in clique.metric_points)
        lines.append("")
    atomic_write_text(path, "\n".join(lines) + "\n")


def _read_dat_lines(path: Path) -> list[str]:
    raw = _read_bytes(path, what="a .dat file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        line = raw[: error.start].count(b"\n") + 1
        raise FormatError(f"line {line}: not text (undecodable byte); not a .dat file", path=path) from None
    return text.splitlines()


def _parse_dat_header(line: str, path: Path) -> tuple[MapRef, MapRef]:
    tokens = line.strip().lstrip("#").split() if line.strip().startswith("#") else None
    if tokens is None or len(tokens) != 2:
        raise FormatError(f"line 1: expected '# <map1 path> <map2 path>', got {line.strip()!r}", path=path)
    refs = []
    for token in tokens:
        if token == _DAT_NO_PATH:
            refs.append(MapRef())
        else:
            text = urllib.parse.unquote(token)
            refs.append(MapRef(path=Path(text), extra={"dat_path": text}))
    return refs[0], refs[1]


def _finish_dat_set(current: dict | None, number: int, path: Path) -> None:
    if current is not None and current["side"] != "2":
        missing = "'# map1' and '# map2'" if current["side"] is None else "'# map2'"
        raise FormatError(
            f"line {number}: the match set started on line {current['line']} has no {missing} line", path=path
        )


def _dat_header_token(ref: MapRef) -> str:
    if ref.path is None:
        return _DAT_NO_PATH
    written = ref.extra.get("dat_path")
    text = written if isinstance(written, str) and Path(written) == ref.path else ref.path.as_posix()
    if text == _DAT_NO_PATH:
        return "%2D"  # a file really named "-", not to be read back as "no path"
    # Escape only what breaks the header, so ordinary paths stay readable.
    return "".join(urllib.parse.quote(char, safe="") if char.isspace() or char == "%" else char for char in text)


# --------------------------------------------------------------------------- regions


def regions_at_points(labels: np.ndarray, points: Iterable, *, tolerance: float = 10) -> list[int]:
    """The region id under each ``(row, col)`` point, with the released code's tolerance.

    A point on a region pixel gets that region. A point on 0 (a wall, outside
    the segmentation) or outside the image gets the region of the nearest
    non-zero pixel when that pixel is at most ``tolerance`` pixels away
    (Euclidean), else 0, meaning "dropped" (``GraphLaplacian::getVertex``).
    When several regions are equally near, any one of them may be returned.

    Parameters
    ----------
    labels : (rows, cols) integer array
        Label image, 0 = no region.
    points : iterable of (row, col)
        Pixel coordinates; non-integers are rounded to the nearest pixel.
    tolerance : float, keyword-only
        Largest distance in pixels to a region pixel, 10 by default.

    Returns
    -------
    list of int
        One id per point, 0 where no region is near enough.

    Examples
    --------
    >>> labels = np.zeros((5, 20), dtype=np.int32)
    >>> labels[:, :4] = 1
    >>> labels[:, 10:] = 2
    >>> regions_at_points(labels, [(2, 1), (2, 5), (2, 8), (2, 25)], tolerance=3)
    [1, 1, 2, 0]
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"labels must be a 2-D array, got shape {labels.shape}")
    coordinates = np.asarray(list(points) if not isinstance(points, np.ndarray) else points, dtype=float)
    if coordinates.size == 0:
        return []
    if coordinates.ndim != 2 or coordinates.shape[1] != 2:
        raise ValueError(f"points must be (row, col) pairs, got an array of shape {coordinates.shape}")
    if not np.all(np.isfinite(coordinates)):
        raise ValueError("points must be finite numbers")
    coordinates = np.rint(coordinates).astype(np.int64)
    rows, cols = labels.shape
    result = np.zeros(len(coordinates), dtype=np.int64)
    inside = (
        (coordinates[:, 0] >= 0) & (coordinates[:, 0] < rows) & (coordinates[:, 1] >= 0) & (coordinates[:, 1] < cols)
    )
    result[inside] = labels[coordinates[inside, 0], coordinates[inside, 1]]
    misses = np.flatnonzero(result == 0)
    if len(misses) == 0 or tolerance < 0 or not labels.any():
        return [int(value) for value in result]

    reach = int(math.floor(tolerance))
    window_area = (2 * reach + 1) ** 2
    remaining = misses
    # Measured costs: a window search is ~80 us per point plus ~0.02 us per
    # window pixel; the distance transform with indices ~0.3 us per image pixel.
    if len(misses) * (window_area + 4000) > 15 * labels.size:
        # Many misses or a large tolerance: one distance transform answers all
        # points inside the image at once.
        distance, (nearest_row, nearest_col) = ndimage.distance_transform_edt(labels == 0, return_indices=True)
        inside_misses = misses[inside[misses]]
        miss_rows, miss_cols = coordinates[inside_misses, 0], coordinates[inside_misses, 1]
        near = distance[miss_rows, miss_cols] <= tolerance
        result[inside_misses[near]] = labels[
            nearest_row[miss_rows[near], miss_cols[near]], nearest_col[miss_rows[near], miss_cols[near]]
        ]
        remaining = misses[~inside[misses]]
    for index in remaining:
        row, col = coordinates[index]
        result[index] = _nearest_label_in_window(labels, row, col, tolerance, reach)
    return [int(value) for value in result]


def _nearest_label_in_window(labels: np.ndarray, row: int, col: int, tolerance: float, reach: int) -> int:
    top, bottom = max(row - reach, 0), min(row + reach + 1, labels.shape[0])
    left, right = max(col - reach, 0), min(col + reach + 1, labels.shape[1])
    if top >= bottom or left >= right:
        return 0
    window = labels[top:bottom, left:right]
    found_rows, found_cols = np.nonzero(window)
    if len(found_rows) == 0:
        return 0
    squared = (found_rows + top - row) ** 2 + (found_cols + left - col) ** 2
    best = int(np.argmin(squared))
    if squared[best] > tolerance * tolerance:
        return 0
    return int(window[found_rows[best], found_cols[best]])


def assign_regions(
    corr: Correspondences, sketch_labels: np.ndarray, metric_labels: np.ndarray, *, tolerance: float = 10
) -> Correspondences:
    """Fill every clique's region ids from its points.

    Each side's regions become the ids under its points (see
    :func:`regions_at_points`), without duplicates, in point order, with
    dropped points (0) left out. Points are not changed.

    Parameters
    ----------
    corr : Correspondences
        Cliques with points.
    sketch_labels, metric_labels : (rows, cols) integer arrays
        Label images of the two maps.
    tolerance : float, keyword-only
        As in :func:`regions_at_points`.

    Returns
    -------
    Correspondences
        A copy with ``sketch_regions`` and ``metric_regions`` replaced.

    Raises
    ------
    SegmentationError
        A label image's shape differs from the size recorded for its map.

    Examples
    --------
    >>> labels = np.array([[1, 1, 0, 2, 2]], dtype=np.int32)
    >>> corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(0, 0), (0, 1), (0, 4)],
    ...                                        metric_points=[(0, 3)]),))
    >>> done = assign_regions(corr, labels, labels)
    >>> done.cliques[0].sketch_regions, done.cliques[0].metric_regions
    ((1, 2), (2,))
    """
    for side, ref, labels in (("sketch", corr.sketch, sketch_labels), ("metric", corr.metric, metric_labels)):
        shape = np.shape(labels)
        if ref.size is not None and tuple(shape) != tuple(ref.size):
            raise SegmentationError(
                f"the {side} label image is {shape[0]}x{shape[1]} but the {side} map is "
                f"{ref.size[0]}x{ref.size[1]}: labels of another image?",
                path=ref.labels_path or ref.path,
            )
    sketch_regions = _regions_per_clique(sketch_labels, [c.sketch_points for c in corr.cliques], tolerance)
    metric_regions = _regions_per_clique(metric_labels, [c.metric_points for c in corr.cliques], tolerance)
    return corr.with_cliques(
        dataclasses.replace(clique, sketch_regions=sketch, metric_regions=metric)
        for clique, sketch, metric in zip(corr.cliques, sketch_regions, metric_regions)
    )


def _regions_per_clique(labels: np.ndarray, point_lists: Sequence[Sequence], tolerance: float) -> list[tuple]:
    # One call for all points, so the distance transform (if needed) is computed once.
    flat = [point for points in point_lists for point in points]
    found = iter(regions_at_points(labels, flat, tolerance=tolerance))
    result = []
    for points in point_lists:
        ids = [next(found) for _ in points]
        result.append(tuple(dict.fromkeys(region for region in ids if region != 0)))
    return result


def from_pairs(
    pairs: Iterable[tuple[int, int]],
    *,
    sketch_points_of: Callable[[int], tuple[int, int]],
    metric_points_of: Callable[[int], tuple[int, int]],
    source: str = "auto",
    scores: Sequence[float | None] | None = None,
    first_id: int = 1,
) -> tuple[Clique, ...]:
    """One clique per matched region pair, anchored at a representative point of each region.

    Parameters
    ----------
    pairs : iterable of (sketch_region, metric_region)
        E.g. ``MatchResult.pairs``.
    sketch_points_of, metric_points_of : callable, keyword-only
        Region id -> ``(row, col)`` interior point, e.g.
        ``lambda region: graph.nodes[region]["interior"]``.
    source : {"auto", "manual"}, keyword-only
        Source recorded on every clique.
    scores : sequence of float or None, keyword-only
        One score per pair.
    first_id : int, keyword-only
        Id of the first clique (e.g. ``corr.next_clique_id()`` to append).

    Returns
    -------
    tuple of Clique

    Examples
    --------
    >>> centres = {1: (5, 5), 2: (5, 30), 7: (40, 12)}
    >>> cliques = from_pairs([(1, 7), (2, 7)], sketch_points_of=centres.get, metric_points_of=centres.get)
    >>> [(c.id, c.sketch_points, c.metric_regions, c.effective_status) for c in cliques]
    [(1, ((5, 5),), (7,), 'pending'), (2, ((5, 30),), (7,), 'pending')]
    """
    pairs = [(operator.index(sketch), operator.index(metric)) for sketch, metric in pairs]
    if scores is not None and len(scores) != len(pairs):
        raise ValueError(f"{len(scores)} scores for {len(pairs)} pairs")
    return tuple(
        Clique(
            id=first_id + index,
            sketch_points=(sketch_points_of(sketch),),
            metric_points=(metric_points_of(metric),),
            sketch_regions=(sketch,),
            metric_regions=(metric,),
            source=source,
            score=None if scores is None else scores[index],
        )
        for index, (sketch, metric) in enumerate(pairs)
    )
