"""Constants and pure helpers shared by the session modules (Qt-free, no state)."""

from __future__ import annotations

import colorsys
import dataclasses
import os
from collections.abc import Iterable
from pathlib import Path

from ursim_core.correspondences import Correspondences, regions_at_points
from ursim_core.matching import MATCH_PRESETS

__all__ = [
    "SIDES",
    "APP_TITLE",
    "REFERENCE_TOLERANCE",
    "DEFAULT_PRESETS",
    "AUTOSAVE_ORIGIN_KEY",
    "color_of_clique",
]

SIDES = ("sketch", "metric")
APP_TITLE = "URSIM Studio"
#: Pixels a reference point may lie off a region and still count for it (the released code's value).
REFERENCE_TOLERANCE = 10
#: Segmentation preset a side starts with.
DEFAULT_PRESETS = dict(MATCH_PRESETS)
#: Top-level key of an autosave file naming the document it belongs to (see autosave.py).
AUTOSAVE_ORIGIN_KEY = "autosave_of"

_GOLDEN_RATIO_CONJUGATE = 0.618033988749895
_STATUS_VERBS = {"accepted": "Accept", "rejected": "Reject", "pending": "Mark pending"}


def color_of_clique(clique_id: int) -> tuple[int, int, int]:
    """Deterministic, well separated ``(r, g, b)`` colour of a clique (ints 0..255).

    Hues step by the golden ratio so neighbouring ids never look alike; saturation and
    value cycle over three levels so hues that come round again stay distinct. The
    formula is the one of ``ursim_gui.model.region_style.clique_colour`` so the table, the maps and
    exported figures agree (a test checks it).

    Examples
    --------
    >>> color_of_clique(1) == color_of_clique(1), color_of_clique(1) != color_of_clique(2)
    (True, True)
    """
    index = int(clique_id)
    hue = (0.08 + index * _GOLDEN_RATIO_CONJUGATE) % 1.0
    saturation = (0.75, 0.55, 0.9)[index % 3]
    value = (0.95, 0.8, 0.7)[(index // 3) % 3]
    r, g, b = colorsys.hsv_to_rgb(hue, saturation, value)
    return int(round(r * 255)), int(round(g * 255)), int(round(b * 255))


def _absolute(path: str | os.PathLike) -> Path:
    # Normalised the way load_correspondences returns paths, so a saved and re-loaded
    # document compares equal to the value in memory.
    return Path(os.path.normpath(os.path.abspath(path)))


def _check_side(side: str) -> str:
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, got {side!r}")
    return side


def _regions_text(regions: Iterable[int]) -> str:
    return ", ".join(str(region) for region in regions) or "-"


def _with_side_regions(corr: Correspondences, side: str, labels) -> Correspondences:
    """Re-derive one side's region ids of every clique from its points.

    Same rule as :func:`ursim_core.correspondences.assign_regions` (ids under the points,
    tolerance 10, duplicates and dropped points left out, point order), for one side only,
    because the other side may not be segmented yet.
    """
    point_lists = [getattr(clique, f"{side}_points") for clique in corr.cliques]
    found = iter(
        regions_at_points(labels, [p for points in point_lists for p in points], tolerance=REFERENCE_TOLERANCE)
    )
    cliques = []
    for clique, points in zip(corr.cliques, point_lists):
        ids = tuple(dict.fromkeys(region for region in (next(found) for _ in points) if region != 0))
        cliques.append(dataclasses.replace(clique, **{f"{side}_regions": ids}))
    return corr.with_cliques(cliques)
