"""The sketch's known orientation: a turn (degrees counter-clockwise) and a mirror, or unknown.

Qt-free. The view shows the sketch turned this way (its points stay in the original
image's pixel frame: only the view's transform changes) and the matcher is told the
same through ``MatchConfig(orientation=..., mirrored=...)`` when the core's MatchConfig
has those fields.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

__all__ = ["SketchOrientation"]


@dataclass(frozen=True)
class SketchOrientation:
    """``angle`` in degrees counter-clockwise, applied after the mirror; None = unknown.

    Examples
    --------
    >>> SketchOrientation().turned(90).turned(300).angle
    30.0
    >>> SketchOrientation(angle=90).match_options({"orientation", "mirrored"})
    {'orientation': 90.0, 'mirrored': False}
    """

    angle: float | None = None
    mirrored: bool = False

    @property
    def known(self) -> bool:
        return self.angle is not None

    def turned(self, degrees: float) -> SketchOrientation:
        """Turned ``degrees`` more counter-clockwise (an unknown orientation starts upright)."""
        return dataclasses.replace(self, angle=float(((self.angle or 0.0) + degrees) % 360.0))

    def at(self, degrees: float) -> SketchOrientation:
        return dataclasses.replace(self, angle=float(degrees % 360.0))

    def with_mirror(self, mirrored: bool) -> SketchOrientation:
        angle = self.angle if self.angle is not None else 0.0
        return dataclasses.replace(self, angle=angle, mirrored=bool(mirrored))

    def match_options(self, fields) -> dict:
        """Keyword arguments for ``MatchConfig`` given its field names (none it lacks)."""
        options = {}
        if "orientation" in fields:
            options["orientation"] = "any" if self.angle is None else float(self.angle)
        if "mirrored" in fields:
            options["mirrored"] = None if self.angle is None and not self.mirrored else bool(self.mirrored)
        return options

    def describe(self) -> str:
        """The orientation in words.

        Examples
        --------
        >>> SketchOrientation().describe(), SketchOrientation(angle=0).describe()
        ('unknown', 'upright')
        >>> SketchOrientation(angle=0, mirrored=True).describe(), SketchOrientation(angle=90, mirrored=True).describe()
        ('mirrored', 'turned 90° counter-clockwise, mirrored')
        """
        if not self.known:
            return "unknown"
        if self.angle == 0:
            return "mirrored" if self.mirrored else "upright"
        return f"turned {self.angle:g}° counter-clockwise" + (", mirrored" if self.mirrored else "")

    @classmethod
    def found_in(cls, result) -> SketchOrientation | None:
        """The orientation the matcher chose for ``result`` when it was not told one; else None.

        ``result`` is a ``MatchResult``: its ``orientation`` is the (degrees, mirrored) it laid the
        sketch in, the same convention as ``MatchConfig(orientation=, mirrored=)``, so telling the
        matcher this orientation asks it for the reading it found.

        Examples
        --------
        >>> from types import SimpleNamespace as Result
        >>> SketchOrientation.found_in(Result(config=Result(orientation="any"), orientation=(359.96, True)))
        SketchOrientation(angle=0.0, mirrored=True)
        >>> SketchOrientation.found_in(Result(config=Result(orientation=90.0), orientation=(90.0, False))) is None
        True
        """
        config = getattr(result, "config", None)
        if result is None or getattr(config, "orientation", None) != "any":
            return None
        degrees, mirrored = result.orientation
        return cls._read(degrees, mirrored)

    @classmethod
    def found_in_record(cls, record) -> SketchOrientation | None:
        """:meth:`found_in` for a correspondence file's ``matcher`` record (what ``ursim match`` and
        the app write beside the automatic cliques); None when the record says no such thing.

        Examples
        --------
        >>> record = {"config": {"orientation": "any"}, "orientation": {"degrees": 90.0, "mirrored": False}}
        >>> SketchOrientation.found_in_record(record), SketchOrientation.found_in_record({"m": 0.1})
        (SketchOrientation(angle=90.0, mirrored=False), None)
        """
        try:
            if record["config"]["orientation"] != "any":
                return None
            degrees, mirrored = float(record["orientation"]["degrees"]), record["orientation"]["mirrored"]
        except (KeyError, TypeError, ValueError):
            return None  # an older file, or one a person or another tool wrote
        if not isinstance(mirrored, bool) or not math.isfinite(degrees):
            return None
        return cls._read(degrees, mirrored)

    @classmethod
    def runner_up_in(cls, result=None, record=None) -> tuple[SketchOrientation, float] | None:
        """The reading the matcher ranked next when it chose the orientation, and how much worse it
        ranked (relative; negative when better, see ``ursim_core.matching.orientation.next_reading``):
        from ``result`` (a ``MatchResult``), else from a file's ``matcher`` record (its
        ``next_reading``). None when there is none.

        Examples
        --------
        >>> record = {"next_reading": {"degrees": 180.04, "mirrored": True, "ranked_worse_by": 0.02}}
        >>> SketchOrientation.runner_up_in(record=record)
        (SketchOrientation(angle=180.0, mirrored=True), 0.02)
        >>> SketchOrientation.runner_up_in(record={"m": 0.1}) is None
        True
        """
        if result is not None:
            if cls.found_in(result) is None:
                return None
            from ursim_core.matching.orientation import next_reading

            found = next_reading(result.orientation, getattr(result, "orientation_scan", None) or {})
            if found is None:
                return None
            (degrees, mirrored), gap = found
            return cls._read(degrees, mirrored), gap
        try:
            runner_up = record["next_reading"]
            degrees, mirrored, gap = (
                float(runner_up["degrees"]),
                runner_up["mirrored"],
                float(runner_up["ranked_worse_by"]),
            )
        except (KeyError, TypeError, ValueError):
            return None  # an older file, or one a person or another tool wrote
        if not isinstance(mirrored, bool) or not math.isfinite(degrees) or not math.isfinite(gap):
            return None
        return cls._read(degrees, mirrored), gap

    @classmethod
    def _read(cls, degrees: float, mirrored: bool) -> SketchOrientation:
        # Rounded to the tenth of a degree the panel shows: 359.96 is upright.
        return cls(angle=float(round(float(degrees) % 360.0, 1) % 360.0), mirrored=bool(mirrored))
