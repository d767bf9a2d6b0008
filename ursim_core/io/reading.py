"""Bounded reads of regular files: every loader of the project reads its input through here.

A map, a ROS YAML file or a correspondence file is read only when it is a regular file of a
size within the caller's limit, checked with ``stat`` before the first byte: a named pipe
(which would block the reader forever), a device such as ``/dev/zero`` (endless), a folder, a
symbolic link loop or a dangling link each get their own message, and a multi-gigabyte sparse
file is refused from its size. The file is opened non-blocking and checked again after the
open, so swapping a pipe in between does not hang either.

Text and JSON read through here too (:func:`decode_text`, :func:`parse_json`,
:func:`read_json_file`): UTF-8 with or without a byte-order mark, and JSON whose nesting or
numbers would make ``json.loads`` or the next ``float()`` raise (``RecursionError``, an
integer of thousands of digits, ``NaN``, ``1e999``) refused with a message.

Errors are the caller's :class:`~ursim_core.errors.UrsimError` subclass, naming the file.
"""

from __future__ import annotations

import errno
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ursim_core.errors import UrsimError, file_not_found

__all__ = [
    "check_regular_file",
    "read_regular_file",
    "describe_size",
    "decode_text",
    "parse_json",
    "read_json_file",
    "MAX_JSON_DEPTH",
]

_CHUNK = 1 << 20


