"""Reading and writing correspondence files safely: the parts the JSON and .dat codecs share.

- :func:`read_file_bytes`: a bounded read of a regular file (no pipe, device or multi-GB file).
- :func:`write_guarded`: the save every codec goes through. It refuses to write onto one of the
  maps or label images the correspondences refer to (that would destroy the image), and, when
  given the digest the file had when it was loaded, refuses to overwrite a file that changed
  on disk since (another session saved it): :class:`~ursim_core.errors.FileChangedError`,
  which a GUI turns into a question. The write itself is atomic, and its SHA-256 is returned
  so the caller can pass it to the next save.
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import os
from collections.abc import Iterator
from pathlib import Path

from ursim_core.correspondences.values import Correspondences
from ursim_core.errors import FileChangedError, FormatError, SaveRefusedError
from ursim_core.io.atomic import atomic_write_bytes
from ursim_core.io.reading import read_regular_file

__all__ = ["MAX_FILE_BYTES", "read_file_bytes", "write_guarded", "sha256_of_file", "paused_garbage_collection"]

# 100k cliques take about 20 MB of JSON; this bounds memory, not any real file.
MAX_FILE_BYTES = 1024**3


def read_file_bytes(path: Path, *, what: str) -> bytes:
    """The file's bytes, or a FormatError naming the file and why it cannot be read."""
    return read_regular_file(path, max_bytes=MAX_FILE_BYTES, error=FormatError, what=what)


@contextlib.contextmanager
def paused_garbage_collection() -> Iterator[None]:
    """No cyclic garbage collection inside the block (restored after, also on error).

    Parsing a big file makes hundreds of thousands of lists, dicts and tuples, none of which
    form cycles; each allocation burst triggers a full collection that walks all of them
    again, which made loading 100k cliques 2.5x slower (3.3 s of CPU instead of 1.3 s).
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def sha256_of_file(path: Path) -> str | None:
    """Hex SHA-256 of the file at ``path``, None when there is no regular file there."""
    digest = hashlib.sha256()
    if not os.path.isfile(path):
        return None  # checked first: opening a named pipe would block
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        return None
    return digest.hexdigest()


def _real(path: Path | str) -> str:
    return os.path.normcase(os.path.realpath(path))


def _check_name(target: Path) -> None:
    # The system would refuse these names with ValueError / UnicodeEncodeError, which a caller
    # catching OSError (an autosave) would not expect.
    text = str(target)
    if "\x00" in text:
        raise SaveRefusedError("the file name contains a NUL character", path=target)
    try:
        os.fsencode(text)
    except UnicodeEncodeError:
        raise SaveRefusedError(
            "the file name holds characters no file system name can (lone surrogates)", path=target
        ) from None


def _check_not_a_map(corr: Correspondences, target: Path) -> None:
    real_target = _real(target)
    for side, ref in (("sketch", corr.sketch), ("metric", corr.metric)):
        for what, path in (("map", ref.path), ("label image", ref.labels_path)):
            if path is not None and _real(path) == real_target:
                raise SaveRefusedError(
                    f"refusing to save the correspondences onto the {side} {what} they refer to "
                    "(it would be overwritten): choose another file name",
                    path=target,
                )


def write_guarded(corr: Correspondences, target: Path, data: bytes, *, expected_sha256: str | None, what: str) -> str:
    """Write ``data`` to ``target`` atomically, unless that would lose data; return its SHA-256.

    Parameters
    ----------
    corr : Correspondences
        What ``data`` encodes (its maps must not be overwritten).
    target : Path
        The destination.
    data : bytes
        The complete new file.
    expected_sha256 : str or None
        The digest ``target`` had when it was loaded (``Correspondences.loaded_sha256``).
        When given and ``target`` now holds other bytes, nothing is written. A missing
        ``target`` (deleted since) is written.
    what : str
        The kind of file, for messages.

    Raises
    ------
    SaveRefusedError
        ``target`` is one of the maps or label images of ``corr``.
    FileChangedError
        ``target`` changed on disk since it was loaded.
    OSError
        Writing failed; the old file is untouched.
    """
    _check_name(target)
    _check_not_a_map(corr, target)
    if expected_sha256 is not None:
        actual = sha256_of_file(target)
        if actual is not None and actual != expected_sha256.lower():
            raise FileChangedError(
                f"the {what} changed on disk since it was loaded (another session or program saved "
                "it); saving now would drop that change: reload it, or save again to overwrite",
                path=target,
                expected_sha256=expected_sha256,
                actual_sha256=actual,
            )
    atomic_write_bytes(target, data)
    return hashlib.sha256(data).hexdigest()
