"""One exception family for every input problem the core reports.

Each error names the file (when there is one) and the problem, so the CLI
can print ``str(error)`` as a single line and the GUI can show it in a dialog.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "UrsimError",
    "MapError",
    "SegmentationError",
    "FormatError",
    "ParameterError",
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
        return f"{where}{self.problem}"


class MapError(UrsimError):
    """A map file cannot be read or holds no usable map."""


class SegmentationError(UrsimError):
    """A label image or segmentation input is unusable."""


class FormatError(UrsimError):
    """A correspondence file (JSON or .dat) is malformed or of an unknown version."""


class ParameterError(UrsimError):
    """A parameter (CLI option, preset name, parameter value) is invalid."""
