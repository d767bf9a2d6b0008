"""One exception family for every input problem the core reports, and one warning family.

Each error names the file (when there is one) and the problem, so the CLI
can print ``str(error)`` as a single line and the GUI can show it in a dialog.
Warnings (:class:`UrsimWarning`) report something a user should know that does
not stop the work: a map that changed since its correspondences were made,
region ids recomputed from their points.

A missing file is both the core's error and a :class:`FileNotFoundError`
(:class:`UrsimFileNotFoundError` and its subclasses, made by :func:`file_not_found`), so
``except MapError`` and ``except FileNotFoundError`` both catch a map that is not there.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

__all__ = [
    "UrsimError",
    "MapError",
    "SegmentationError",
    "FormatError",
    "ParameterError",
    "SaveRefusedError",
    "FileChangedError",
    "UrsimFileNotFoundError",
    "MapFileNotFoundError",
    "FormatFileNotFoundError",
    "SegmentationFileNotFoundError",
    "file_not_found",
    "UrsimWarning",
    "MapChangedWarning",
    "RegionsRecomputedWarning",
]


class UrsimError(Exception):
    """Base class of every error raised on bad input.

    Parameters
    ----------
    problem : str
        What is wrong, in words a user understands.
    path : str or Path, optional
        The file the problem is about.
    field : str, optional
        The field inside the file (JSON pointer-like, e.g. ``cliques[2].sketch_points``).

    Examples
    --------
    >>> str(MapError("not an image", path="a.txt"))
    'a.txt: not an image'
    """

    def __init__(self, problem: str, *, path: str | Path | None = None, field: str | None = None):
        self.problem = problem
        self.path = None if path is None else Path(path)
        self.field = field
        super().__init__(self._message())

    def _message(self) -> str:
        where = ""
        if self.path is not None:
            where = f"{self.path}: "
        if self.field:
            where += f"field '{self.field}': "
        # One line, whatever the problem text holds: the CLI prints it as the whole message.
        return " ".join(f"{where}{self.problem}".splitlines())


class MapError(UrsimError):
    """A map file cannot be read or holds no usable map."""


class SegmentationError(UrsimError):
    """A label image or segmentation input is unusable."""


class FormatError(UrsimError):
    """A correspondence file (JSON or .dat) is malformed or of an unknown version."""


class ParameterError(UrsimError):
    """A parameter (CLI option, preset name, parameter value) is invalid."""


class SaveRefusedError(UrsimError):
    """A save was refused because it would lose data; nothing was written.

    For example saving correspondences onto the path of one of their map images.
    """


class FileChangedError(SaveRefusedError):
    """The file changed on disk since it was loaded: saving would drop the other change.

    Raised by the savers when given ``expected_sha256`` (the digest the file had when it
    was loaded) and the file now holds other bytes. A GUI turns it into a question
    ("overwrite, or reload?"); saving again without ``expected_sha256`` overwrites.

    Attributes
    ----------
    expected_sha256, actual_sha256 : str
        The digest the caller loaded and the digest on disk now.
    """

    def __init__(self, problem: str, *, path=None, field=None, expected_sha256: str = "", actual_sha256: str = ""):
        self.expected_sha256 = expected_sha256
        self.actual_sha256 = actual_sha256
        super().__init__(problem, path=path, field=field)


class UrsimFileNotFoundError(UrsimError, FileNotFoundError):
    """A file that an input names does not exist: a :class:`UrsimError` and a :class:`FileNotFoundError`.

    Like the error the system raises, it has ``errno`` (``errno.ENOENT``), ``strerror`` and
    ``filename`` (the missing file); ``str()`` is the one-line message of every
    :class:`UrsimError`. Raise the subclass of the error type the caller expects (e.g.
    :class:`MapFileNotFoundError` where a :class:`MapError` is documented), through
    :func:`file_not_found`.

    Parameters
    ----------
    problem, path, field
        As for :class:`UrsimError`.
    filename : str or Path, optional
        The missing file, when it is not ``path`` (a ROS YAML's ``image``); ``path`` by default.

    Examples
    --------
    >>> error = MapFileNotFoundError("file not found", path="maps/a.png")
    >>> isinstance(error, MapError), isinstance(error, FileNotFoundError), error.errno == errno.ENOENT
    (True, True, True)
    >>> str(error), error.filename
    ('maps/a.png: file not found', 'maps/a.png')
    """

    def __init__(
        self,
        problem: str,
        *,
        path: str | Path | None = None,
        field: str | None = None,
        filename: str | Path | None = None,
    ):
        # UrsimError.__init__ ends in OSError.__init__(message): args stay (message,), as for
        # every UrsimError, and no errno is parsed from them.
        super().__init__(problem, path=path, field=field)
        missing = filename if filename is not None else path
        self.errno = errno.ENOENT
        self.strerror = os.strerror(errno.ENOENT)
        self.filename = None if missing is None else str(missing)

    def __str__(self) -> str:
        # OSError's str would be "[Errno 2] ...: 'file'"; the core's errors print one line of their own.
        return self.args[0] if self.args else ""

    def __reduce__(self):
        # OSError pickles (errno, strerror, filename) as the constructor's arguments, which this
        # constructor does not take: rebuild from the keywords (errors cross process pools).
        return (_rebuild_not_found, (type(self), self.problem, self.path, self.field, self.filename))


class MapFileNotFoundError(UrsimFileNotFoundError, MapError):
    """A map file (image, ROS YAML or the image it names) does not exist."""


class FormatFileNotFoundError(UrsimFileNotFoundError, FormatError):
    """A file read as a :class:`FormatError` (a correspondence file, points, waypoints, a
    manifest) does not exist."""


class SegmentationFileNotFoundError(UrsimFileNotFoundError, SegmentationError):
    """A file read as a :class:`SegmentationError` (a label image, a learned merge model) does not exist."""


def _rebuild_not_found(cls, problem, path, field, filename):
    return cls(problem, path=path, field=field, filename=filename)


#: The not-found class of each error type (see :func:`file_not_found`).
_NOT_FOUND = {
    UrsimError: UrsimFileNotFoundError,
    MapError: MapFileNotFoundError,
    FormatError: FormatFileNotFoundError,
    SegmentationError: SegmentationFileNotFoundError,
}


def file_not_found(
    error: type[UrsimError],
    problem: str,
    *,
    path: str | Path | None = None,
    field: str | None = None,
    filename: str | Path | None = None,
) -> UrsimError:
    """The error to raise for a missing file where errors of type ``error`` are documented.

    An instance of ``error`` that is also a :class:`FileNotFoundError` when ``error`` is
    :class:`UrsimError`, :class:`MapError`, :class:`FormatError` or :class:`SegmentationError`
    (or one of their not-found classes); for any other type, a plain ``error``, since a class
    made on the fly could not be pickled nor caught by name.

    Parameters
    ----------
    error : UrsimError subclass
        The type the caller catches (e.g. the ``error`` argument of a reader).
    problem, path, field, filename
        As for :class:`UrsimFileNotFoundError`.

    Examples
    --------
    >>> found = file_not_found(FormatError, "file not found", path="corr.json")
    >>> type(found).__name__, isinstance(found, FileNotFoundError)
    ('FormatFileNotFoundError', True)
    >>> type(file_not_found(ParameterError, "file not found", path="p.json")).__name__
    'ParameterError'
    """
    if issubclass(error, UrsimFileNotFoundError):
        return error(problem, path=path, field=field, filename=filename)
    not_found = _NOT_FOUND.get(error)
    if not_found is None:
        return error(problem, path=path, field=field)
    return not_found(problem, path=path, field=field, filename=filename)


class UrsimWarning(UserWarning):
    """Base class of the warnings the core emits (``warnings.warn``)."""


class MapChangedWarning(UrsimWarning):
    """A map's SHA-256 differs from the one its correspondence file recorded."""


class RegionsRecomputedWarning(UrsimWarning):
    """Region ids stored with cliques disagreed with their points and were recomputed."""
