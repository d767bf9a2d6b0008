"""The overlay matcher's answer in the matching pipeline (``MatchConfig(matcher='overlay')``).

The input map is laid on the metric map by the placement whose free space correlates best
(:mod:`ursim_core.matching.overlay`), or by two or more fixed pairs, and its regions are paired
where they overlap: one answer, whatever m. :func:`ursim_core.matching.prepare` hands the
overlay matcher here.
"""

from __future__ import annotations

import dataclasses

from ursim_core.errors import ParameterError
from ursim_core.matching.config import MatchConfig
from ursim_core.matching.oriented import orientations_to_try, prepare_oriented, region_graph_of, sketch_outlines
from ursim_core.matching.results import MatchResult, Prepared

__all__ = ["prepare_overlay"]


def prepare_overlay(sketch_seg, metric_seg, config: MatchConfig, constraints=None) -> Prepared:
    """The overlay matcher's answer, found once: it does not depend on m.

    With two fixed pairs or more, they lay the input map (:func:`~ursim_core.matching.overlay.fit_to_pairs`,
    in the mirror readings of the orientation candidates) instead of the search; the answer then
    holds the fixed pairs and avoids the forbidden ones.
    """
    from ursim_core.matching.alignment import Alignment
    from ursim_core.matching.overlay import constrained_pairs, fit_to_pairs, overlay_pairs, ranked_overlays

    sketch_labels = getattr(sketch_seg, "labels", None)
    metric_labels = getattr(metric_seg, "labels", None)
    if sketch_labels is None or metric_labels is None:
        raise ParameterError("the overlay matcher needs segmentations (label images), not bare graphs", field="matcher")
    candidates = orientations_to_try(config, sketch_seg, metric_seg)
    sketch_graph, metric_graph = region_graph_of(sketch_seg), region_graph_of(metric_seg)
    fit = None
    scan: dict = {}
    if constraints is not None and len(constraints.fixed) >= 2:
        flags = [mirrored for _, mirrored in candidates]
        fit = fit_to_pairs(
            sketch_labels, metric_labels, constraints.fixed, sketch_graph, metric_graph, mirror_flags=flags
        )
    if fit is None:
        # A told orientation is kept exactly; found ones are refined by a few degrees.
        step = config.overlay_angle_step if config.orientation == "any" else 0.0
        ranked = ranked_overlays(
            sketch_labels, metric_labels, orientations=candidates, scale=config.scale, angle_step=step
        )
        fit = ranked[0][1] if ranked else Alignment.unfitted(*candidates[0])
        # Rank values as the planar matcher's (lower is better): 1 - the correlation. The answer's
        # runner-up reading (orientation.next_reading) then tells a person how close the call was.
        scan = {(placed.degrees, placed.mirrored): 1.0 - score for score, placed in ranked}
    orientation = (fit.degrees, fit.mirrored)
    outlines = sketch_outlines(sketch_seg, sketch_graph, [orientation])
    base = prepare_oriented(sketch_graph, metric_graph, config, orientation, outlines)
    pairs = overlay_pairs(sketch_labels, metric_labels, fit.matrix, min_iou=config.overlay_min_iou)
    pairs = constrained_pairs(pairs, constraints)
    descriptors = base.descriptors
    reasons = list(base.notes)
    if not pairs:
        reasons.append(f"no regions overlap by IoU >= {config.overlay_min_iou:g}")
    result = MatchResult(
        pairs=pairs,
        anchors=list(descriptors.anchors) if descriptors else [],
        unique_sketch=list(descriptors.unique_sketch) if descriptors else [],
        unique_metric=list(descriptors.unique_metric) if descriptors else [],
        m=0.0,
        # The share of the input that does not agree with the metric map where it was laid.
        cost=1.0 - fit.overlap,
        normalised_cost=1.0 - fit.overlap,
        signatures=None,
        c_matrix=base.c_matrix,
        seeds_count=0,
        hypotheses=len(candidates),
        reason="; ".join(dict.fromkeys(reasons)),
        config=config,
        orientation=orientation,
        orientation_scan=scan,
    )
    return dataclasses.replace(base, chosen=result, constraints=constraints, orientation_scan=scan)
