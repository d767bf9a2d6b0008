"""Which matching settings belong to which maps. Qt-free.

The matching panel's orientation, input kind and scale describe the maps open now, not the
next ones: the orientation and the input kind say how the sketch was drawn, and the scale
relates the two maps' pixels. Opening another map (a campaign's next pair, a file from the
recent list) must not match it as if it were the last one. :class:`MapIdentities` says which
settings to forget when a side's map changes; :func:`recorded_settings` reads back the
settings a correspondence file's automatic cliques were made with, so that a file opened
again is matched again as it was.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["MAX_SCALE", "MapIdentities", "SETTINGS_OF_SIDE", "recorded_settings"]

#: The settings that belong to each side's map.
SETTINGS_OF_SIDE = {
    "sketch": ("orientation", "input_kind", "scale"),
    "metric": ("scale",),
}
#: The largest scale the panel can show (metric pixels per input pixel).
MAX_SCALE = 100.0


class MapIdentities:
    """The identity (the file's digest) of each side's map the settings were set for.

    A drawing made on the canvas has no digest (None): edited and used again, it keeps
    its settings, as the same file opened again does.

    Examples
    --------
    >>> identities = MapIdentities({"sketch": "a", "metric": "m"})
    >>> identities.settings_to_forget("sketch", "a"), identities.settings_to_forget("metric", "n")
    ((), ('scale',))
    >>> identities.settings_to_forget("sketch", "b")
    ('orientation', 'input_kind', 'scale')
    """

    def __init__(self, digests: dict[str, str | None]) -> None:
        self._digests = dict(digests)

    def settings_to_forget(self, side: str, digest: str | None) -> tuple[str, ...]:
        """The settings to reset now that ``side`` holds the map of ``digest``."""
        if side not in SETTINGS_OF_SIDE or self._digests.get(side) == digest:
            return ()
        self._digests[side] = digest
        return SETTINGS_OF_SIDE[side]


def recorded_settings(record: Any) -> dict[str, Any]:
    """The input kind and scale a file's ``matcher`` record says its match used.

    Only valid values are returned (a record written by a person or another tool may hold
    anything); a setting the record leaves unknown is returned as None, so that it is
    reset too.

    Examples
    --------
    >>> recorded_settings({"config": {"input_kind": "metric", "scale": 0.25}})
    {'input_kind': 'metric', 'scale': 0.25}
    >>> recorded_settings({"config": {"input_kind": "robot", "scale": -1}})
    {'input_kind': None, 'scale': None}
    >>> recorded_settings(None)
    {}
    """
    config = record.get("config") if isinstance(record, dict) else None
    if not isinstance(config, dict):
        return {}
    kind = config.get("input_kind")
    scale = config.get("scale")
    valid_scale = (
        isinstance(scale, (int, float))
        and not isinstance(scale, bool)
        and math.isfinite(scale)
        and 0 < scale <= MAX_SCALE
    )
    return {
        "input_kind": kind if kind in ("sketch", "metric") else None,
        "scale": float(scale) if valid_scale else None,
    }
