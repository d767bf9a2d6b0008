"""One exception family for every input problem the core reports, and one warning family.

Each error names the file (when there is one) and the problem, so the CLI
can print ``str(error)`` as a single line and the GUI can show it in a dialog.
Warnings (:class:`UrsimWarning`) report something a user should know that does
not stop the work: a map that changed since its correspondences were made,
region ids recomputed from their points.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "UrsimError",
    "MapError",
    "SegmentationError",
    "FormatError",
    "ParameterError",
    "SaveRefusedError",
    "FileChangedError",
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


class UrsimWarning(UserWarning):
    """Base class of the warnings the core emits (``warnings.warn``)."""


class MapChangedWarning(UrsimWarning):
    """A map's SHA-256 differs from the one its correspondence file recorded."""


class RegionsRecomputedWarning(UrsimWarning):
    """Region ids stored with cliques disagreed with their points and were recomputed."""
