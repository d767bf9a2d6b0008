"""Pair F1 and place accuracy of one match against a ground-truth file, as ``ursim match
--reference`` reports them.

A reference file's region ids belong to the segmentation it was saved with (or, for a ``.dat``
file, to none): its cliques are assigned regions from their points in the matcher's
segmentations first. Place accuracy needs a fixed reference segmentation of the metric map
(:data:`~ursim_core.evaluation.place.PLACE_REFERENCE_PRESET`); the matcher's own is used when
it is that one, else the metric map is segmented with it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ursim_core.evaluation.place import PlaceScore
from ursim_core.evaluation.scoring import MatchScore

__all__ = ["MatchScores", "score_against_reference"]


@dataclass(frozen=True)
class MatchScores:
    """Both scores of one match: ``pairs`` (precision, recall, F1) and ``place`` (accuracy).

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> from ursim_core.segmentation import segment
    >>> free = np.zeros((60, 130), bool); free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True
    >>> seg = segment(free, preset="default")  # two rooms: 1 on the left, 2 on the right
    >>> left = Clique(id=1, sketch_points=[(30, 30)], metric_points=[(30, 30)])
    >>> scores = score_against_reference([(1, 2)], Correspondences(cliques=(left,)), seg, seg, free)
    >>> scores.pairs.f1, scores.pairs.pair_labels, scores.place.accuracy  # the robot goes to room 2
    (0.0, ('fp',), 0.0)
    """

    pairs: MatchScore
    place: PlaceScore


def score_against_reference(
    pairs: Any,
    reference: Any,
    sketch_seg: Any,
    metric_seg: Any,
    metric_map: Any,
    *,
    tolerance: float = 10,
) -> MatchScores:
    """Pair score and place accuracy of ``pairs`` against ``reference`` (cliques with points).

    Parameters
    ----------
    pairs : iterable of (sketch_region, metric_region)
        In the ids of ``sketch_seg`` and ``metric_seg``, e.g. ``MapsMatch.result.pairs``.
    reference : Correspondences
        Ground truth, e.g. :func:`~ursim_core.correspondences.load_correspondences` or
        :func:`~ursim_core.correspondences.load_dat`; its stored region ids are not used.
    sketch_seg, metric_seg : Segmentation
        The segmentations the pairs refer to.
    metric_map : Map
        The metric map, segmented with the place reference preset when ``metric_seg`` is not.
    tolerance : float, keyword-only
        The 10 px rule: how far from a region a point may lie and still be in it.

    Returns
    -------
    MatchScores

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> from ursim_core.io import map_from_array
    >>> from ursim_core.matching import match_maps
    >>> image = np.zeros((100, 170), np.uint8)
    >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
    >>> found = match_maps(map_from_array(image), map_from_array(image))
    >>> truth = Correspondences(cliques=(Clique(id=1, sketch_points=[(50, 40)], metric_points=[(50, 40)]),))
    >>> scores = score_against_reference(found.result.pairs, truth, found.sketch_seg, found.metric_seg,
    ...                                  found.metric_map)
    >>> scores.pairs.tp, scores.place.accuracy
    (1, 1.0)
    """
    from ursim_core.correspondences import assign_regions
    from ursim_core.evaluation.place import PLACE_REFERENCE_PRESET, place_accuracy
    from ursim_core.evaluation.scoring import score_matches
    from ursim_core.segmentation import resolve_params, segment

    pairs = list(pairs)
    assigned = assign_regions(reference, sketch_seg.labels, metric_seg.labels, tolerance=tolerance)
    # As region sets: assigned here, so cliques whose points all fell off every region (and have
    # no ids) are unusable, not a sign that assign_regions was forgotten.
    pair_score = score_matches(pairs, [(c.sketch_regions, c.metric_regions) for c in assigned.cliques])
    reference_params = resolve_params("maoris", PLACE_REFERENCE_PRESET, {})
    # A segmentation records its resolved parameters: the matcher's is reused when it is the
    # reference one (a metric map's is never canonical).
    if metric_seg.method == "maoris" and dict(metric_seg.params) == reference_params:
        place_labels = metric_seg.labels
    else:
        place_labels = segment(metric_map, preset=PLACE_REFERENCE_PRESET).labels
    place = place_accuracy(
        pairs, reference, sketch_seg.labels, metric_seg.labels, place_labels, metric_seg.graph, tolerance=tolerance
    )
    return MatchScores(pair_score, place)
