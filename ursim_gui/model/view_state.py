"""Qt-free helpers that turn session state into what the views draw.

Pure functions of values the session exposes; they derive nothing that is stored, and
every rule about cliques (partners, TP/FP marks, misses) stays in the session.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from ursim_gui.model.region_style import NEUTRAL_REGION, Colour, region_colour_table

__all__ = ["side_colour_table", "first_regions", "eval_badges"]


def side_colour_table(
    correspondences,
    side: str,
    labels: np.ndarray,
    colour_of: Callable[[int], Colour],
    *,
    alpha: int = 255,
    max_label: int | None = None,
) -> np.ndarray:
    """Colour lookup table of one side's label image.

    Without cliques every region gets its own palette colour (segmentation view). With
    cliques, a region of a clique takes the clique's colour (``colour_of(id)``, the same
    in both views) and the other regions are neutral grey so the matches stand out;
    rejected cliques stay grey. ``max_label`` saves a pass over the image when known.
    """
    if max_label is None:
        max_label = int(labels.max()) if labels.size else 0
    if not correspondences.cliques:
        return region_colour_table(max_label, alpha=alpha)
    colours: dict[int, Colour] = {}
    for clique in correspondences.cliques:
        if clique.effective_status == "rejected":
            continue
        for region in getattr(clique, f"{side}_regions"):
            colours.setdefault(region, colour_of(clique.id))  # the first clique wins
    return region_colour_table(max_label, colours, default=NEUTRAL_REGION, alpha=alpha)


def first_regions(correspondences) -> list[tuple[int, int, int]]:
    """(clique id, first sketch region, first metric region) of cliques with both sides and
    not rejected: where connector lines go."""
    return [
        (clique.id, clique.sketch_regions[0], clique.metric_regions[0])
        for clique in correspondences.cliques
        if clique.sketch_regions and clique.metric_regions and clique.effective_status != "rejected"
    ]


def eval_badges(
    correspondences, side: str, status_of: Callable[[int], str | None], missed: Iterable = ()
) -> dict[int, str]:
    """'TP' / 'FP' tag per region of ``side`` on each marked clique's first region, then 'FN'.

    ``missed`` holds the reference cliques no predicted pair hits, as (sketch regions,
    metric regions); each gets 'FN' on its lowest region of ``side`` that has no tag yet,
    so a miss is visible on the map and not only in the evaluation list.
    """
    badges: dict[int, str] = {}
    for clique in correspondences.cliques:
        mark = status_of(clique.id)
        regions = getattr(clique, f"{side}_regions")
        if mark and regions:
            badges.setdefault(regions[0], mark.upper())
    index = 0 if side == "sketch" else 1
    for reference in missed:
        free = sorted(region for region in reference[index] if region not in badges)
        if free:
            badges[free[0]] = "FN"
    return badges


def laid_sketch_of(result, sketch_labels, metric_labels) -> np.ndarray | None:
    """The sketch's regions where a match laid them on the metric map, on the metric map's pixels
    (:func:`ursim_core.matching.elastic.laid_sketch`, laid as the match laid it:
    ``MatchResult.laying``); None when the result's pairs are not the laid sketch's
    (``MatchResult.laid``) or a map has no segmentation."""
    if result is None or not getattr(result, "laid", False) or sketch_labels is None or metric_labels is None:
        return None
    from ursim_core.matching.elastic import laid_sketch

    degrees, mirrored = result.orientation
    laying = getattr(result, "laying", None)
    return laid_sketch(sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, laying=laying)
