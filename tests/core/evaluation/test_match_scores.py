"""Pair score and place accuracy of one match against a ground-truth file
(ursim_core.evaluation.match_scores), as ``ursim match --reference`` reports them."""

from __future__ import annotations

import numpy as np

from ursim_core.correspondences import Clique, Correspondences
from ursim_core.evaluation import score_against_reference
from ursim_core.io import map_from_array
from ursim_core.matching import match_maps
from ursim_core.segmentation import Segmentation, segment
from ursim_core.segmentation.regions import region_table


def _rooms() -> np.ndarray:
    image = np.zeros((120, 200), np.uint8)
    image[10:110, 10:80] = image[30:90, 120:180] = image[55:65, 80:120] = 255
    return image


def _truth(*points) -> Correspondences:
    # Stored region ids that are wrong on purpose: the points decide.
    return Correspondences(
        cliques=tuple(
            Clique(id=i + 1, sketch_points=[p], metric_points=[p], sketch_regions=(99,), metric_regions=(98,))
            for i, p in enumerate(points)
        )
    )


def test_the_reference_is_scored_by_its_points_not_its_stored_ids():
    found = match_maps(map_from_array(_rooms()), map_from_array(_rooms()))
    scores = score_against_reference(
        found.result.pairs, _truth((60, 40), (60, 100), (60, 150)), found.sketch_seg, found.metric_seg, found.metric_map
    )
    assert (scores.pairs.tp, scores.pairs.fn, scores.pairs.f1) == (3, 0, 1.0)
    assert scores.place.accuracy == 1.0 and scores.place.n_cliques == 3


def test_swapped_rooms_fail_both_scores():
    the_map = map_from_array(_rooms())
    seg = segment(the_map, preset="default")
    at = {region: seg.labels[row, col] for region, (row, col) in (("left", (60, 40)), ("right", (60, 150)))}
    swapped = [(at["left"], at["right"]), (at["right"], at["left"])]
    scores = score_against_reference(swapped, _truth((60, 40), (60, 150)), seg, seg, the_map)
    assert scores.pairs.tp == 0 and scores.place.accuracy == 0.0


def test_a_metric_segmentation_of_another_preset_is_scored_on_the_place_reference():
    # One region for the whole metric map (a coarse segmentation): F1 is perfect, place accuracy
    # is not, because the place is judged on the reference segmentation, not the matcher's.
    the_map = map_from_array(_rooms())
    sketch = segment(the_map, preset="default")
    whole = the_map.free.astype(np.int32)
    coarse = Segmentation(whole, regions=region_table(whole), method="label-image")
    pairs = [(region, 1) for region in sketch.graph.nodes]
    scores = score_against_reference(pairs, _truth((60, 40), (60, 100), (60, 150)), sketch, coarse, the_map)
    assert scores.pairs.f1 == 1.0
    assert scores.place.successes == 1 and scores.place.n_points == 3  # one place holds the goal


def test_a_reference_whose_points_fall_off_every_region_scores_zero_without_an_error():
    found = match_maps(map_from_array(_rooms()), map_from_array(_rooms()))
    far = _truth((0, 199), (119, 0))  # in the walls, farther than 10 px from any room
    scores = score_against_reference(found.result.pairs, far, found.sketch_seg, found.metric_seg, found.metric_map)
    assert scores.pairs.tp == 0 and scores.pairs.fp == len(found.result.pairs)
