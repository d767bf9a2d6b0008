"""Atomic file writing: a reader sees the old file or the new one, never half of one.

Every file URSIM Studio writes (correspondences, label images, reports) goes
through these two functions, so a crash, a full disk or a killed process in the
middle of a save leaves the previous version intact.

The new content is written to a temporary file in the *same* directory (so the
final rename never crosses a file system), flushed and fsync'ed, then moved over
the target with :func:`os.replace`, which is atomic on POSIX and Windows.

A writer killed between the two leaves its hidden ``.NAME.xxxxxxxx.tmp`` behind.
The next save of ``NAME`` removes such files of our own pattern once they are
older than :data:`STALE_TEMP_SECONDS` (no live save takes minutes), so repeated
crashes cannot fill a disk.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import stat
import threading
import time
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_write_bytes", "atomic_write_text", "scratch_directory", "sync_directory", "STALE_TEMP_SECONDS"]

_TEMP_ATTEMPTS = 100
# A temporary file this old belongs to a writer that died: a save takes seconds at most.
STALE_TEMP_SECONDS = 300


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
    _remove_stale_temp_files(directory, target.name)
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
    if not _is_scratch(directory):
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


# Directories of :func:`scratch_directory` blocks, by the string of their path; several threads
# may save into one at once (``ursim match`` encodes its images on two).
_scratch: dict[str, int] = {}
_scratch_lock = threading.Lock()


@contextlib.contextmanager
def scratch_directory(directory: str | os.PathLike) -> Iterator[None]:
    """Within the block, saves into ``directory`` do not fsync the directory itself.

    For a private folder whose files are moved elsewhere when it is complete (the staged
    outputs of the command line): each file's content is still synced before its rename, but
    the names in a folder that is about to be emptied and removed need not reach the disk,
    and each of those syncs cost about 5 ms on the project's machine. Whoever moves the files
    syncs their final folder.
    """
    key = str(Path(directory))
    with _scratch_lock:
        _scratch[key] = _scratch.get(key, 0) + 1
    try:
        yield
    finally:
        with _scratch_lock:
            _scratch[key] -= 1
            if not _scratch[key]:
                del _scratch[key]


def _is_scratch(directory: Path) -> bool:
    return bool(_scratch) and str(directory) in _scratch


def sync_directory(directory: str | os.PathLike) -> None:
    """Make the names in ``directory`` durable (renames into it); a no-op where unsupported."""
    _fsync_directory(Path(directory))


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


def _remove_stale_temp_files(directory: Path, name: str) -> None:
    """Delete ``.NAME.<8 hex>.tmp`` files older than STALE_TEMP_SECONDS: killed writers' leftovers."""
    pattern = re.compile(re.escape(f".{name}.") + r"[0-9a-f]{8}\.tmp\Z")
    deadline = time.time() - STALE_TEMP_SECONDS
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return  # cleaning is a courtesy; the save itself reports real problems
    for entry in entries:
        if not pattern.match(entry.name):
            continue
        with contextlib.suppress(OSError):
            if entry.is_file(follow_symlinks=False) and entry.stat(follow_symlinks=False).st_mtime < deadline:
                os.unlink(entry.path)


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
