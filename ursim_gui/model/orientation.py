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
        return cls.laid_in(result)

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
            chosen = record["config"]["orientation"] == "any"
        except (KeyError, TypeError):
            return None  # an older file, or one a person or another tool wrote
        return cls.laid_in(record=record) if chosen else None

    @classmethod
    def laid_in(cls, result=None, record=None) -> SketchOrientation | None:
        """The reading an answer laid the sketch in, told or chosen: ``result``'s (a
        ``MatchResult``), else a file's ``matcher`` record's; None when neither says.

        Examples
        --------
        >>> from types import SimpleNamespace as Result
        >>> SketchOrientation.laid_in(Result(orientation=(90.0, False)))
        SketchOrientation(angle=90.0, mirrored=False)
        >>> SketchOrientation.laid_in(record={"orientation": {"degrees": 180.0, "mirrored": True}}).describe()
        'turned 180° counter-clockwise, mirrored'
        >>> SketchOrientation.laid_in(record={"orientation": "upright"}) is None
        True
        """
        if result is not None:
            # A result of a matcher that reads no orientation (a stand-in in tests) has none.
            orientation = getattr(result, "orientation", None)
            return cls._read(*orientation) if orientation is not None else None
        try:
            degrees, mirrored = float(record["orientation"]["degrees"]), record["orientation"]["mirrored"]
        except (KeyError, TypeError, ValueError):
            return None
        if not isinstance(mirrored, bool) or not math.isfinite(degrees):
            return None
        return cls._read(degrees, mirrored)

    @classmethod
    def readings_in(cls, result=None, record=None) -> list[tuple[SketchOrientation, float]]:
        """Every reading the matcher ranked when it chose the orientation, the one it chose first,
        each with how much worse it ranked (relative; see
        ``ursim_core.matching.orientation.ranked_readings``): from ``result`` (a ``MatchResult``),
        else from a file's ``matcher`` record (its ``readings``, or for a file written before
        them its ``orientation`` and ``next_reading``). Empty when the matcher was told the
        orientation or ranked one reading only.

        Examples
        --------
        >>> record = {"config": {"orientation": "any"}, "orientation": {"degrees": 0.0, "mirrored": False},
        ...           "next_reading": {"degrees": 180.0, "mirrored": True, "ranked_worse_by": 0.02}}
        >>> [(reading.describe(), gap) for reading, gap in SketchOrientation.readings_in(record=record)]
        [('upright', 0.0), ('turned 180° counter-clockwise, mirrored', 0.02)]
        >>> record["readings"] = [{"degrees": 0.0, "mirrored": False, "ranked_worse_by": 0.0},
        ...                       {"degrees": 180.0, "mirrored": True, "ranked_worse_by": 0.02},
        ...                       {"degrees": 90.0, "mirrored": False, "ranked_worse_by": 0.3}]
        >>> len(SketchOrientation.readings_in(record=record)), SketchOrientation.readings_in(record={"m": 0.1})
        (3, [])
        """
        if result is not None:
            if cls.found_in(result) is None:
                return []
            from ursim_core.matching.orientation import ranked_readings

            ranked = ranked_readings(result.orientation, getattr(result, "orientation_scan", None) or {})
            return (
                [(cls._read(degrees, mirrored), gap) for (degrees, mirrored), gap in ranked] if len(ranked) > 1 else []
            )
        found = cls.found_in_record(record)
        if found is None:
            return []
        readings = record.get("readings")
        if isinstance(readings, list):
            parsed = [cls._ranked(reading) for reading in readings]
            if len(parsed) > 1 and None not in parsed and parsed[0][0] == found:
                return parsed
        runner_up = cls.runner_up_in(record=record)
        return [(found, 0.0), runner_up] if runner_up is not None else []

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
            readings = cls.readings_in(result)
            return readings[1] if readings else None
        try:
            return cls._ranked(record["next_reading"])
        except (KeyError, TypeError):
            return None  # an older file, or one a person or another tool wrote

    @classmethod
    def _ranked(cls, entry) -> tuple[SketchOrientation, float] | None:
        """A reading of a ``matcher`` record (``{"degrees", "mirrored", "ranked_worse_by"}``) and its
        gap; None when it is not one (a file a person or another tool wrote)."""
        try:
            degrees, mirrored, gap = float(entry["degrees"]), entry["mirrored"], float(entry["ranked_worse_by"])
        except (KeyError, TypeError, ValueError):
            return None
        if not isinstance(mirrored, bool) or not math.isfinite(degrees) or not math.isfinite(gap):
            return None
        return cls._read(degrees, mirrored), gap

    @classmethod
    def _read(cls, degrees: float, mirrored: bool) -> SketchOrientation:
        # Rounded to the tenth of a degree the panel shows: 359.96 is upright.
        return cls(angle=float(round(float(degrees) % 360.0, 1) % 360.0), mirrored=bool(mirrored))