def describe_size(n_bytes: int) -> str:
    """``n_bytes`` in words, e.g. ``'3221225472 bytes (3.0 GiB)'``.

    Examples
    --------
    >>> describe_size(3 * 1024**3)
    '3221225472 bytes (3.0 GiB)'
    >>> describe_size(12)
    '12 bytes'
    """
    for unit, size in (("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if n_bytes >= size:
            return f"{n_bytes} bytes ({n_bytes / size:.1f} {unit})"
    return f"{n_bytes} bytes"


def _kind(mode: int) -> str | None:
    """Why a file of this ``st_mode`` is not readable as a regular file, or None if it is."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "is a directory"
    if stat.S_ISFIFO(mode):
        return "is a named pipe (FIFO), not a regular file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "is a device, not a regular file"
    if stat.S_ISSOCK(mode):
        return "is a socket, not a regular file"
    return "is not a regular file"


def check_regular_file(path: Path, *, error: type[UrsimError], what: str) -> os.stat_result:
    """``os.stat(path)`` of a regular file, or ``error`` saying what ``path`` is instead.

    Parameters
    ----------
    path : Path
        The file (symbolic links are followed).
    error : UrsimError subclass
        Raised, with ``path=path``.
    what : str
        What the file should be, for the messages ("map file", "correspondence file").

    Examples
    --------
    >>> from ursim_core.errors import MapError
    >>> try:
    ...     check_regular_file(Path("/"), error=MapError, what="map file")
    ... except MapError as problem:
    ...     print(problem)
    /: is a directory, not a map file
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        # Also a FileNotFoundError (file_not_found): ``except FileNotFoundError`` catches it too.
        if os.path.islink(path):
            raise file_not_found(
                error, f"dangling symbolic link to {os.readlink(path)} (no such file)", path=path
            ) from None
        raise file_not_found(error, "file not found", path=path) from None
    except ValueError:
        # os.stat refuses embedded NUL characters before asking the system.
        raise error("the file name contains a NUL character", path=path) from None
    except UnicodeEncodeError:
        raise error("the file name cannot be encoded for this file system", path=path) from None
    except OSError as problem:
        if problem.errno == errno.ELOOP:
            raise error("symbolic link loop (a link that points back to itself)", path=path) from None
        if problem.errno == errno.ENAMETOOLONG:
            raise error("file name too long", path=path) from None
        raise error(f"cannot read the file: {problem.strerror or problem}", path=path) from None
    kind = _kind(info.st_mode)
    if kind == "is a directory":
        raise error(f"is a directory, not a {what}", path=path)
    if kind is not None:
        raise error(kind, path=path)
    return info


def read_regular_file(
    path: Path,
    *,
    max_bytes: int,
    error: type[UrsimError],
    what: str,
    empty_problem: str | None = None,
    limit_reason: str = "",
    check_head=None,
) -> bytes:
    """The whole content of a regular file of at most ``max_bytes`` bytes.

    Parameters
    ----------
    path : Path
        The file.
    max_bytes : int
        Largest size accepted; a larger file is refused from its ``stat`` size, before reading.
    error : UrsimError subclass
        Raised for every problem, with ``path=path``.
    what : str
        What the file should be, for the messages.
    empty_problem : str, optional
        The message for an empty file; empty files are returned as ``b""`` when None.
    limit_reason : str, optional
        Appended to the size message, e.g. ``" (an image of at most max_pixels=... pixels)"``.
    check_head : callable, optional
        ``check_head(head, complete)`` is called with the first MiB before the rest is read
        (``complete`` when that is the whole file); it raises to refuse the file early, e.g.
        from an image header that declares too many pixels.

    Raises
    ------
    UrsimError
        Of class ``error``: missing, not a regular file, too large, unreadable, or empty.
    """
    info = check_regular_file(path, error=error, what=what)
    _check_size(info.st_size, path, max_bytes=max_bytes, error=error, what=what, limit_reason=limit_reason)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        descriptor = os.open(path, flags)
    except OSError as problem:
        raise error(f"cannot read the file: {problem.strerror or problem}", path=path) from None
    try:
        # The file may have been replaced between stat and open: check what was opened.
        opened = os.fstat(descriptor)
        kind = _kind(opened.st_mode)
        if kind is not None:
            raise error(kind, path=path)
        _check_size(opened.st_size, path, max_bytes=max_bytes, error=error, what=what, limit_reason=limit_reason)
        chunks = []
        total = 0
        while True:
            chunk = os.read(descriptor, min(_CHUNK, max_bytes + 1 - total))
            if not chunk:
                break
            if check_head is not None and not chunks:
                check_head(chunk, len(chunk) >= opened.st_size)
            chunks.append(chunk)
            total += len(chunk)
            if total > max_bytes:
                # It grew while being read.
                _check_size(total, path, max_bytes=max_bytes, error=error, what=what, limit_reason=limit_reason)
    except OSError as problem:
        raise error(f"cannot read the file: {problem.strerror or problem}", path=path) from None
    finally:
        os.close(descriptor)
    data = b"".join(chunks)
    if not data and empty_problem is not None:
        raise error(empty_problem, path=path)
    return data


def _check_size(size: int, path: Path, *, max_bytes: int, error, what: str, limit_reason: str) -> None:
    if size > max_bytes:
        raise error(
            f"file is {describe_size(size)}, more than the {describe_size(max_bytes)} accepted for a {what}"
            f"{limit_reason}",
            path=path,
        )


# Deeper than any JSON file the project reads by far (a points list is 2 levels, a merge model
# 4, a correspondence file 6), shallow enough that no recursive step after parsing (validation,
# json.dumps on the next save) comes near Python's recursion limit.
MAX_JSON_DEPTH = 64
# The most digits an integer may have and still convert to a float (10**308 < 1.8e308):
# every number the project reads ends up as one.
_MAX_INT_DIGITS = 308


def decode_text(raw: bytes, path: Path, *, error: type[UrsimError], what: str) -> str:
    """``raw`` as UTF-8 text, a leading byte-order mark dropped (Excel's "CSV UTF-8", Notepad).

    Examples
    --------
    >>> from ursim_core.errors import FormatError
    >>> decode_text(b"\\xef\\xbb\\xbfsketch,metric", Path("p.csv"), error=FormatError, what="manifest")
    'sketch,metric'
    """
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as problem:
        line = raw[: problem.start].count(b"\n") + 1
        raise error(f"line {line}: not UTF-8 text (byte {problem.start}): not a {what}", path=path) from None


class _JsonRefused(ValueError):
    """A JSON value the project refuses (its text says why); a ValueError so json stops parsing."""


def _refuse_out_of_range(text: str):
    if text.lstrip("-").isdigit():
        raise _JsonRefused(f"an integer of {len(text.lstrip('-'))} digits is too large (at most {_MAX_INT_DIGITS})")
    shown = text if len(text) <= 40 else text[:37] + "..."
    raise _JsonRefused(f"the number {shown} is out of range")


def _refuse_constant(name: str):
    raise _JsonRefused(f"{name} is not a JSON number")


def _refuse_duplicate_keys(pairs: list) -> dict:
    # json.loads keeps the last of two equal keys: a hand-edited file would lose data unseen.
    result = dict(pairs)
    if len(result) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                shown = repr(key) if len(key) <= 60 else repr(key[:57]) + "..."
                raise _JsonRefused(f"key {shown} appears twice in one object")
            seen.add(key)
    return result


def parse_json(
    data: bytes | str,
    path: Path,
    *,
    error: type[UrsimError],
    what: str,
    max_depth: int | None = MAX_JSON_DEPTH,
    out_of_range: Callable[[str], Any] | None = None,
):
    """The JSON document in ``data``, or ``error`` naming ``path`` and what is wrong.

    ``json.loads`` alone keeps the last of two equal keys, raises ``RecursionError`` for
    arrays nested a few thousand deep and ``ValueError`` for an integer of more than 4300
    digits, and lets through ``NaN``, ``Infinity``, ``1e999`` and integers too large for a
    float (``OverflowError`` at the first ``float()``). Each of these is refused here, as is
    nesting deeper than ``max_depth``, so whatever is returned can be used and written again.
    This is the one JSON reader of the project: points files, manifests, merge models and
    correspondence files.

    Parameters
    ----------
    data : bytes or str
        The file's content; bytes are decoded as UTF-8 (a byte-order mark allowed).
    path : Path
        The file, for the messages.
    error : UrsimError subclass
        Raised for every problem, with ``path=path``.
    what : str
        What the file should be, for the messages ("points file").
    max_depth : int or None, optional
        Most levels of arrays and objects inside each other; None leaves the depth to the
        caller, which walks the document anyway (the correspondence codec, to name the field).
    out_of_range : callable, optional
        Given the text of a number that is not a finite float (``1e999``) or an integer of
        more than 308 digits (too large for the float every number becomes), returns the value
        to keep in its place: a placeholder the caller refuses later with the field's path. By
        default such numbers are refused here.

    Examples
    --------
    >>> from ursim_core.errors import FormatError
    >>> parse_json(b'{"points": [[1, 2]]}', Path("p.json"), error=FormatError, what="points file")
    {'points': [[1, 2]]}
    >>> parse_json("[1e999]", Path("p.json"), error=FormatError, what="points file")
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: p.json: not JSON for a points file: the number 1e999 is out of range
    >>> parse_json('{"a": 1, "a": 2}', Path("p.json"), error=FormatError, what="points file")
    Traceback (most recent call last):
    ...
    ursim_core.errors.FormatError: p.json: not JSON for a points file: key 'a' appears twice in one object
    """
    import json

    text = decode_text(data, path, error=error, what=what) if isinstance(data, (bytes, bytearray)) else data
    if text.startswith("\ufeff"):
        text = text[1:]
    keep = out_of_range or _refuse_out_of_range

    def parse_float(number: str):
        value = float(number)
        return value if value not in (_INF, -_INF) else keep(number)

    hooks = {"object_pairs_hook": _refuse_duplicate_keys, "parse_constant": _refuse_constant}
    try:
        if _LONG_DIGITS.search(text) is None:
            document = json.loads(text, parse_float=parse_float, **hooks)
        else:
            # A run of more digits than a float's integers have (rare; C-speed to find): every
            # integer through Python, those too large for a float kept by the caller's rule.
            def parse_int(number: str):
                return keep(number) if len(number.lstrip("-")) > _MAX_INT_DIGITS else int(number)

            document = json.loads(text, parse_float=parse_float, parse_int=parse_int, **hooks)
    except json.JSONDecodeError as problem:
        raise error(f"not JSON: {problem.msg} (line {problem.lineno}, column {problem.colno})", path=path) from None
    except RecursionError:
        raise error(
            f"not JSON for a {what}: nested deeper than {max_depth or MAX_JSON_DEPTH} levels", path=path
        ) from None
    except (ValueError, OverflowError) as problem:
        raise error(f"not JSON for a {what}: {problem}", path=path) from None
    if max_depth is not None:
        _check_depth(document, path, error=error, what=what, max_depth=max_depth)
    return document


_INF = float("inf")
_LONG_DIGITS = re.compile(rf"\d{{{_MAX_INT_DIGITS + 1}}}")


def _check_depth(document, path: Path, *, error, what: str, max_depth: int) -> None:
    # An explicit stack: a check of depth must not itself recurse.
    stack = [(document, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            if depth > max_depth:
                raise error(f"not JSON for a {what}: nested deeper than {max_depth} levels", path=path)
            stack.extend((item, depth + 1) for item in (value.values() if isinstance(value, dict) else value))


def read_json_file(path: Path, *, max_bytes: int, error: type[UrsimError], what: str, max_depth: int = MAX_JSON_DEPTH):
    """The JSON document of a regular file of at most ``max_bytes``: :func:`read_regular_file`,
    then :func:`parse_json`; every problem is ``error`` naming ``path``."""
    raw = read_regular_file(
        path, max_bytes=max_bytes, error=error, what=what, empty_problem=f"empty file: not a {what}"
    )
    return parse_json(raw, path, error=error, what=what, max_depth=max_depth)
