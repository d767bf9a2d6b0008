"""The sketch's known orientation: a turn (degrees counter-clockwise) and a mirror, or unknown.

Qt-free. The view shows the sketch turned this way (its points stay in the original
image's pixel frame: only the view's transform changes) and the matcher is told the
same through ``MatchConfig(orientation=..., mirrored=...)`` when the core's MatchConfig
has those fields.
"""

from __future__ import annotations

import dataclasses
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
