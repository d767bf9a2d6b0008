"""The JSON correspondence file (``"format": "ursim-correspondences"``, versioned).

:func:`load_correspondences` reads, upgrades (``_MIGRATIONS``) and validates a file against the
schema shipped in ``schemas/`` (:mod:`ursim_core.correspondences.schema`);
:func:`save_correspondences` writes one atomically. Unknown keys are preserved on re-save. See
the "Correspondence format" section of README.md.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path, PurePath
from typing import Any

from ursim_core.correspondences.files import paused_garbage_collection, read_file_bytes, write_guarded
from ursim_core.correspondences.json_text import (
    EMPTY_CLIQUES,
    cliques_text,
    collapse_number_lists,
    escape_lone_surrogates,
)
from ursim_core.correspondences.schema import (
    CURRENT_VERSION,
    FORMAT_NAME,
    short,
    validate,
)
from ursim_core.correspondences.strict_json import MAX_DEPTH, check_values, parse_json_object
from ursim_core.correspondences.values import (
    CLIQUE_KEYS,
    MAP_KEYS,
    MAPS_KEYS,
    SEGMENTATION_KEYS,
    TOP_KEYS,
    Clique,
    Correspondences,
    MapRef,
    utc_timestamp,
)
from ursim_core.errors import FormatError, MapChangedWarning, ParameterError

__all__ = [
    "SUPPORTED_VERSIONS",
    "check_maps",
    "load_correspondences",
    "load_correspondence_file",
    "save_correspondences",
    "correspondences_to_json",
    "MAX_DEPTH",
]

# version n -> function turning a version-n document (a dict) into a version n+1
# document. Version 1 is the first, so there is nothing to migrate yet; a
# version 2 adds `_MIGRATIONS[1] = _migrate_1_to_2`, bumps CURRENT_VERSION and
# ships correspondences-2.schema.json, and every old file keeps loading.
_MIGRATIONS: dict[int, Callable[[dict], dict]] = {}
SUPPORTED_VERSIONS = tuple(sorted({CURRENT_VERSION, *_MIGRATIONS}))


def load_correspondences(path: str | os.PathLike, *, sketch_map=None, metric_map=None) -> Correspondences:
    """Read and validate a correspondence JSON file.

    Map and label paths, stored relative to the file's folder, come back absolute. The
    value's ``loaded_sha256`` is the digest of the bytes read (pass it to the next save).

    Parameters
    ----------
    path : str or path-like
        The ``.json`` file.
    sketch_map, metric_map : Map, optional
        The maps in use (anything with a ``sha256``): a :class:`MapChangedWarning` is
        issued when the file recorded another digest for that side.

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
    >>> digest = save_correspondences(Correspondences(cliques=(Clique(id=1, sketch_points=[(1, 2)]),)), target)
    >>> load_correspondences(target).cliques[0].sketch_points
    ((1, 2),)
    """
    path = Path(path)
    raw = read_file_bytes(path, what="correspondence file")
    with paused_garbage_collection():
        document = parse_json_object(raw, path)
        document = _upgrade(document, path)
        check_values(document, path, known_clique_keys=_CLIQUE_KEY_SET)
        validate(document, path)
        _check_unique_ids(document, path)
        folder = Path(os.path.abspath(path)).parent
        corr = _from_document(document, folder, path, loaded_sha256=hashlib.sha256(raw).hexdigest())
    for side, ref, loaded in (("sketch", corr.sketch, sketch_map), ("metric", corr.metric, metric_map)):
        _warn_if_changed(side, ref, loaded, path)
    return corr


def load_correspondence_file(path: str | os.PathLike) -> Correspondences:
    """A correspondence file of either format, by its suffix: ``.dat``
    (:func:`~ursim_core.correspondences.dat_codec.load_dat`), else JSON (:func:`load_correspondences`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from ursim_core.correspondences import save_dat
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "pair.dat"
    >>> _ = save_dat(Correspondences(cliques=(Clique(id=1, sketch_points=[(1, 2)], metric_points=[(3, 4)]),)), target)
    >>> load_correspondence_file(target).cliques[0].metric_points
    ((3, 4),)
    """
    from ursim_core.correspondences.dat_codec import load_dat

    path = Path(path)
    return load_dat(path) if path.suffix.lower() == ".dat" else load_correspondences(path)


def check_maps(corr: Correspondences, sketch_map, metric_map, path: str | os.PathLike) -> None:
    """Refuse correspondences of another pair of maps; warn when a map of the pair was edited.

    Parameters
    ----------
    corr : Correspondences
        As loaded from ``path``.
    sketch_map, metric_map : Map
        The maps in use (their ``shape`` and ``sha256``).
    path : str or path-like
        The file, named in the error.

    Raises
    ------
    ParameterError
        A map's size differs from the one the file recorded for that side.

    Warns
    -----
    MapChangedWarning
        Same size, other SHA-256 (as :func:`load_correspondences` with the maps).

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> sketch, plan = map_from_array(np.ones((4, 6), bool)), map_from_array(np.ones((5, 5), bool))
    >>> corr = Correspondences(MapRef(size=(4, 6)), MapRef(size=(5, 5)))
    >>> check_maps(corr, sketch, plan, "pair.json")  # the pair the file was made on: silent
    >>> check_maps(corr, plan, plan, "pair.json")
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: pair.json: made on a sketch map of 4x6 px, not this one of 5x5 px: ...
    """
    for side, ref, loaded in (("sketch", corr.sketch, sketch_map), ("metric", corr.metric, metric_map)):
        shape = tuple(getattr(loaded, "shape", ())[:2])
        if ref is not None and ref.size is not None and shape and tuple(ref.size) != shape:
            made_on = f" ({Path(ref.path).name})" if ref.path else ""
            raise ParameterError(
                f"made on a {side} map of {ref.size[0]}x{ref.size[1]} px{made_on}, not this one of "
                f"{shape[0]}x{shape[1]} px: a file of another pair?",
                path=path,
            )
        _warn_if_changed(side, ref, loaded, Path(path))


def _warn_if_changed(side: str, ref: MapRef, loaded, path: Path) -> None:
    actual = getattr(loaded, "sha256", None)
    if loaded is None or ref.sha256 is None or actual is None or actual.lower() == ref.sha256.lower():
        return
    warnings.warn(
        MapChangedWarning(
            f"{path}: the {side} map{_named(getattr(loaded, 'path', None) or ref.path)} is not the one these "
            f"correspondences were made on (SHA-256 {actual[:12]}... instead of {ref.sha256[:12]}...): "
            "points may no longer fall on the same places"
        ),
        stacklevel=3,
    )


def _named(map_path) -> str:
    # A map made in code has no file: "the sketch map is not...", never "the sketch map None".
    return f" {map_path}" if map_path else ""


def save_correspondences(
    corr: Correspondences, path: str | os.PathLike, *, now: str | None = None, expected_sha256: str | None = None
) -> str:
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
    expected_sha256 : str, optional
        The digest the file had when it was loaded (``corr.loaded_sha256``). When given and
        the file now holds other bytes (another session saved it), nothing is written.

    Returns
    -------
    str
        SHA-256 of the bytes written: the ``expected_sha256`` of the next save.

    Raises
    ------
    FileChangedError
        ``expected_sha256`` was given and the file changed on disk since.
    SaveRefusedError
        ``path`` is one of the maps or label images ``corr`` refers to.
    FormatError
        The content cannot be represented (e.g. a non-JSON value in ``extra``).
    OSError
        Writing failed; an existing file is left unchanged.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "pair.json"
    >>> digest = save_correspondences(Correspondences(annotator="ana"), target, now="2024-05-01T12:00:00Z")
    >>> load_correspondences(target).modified
    '2024-05-01T12:00:00Z'
    """
    path = Path(path)
    timestamp = utc_timestamp() if now is None else now
    stamped = dataclasses.replace(corr, created=corr.created or timestamp, modified=timestamp)
    with paused_garbage_collection():
        text = correspondences_to_json(stamped, folder=Path(os.path.abspath(path)).parent, path=path)
    data = text.encode("utf-8")
    return write_guarded(corr, path, data, expected_sha256=expected_sha256, what="correspondence file")


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
    # The cliques were checked when they were made (Clique.__post_init__ applies the schema's
    # rules); the rest and every unknown value are checked here, so whatever is saved loads.
    document = _to_document(corr, folder, cliques=[])
    check_values(
        {**document, "cliques": [clique.extra for clique in corr.cliques]}, path, known_clique_keys=_CLIQUE_KEY_SET
    )
    validate(document, path)
    try:
        # Everything but the cliques goes through json.dumps; the cliques, nearly all of a big
        # file, through a writer of the same text that is ~10x faster (_cliques_text).
        head = collapse_number_lists(json.dumps(document, indent=2, ensure_ascii=False, allow_nan=False))
        text = head.replace(EMPTY_CLIQUES, cliques_text(corr.cliques), 1)
    except (TypeError, ValueError) as error:
        raise FormatError(f"cannot be written as JSON: {error}", path=path) from None
    except RecursionError:
        raise FormatError(f"cannot be written as JSON: nested deeper than {MAX_DEPTH} levels", path=path) from None
    # Lone surrogates (half of a pair, or a byte of a non-UTF-8 file name as os.fsdecode keeps
    # it) have no UTF-8 form: written as \\uXXXX escapes they read back as the same string.
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        text = escape_lone_surrogates(text)
    return text + "\n"


def _upgrade(document: dict, path: Path) -> dict:
    if "format" not in document:
        raise FormatError("required field is missing; not a URSIM correspondence file", path=path, field="format")
    if document["format"] != FORMAT_NAME:
        raise FormatError(
            f"expected {FORMAT_NAME!r}, got {short(document['format'])}: not a URSIM correspondence file",
            path=path,
            field="format",
        )
    if "version" not in document:
        raise FormatError("required field is missing", path=path, field="version")
    version = document["version"]
    if isinstance(version, bool) or not isinstance(version, int):
        raise FormatError(f"expected an integer, got {short(version)}", path=path, field="version")
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


def _from_document(document: dict, folder: Path, path: Path, *, loaded_sha256: str | None) -> Correspondences:
    maps = document["maps"]
    return Correspondences(
        sketch=_map_from_json(maps["sketch"], folder, path, "maps.sketch"),
        metric=_map_from_json(maps["metric"], folder, path, "maps.metric"),
        cliques=tuple(_clique_from_json(clique) for clique in document["cliques"]),
        annotator=document.get("annotator", ""),
        created=document.get("created", ""),
        modified=document.get("modified", ""),
        extra=_unknown(document, TOP_KEYS),
        maps_extra=_unknown(maps, MAPS_KEYS),
        loaded_sha256=loaded_sha256,
    )


def _map_from_json(item: dict, folder: Path, path: Path, where: str) -> MapRef:
    segmentation = item.get("segmentation") or {}
    size = item.get("size")
    for name, text in (("path", item.get("path")), ("segmentation.labels", segmentation.get("labels"))):
        if text is not None and "\x00" in text:
            raise FormatError(
                f"a file path cannot contain a NUL character, got {short(text)}", path=path, field=f"{where}.{name}"
            )
    return MapRef(
        path=_resolve(item.get("path"), folder),
        sha256=item.get("sha256"),
        size=None if size is None else tuple(size),
        segmentation_method=segmentation.get("method"),
        segmentation_params=segmentation.get("params", {}),
        labels_path=_resolve(segmentation.get("labels"), folder),
        segmentation_extra=_unknown(segmentation, SEGMENTATION_KEYS),
        extra=_unknown(item, MAP_KEYS),
    )


def _clique_from_json(item: dict) -> Clique:
    # Three keys are required; only a clique with more can have unknown ones.
    extra = {key: value for key, value in item.items() if key not in _CLIQUE_KEY_SET} if len(item) > 3 else {}
    return Clique._from_valid_json(item, extra)


_CLIQUE_KEY_SET = frozenset(CLIQUE_KEYS)


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


def _to_document(corr: Correspondences, folder: Path, *, cliques: list | None = None) -> dict:
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
        "cliques": [_clique_to_json(clique) for clique in corr.cliques] if cliques is None else cliques,
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
