"""Atomic file writing: a reader sees the old file or the new one, never half of one.

Every file URSIM Studio writes (correspondences, label images, reports) goes
through these two functions, so a crash, a full disk or a killed process in the
middle of a save leaves the previous version intact.

The new content is written to a temporary file in the *same* directory (so the
final rename never crosses a file system), flushed and fsync'ed, then moved over
the target with :func:`os.replace`, which is atomic on POSIX and Windows.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from pathlib import Path

__all__ = ["atomic_write_bytes", "atomic_write_text"]

_TEMP_ATTEMPTS = 100


def atomic_write_bytes(path: str | os.PathLike, data: bytes | bytearray | memoryview) -> None:
    """Write ``data`` to ``path`` atomically.

    Parameters
    ----------
    path : str or path-like
        The file to create or replace. Its directory must exist. If it is a
        symbolic link, the file it points to is replaced (the link is kept).
    data : bytes-like
        The complete new content.

    Raises
    ------
    OSError
        The original error when the temporary file cannot be created, written,
        synced or renamed. The temporary file is removed first and an existing
        file at ``path`` is left untouched.

    Notes
    -----
    An existing file keeps its permission bits; a new file gets the usual
    ``0o666 & ~umask``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> atomic_write_bytes(folder / "a.bin", b"new")
    >>> (folder / "a.bin").read_bytes()
    b'new'
    """
    payload = memoryview(data).cast("B")
    target = Path(path)
    if target.is_symlink():
        # Replacing the link itself would silently detach it from its file.
        target = Path(os.path.realpath(target))
    directory = target.parent
    descriptor, temp_path = _create_temp_file(directory, target.name)
    try:
        try:
            handle = os.fdopen(descriptor, "wb")
        except BaseException:
            os.close(descriptor)
            raise
        with handle:
            handle.write(payload)
            handle.flush()
            os.fsync(handle.fileno())
        _copy_permission_bits(target, temp_path)
        os.replace(temp_path, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp_path)
        raise
    _fsync_directory(directory)


def atomic_write_text(path: str | os.PathLike, text: str, *, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically, exactly as given.

    No newline translation happens on any platform, so the same text gives the
    same bytes on Linux, macOS and Windows.

    Parameters
    ----------
    path : str or path-like
        The file to create or replace (see :func:`atomic_write_bytes`).
    text : str
        The complete new content.
    encoding : str, optional
        Text encoding, UTF-8 by default.

    Raises
    ------
    OSError
        As :func:`atomic_write_bytes`.
    UnicodeEncodeError
        When ``text`` cannot be encoded; nothing is written then.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> atomic_write_text(folder / "a.txt", "line 1\\nline 2\\n")
    >>> (folder / "a.txt").read_bytes()
    b'line 1\\nline 2\\n'
    """
    atomic_write_bytes(path, text.encode(encoding))


def _create_temp_file(directory: Path, name: str) -> tuple[int, Path]:
    """Create a new, empty, uniquely named file beside the target."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(_TEMP_ATTEMPTS):
        # A dot prefix hides the file in listings while it exists; the random
        # part lets two writers of the same target not collide.
        candidate = directory / f".{name}.{secrets.token_hex(4)}.tmp"
        try:
            # Mode 0o666 lets the umask decide, like an ordinary open().
            return os.open(candidate, flags, 0o666), candidate
        except FileExistsError:
            continue
    raise FileExistsError(f"could not create a temporary file in {directory}")


def _copy_permission_bits(source: Path, destination: Path) -> None:
    try:
        mode = stat.S_IMODE(os.stat(source).st_mode)
    except OSError:
        return
    # Permission bits are a courtesy; a file system that refuses chmod must not
    # make the save fail.
    with contextlib.suppress(OSError):
        os.chmod(destination, mode)


def _fsync_directory(directory: Path) -> None:
    # Makes the rename itself durable on POSIX; Windows cannot open a directory
    # and some file systems refuse fsync on one, neither of which is an error.
    try:
        descriptor = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)
