"""Bounded reads of regular files: every loader of the project reads its input through here.

A map, a ROS YAML file or a correspondence file is read only when it is a regular file of a
size within the caller's limit, checked with ``stat`` before the first byte: a named pipe
(which would block the reader forever), a device such as ``/dev/zero`` (endless), a folder, a
symbolic link loop or a dangling link each get their own message, and a multi-gigabyte sparse
file is refused from its size. The file is opened non-blocking and checked again after the
open, so swapping a pipe in between does not hang either.

Errors are the caller's :class:`~ursim_core.errors.UrsimError` subclass, naming the file.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from ursim_core.errors import UrsimError

__all__ = ["check_regular_file", "read_regular_file", "describe_size"]

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
        if os.path.islink(path):
            raise error(f"dangling symbolic link to {os.readlink(path)} (no such file)", path=path) from None
        raise error("file not found", path=path) from None
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
