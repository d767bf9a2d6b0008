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

A destination that exists and is not a regular file is never replaced: renaming a file
over ``/dev/null`` (as root) or over a named pipe would destroy the node and silently
turn it into a plain file. A character device (``/dev/null``, ``/dev/full``, a terminal)
or a pipe (a named pipe, or ``/dev/stdout`` when standard output is one: ``-o /dev/stdout |
jq``) is written through instead, in place, since writing to it is what the user asked for
and it has no old content to keep. A pipe is opened without waiting: when no process has it
open for reading, the save fails at once ("no process is reading the named pipe") rather
than hang until one comes. A folder, a socket (cannot be opened) or a block device (a disk:
never what a JSON or an image is meant for) is refused with an error naming it.

Every :class:`OSError` raised names the caller's path (``error.filename``), not the
hidden temporary file, whatever step failed (a missing folder, a read-only folder, a
full disk, a file-size limit), so a message of ``PATH: problem`` points at the file the
user gave.
"""

from __future__ import annotations

import contextlib
import errno
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
        If it is a character device (``/dev/null``) or a pipe with a reader, ``data`` is
        written to it in place (see the module's docstring).
    data : bytes-like
        The complete new content.

    Raises
    ------
    OSError
        The original error when the temporary file cannot be created, written,
        synced or renamed, with ``filename`` set to ``path``. The temporary file
        is removed first and an existing file at ``path`` is left untouched.
        Also raised, before anything is written, when ``path`` is a folder
        (:class:`IsADirectoryError`), a socket, a block device or a named pipe that no
        process is reading (``errno.ENXIO``).

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
    >>> atomic_write_bytes(folder, b"new")
    Traceback (most recent call last):
    ...
    IsADirectoryError: [Errno 21] is a folder, not a file: ...
    """
    payload = memoryview(data).cast("B")
    try:
        _write(Path(path), payload)
    except OSError as error:
        # The same object (callers may compare it), renamed after the user's path.
        error.filename, error.filename2 = os.fspath(path), None
        folder = os.path.dirname(os.fspath(path)) or "."
        if error.errno == errno.ENOENT and not os.path.isdir(folder):
            error.strerror = f"{error.strerror or 'No such file or directory'} (no folder {folder})"
        raise


def _write(target: Path, payload: memoryview) -> None:
    mode = _existing_mode(target)
    if mode is not None and not stat.S_ISREG(mode):
        if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
            _write_through(target, payload, stat.S_IFMT(mode))
            return
        raise _refusal(mode)
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


def _existing_mode(target: Path) -> int | None:
    """``st_mode`` of what ``target`` names (links followed), None when nothing is there yet."""
    try:
        return os.stat(target).st_mode
    except (OSError, ValueError):
        # Missing, or a problem the save itself reports (a dangling link is created through).
        return None


def _refusal(mode: int) -> OSError:
    if stat.S_ISDIR(mode):
        return IsADirectoryError(errno.EISDIR, "is a folder, not a file: nothing was written")
    if stat.S_ISSOCK(mode):
        kind = "a socket"
    elif stat.S_ISFIFO(mode):  # only when one was swapped in for a device during the save
        kind = "a named pipe (FIFO)"
    elif stat.S_ISBLK(mode):
        kind = "a block device (a disk)"
    else:
        kind = "a special file"
    return OSError(errno.EINVAL, f"is {kind}, not a regular file: refusing to write to it or replace it")


def _write_through(target: Path, payload: memoryview, kind: int) -> None:
    """Write ``payload`` in place to ``target``, a character device or a pipe (``kind``, the
    ``S_IFMT`` bits its stat gave): nothing to keep, nothing to sync."""
    # Non-blocking open: a pipe with no reader fails at once (ENXIO) instead of waiting for one,
    # and so does a pipe swapped in for a device since the stat. No O_CREAT: if the node went
    # away, nothing is created in its place.
    flags = os.O_WRONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
    try:
        descriptor = os.open(target, flags)
    except OSError as error:
        if error.errno == errno.ENXIO and kind == stat.S_IFIFO:
            raise OSError(errno.ENXIO, "no process is reading the named pipe: nothing was written") from None
        raise
    try:
        mode = os.fstat(descriptor).st_mode
        if stat.S_IFMT(mode) != kind:
            # Replaced between the stat and the open: refuse rather than write a file in place.
            raise _refusal(mode) if not stat.S_ISREG(mode) else OSError(errno.EAGAIN, "changed while being saved")
        # Blocking again (fcntl F_SETFL): a reader slower than the save makes it wait, not fail
        # with EAGAIN once the pipe's buffer is full.
        os.set_blocking(descriptor, True)
        view = payload
        while view:
            written = os.write(descriptor, view)
            view = view[written:]
    finally:
        os.close(descriptor)


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
    raise FileExistsError(errno.EEXIST, f"could not create a temporary file in {directory}")


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
