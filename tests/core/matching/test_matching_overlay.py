"""The overlay matcher: two metric maps laid on each other, partial coverage, turns, errors."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation import augment
from ursim_core.matching import MatchConfig, match, match_prepared, prepare
from ursim_core.matching.constraints import MatchConstraints
from ursim_core.matching.overlay import fit_overlay, overlay_pairs, ranked_overlays
from ursim_core.matching.results import next_reading_record
from ursim_core.segmentation import segment, segment_canonical
from ursim_core.synth import make_pair

OVERLAY = MatchConfig(matcher="overlay", scale=1.0, mirrored=False)


@pytest.fixture(scope="module")
def plan():
    plan, _ = make_pair(seed=2)
    return plan


@pytest.fixture(scope="module")
def plan_segmentation(plan):
    return segment(plan.free, preset="default")


def _identity_share(pairs, part_labels, full_labels, rows, cols):
    """Share of the pairs whose regions overlap where the part was cut from."""
    good = 0
    for a, b in pairs:
        inside = full_labels[rows, cols][part_labels == a]
        good += np.count_nonzero(inside == b) > 0.5 * inside.size
    return good / max(len(pairs), 1)


@pytest.mark.parametrize("quarter_turns", [0, 1, 3])
def test_a_cropped_turned_copy_is_laid_back_where_it_came_from(plan, plan_segmentation, quarter_turns):
    rows, cols = plan.free.shape
    window = (slice(rows // 5, rows // 5 + int(rows * 0.7)), slice(cols // 8, cols // 8 + int(cols * 0.75)))
    turn = augment.Orientation(90.0 * quarter_turns, mirrored=False)
    part = augment.transform_image(plan.free[window], turn)
    part_seg = segment(part, preset="default")
    result = match(part_seg, plan_segmentation, config=OVERLAY)
    assert result.pairs and result.reason == ""
    # The turn found undoes the one applied (up to the walls' small angle).
    undo = (-90.0 * quarter_turns) % 360.0
    assert abs((result.orientation[0] - undo + 180.0) % 360.0 - 180.0) < 5.0, result.orientation
    # Where each part region lands: the full map's region under the same pixels (turned back).
    back = augment.transform_image(part_seg.labels, augment.Orientation(-90.0 * quarter_turns % 360.0, mirrored=False))
    full_rows, full_cols = np.mgrid[window[0], window[1]]
    share = _identity_share(result.pairs, back, plan_segmentation.labels, full_rows, full_cols)
    assert share >= 0.9, (share, result.pairs)


@pytest.mark.parametrize("seed", [1, 15])
def test_a_cropped_copy_with_no_scale_given_is_laid_where_it_came_from(seed):
    # The placements are ranked by the normalised cross-correlation of the signed images; ranked by
    # the share of the input that agrees, these copies were laid turned by a half turn at 1.09-1.13
    # times their scale (F1 0.14 and 0.11 in `ursim bench invariance`'s robot-map copies).
    from ursim_core.bench.invariance import _parameters, transformed_sketch

    plan, _ = make_pair(seed=seed)
    # Points on a grid of the plan: the crop moves those it keeps by minus its origin.
    grid = [(r, c) for r in range(0, plan.free.shape[0], 10) for c in range(0, plan.free.shape[1], 10)]
    part, moved = transformed_sketch(plan.free, grid, kept=_parameters(seed, "cropped")[3], seed=seed)
    part_seg, plan_seg = segment_canonical(part, preset="default"), segment_canonical(plan.free, preset="default")
    fit = fit_overlay(part_seg.labels, plan_seg.labels, orientations=[(0.0, False), (180.0, False)])
    assert fit.degrees == 0.0
    np.testing.assert_allclose(fit.matrix[:, :2], np.eye(2), atol=0.08)
    result = match(part_seg, plan_seg, config=MatchConfig(input_kind="metric"))
    # Where the crop was cut from.
    point, kept_point = next((p, q) for p, q in zip(grid, moved) if q is not None)
    start = np.subtract(point, kept_point)
    full_rows, full_cols = np.mgrid[start[0] : start[0] + part.shape[0], start[1] : start[1] + part.shape[1]]
    assert _identity_share(result.pairs, part_seg.labels, plan_seg.labels, full_rows, full_cols) >= 0.9


@pytest.mark.parametrize("seed", [6, 11])
def test_a_copy_cut_at_its_image_edge_is_laid_at_its_own_scale_as_a_free_space_mask(seed):
    # Free space touching the image's edge was cut there: no wall band is drawn beyond it. With one,
    # these crops (as bool masks; MAORIS drops the slivers at the cut from a label image) were laid
    # at 0.47 and 0.50 times their scale.
    from ursim_core.bench.invariance import _parameters, transformed_sketch

    plan, _ = make_pair(seed=seed)
    part, _ = transformed_sketch(plan.free, [], kept=_parameters(seed, "cropped")[3], seed=seed)
    assert part[:, 0].any() or part[:, -1].any() or part[0].any() or part[-1].any()
    quarter_turns = [(90.0 * k, False) for k in range(4)]
    fit = fit_overlay(part, plan.free, orientations=quarter_turns)
    assert fit.degrees == 0.0
    np.testing.assert_allclose(fit.matrix[:, :2], np.eye(2), atol=0.08)


def test_the_shift_of_a_crop_is_found_at_full_resolution(plan):
    rows, cols = plan.free.shape
    part = plan.free[40 : 40 + rows // 2, 60 : 60 + cols // 2]
    fit = fit_overlay(part, plan.free, orientations=[(0.0, False), (180.0, False)], scale=1.0)
    assert fit.degrees == 0.0
    np.testing.assert_allclose(fit.matrix[:, :2], np.eye(2), atol=0.06)
    # A coarse search: within a few coarse pixels (about 3 % of the map's side).
    assert np.abs(fit.matrix[:, 2] - [40, 60]).max() <= 0.03 * max(rows, cols)


def test_every_orientation_is_ranked_and_the_first_is_fit_overlays(plan):
    rows, cols = plan.free.shape
    part = np.rot90(plan.free[rows // 6 : rows // 6 + int(rows * 0.7), : int(cols * 0.8)], 2)
    quarter_turns = [(90.0 * k, False) for k in range(4)]
    ranked = ranked_overlays(part, plan.free, orientations=quarter_turns, scale=1.0)
    assert sorted(fit.degrees for _, fit in ranked) == [0.0, 90.0, 180.0, 270.0]
    scores = [score for score, _ in ranked]
    assert scores == sorted(scores, reverse=True) and scores[0] > scores[1]
    best = fit_overlay(part, plan.free, orientations=quarter_turns, scale=1.0)
    assert (ranked[0][1].degrees, ranked[0][1].overlap) == (best.degrees, best.overlap) == (180.0, best.overlap)
    np.testing.assert_array_equal(ranked[0][1].matrix, best.matrix)
    assert ranked_overlays(np.zeros_like(part), plan.free, orientations=quarter_turns) == []


def test_a_copy_turned_a_few_degrees_off_its_candidate_is_laid_by_the_angle_step(plan):
    # A robot map's drift bends its walls: its wall angle can miss the turn between the maps by a
    # few degrees. The candidate here says 0; the copy is turned by 4 degrees.
    from ursim_core.bench.invariance import transformed_sketch

    part, _ = transformed_sketch(plan.free, [], degrees=4.0)
    ((plain, fixed),) = ranked_overlays(part, plan.free, orientations=[(0.0, False)], scale=1.0)
    ((refined, fit),) = ranked_overlays(part, plan.free, orientations=[(0.0, False)], scale=1.0, angle_step=2.0)
    assert fixed.degrees == 0.0 and fit.degrees == 356.0 and refined > plain
    # With no better turn nearby the candidate's own is kept.
    ((_, same),) = ranked_overlays(plan.free, plan.free, orientations=[(0.0, False)], scale=1.0, angle_step=2.0)
    assert same.degrees == 0.0


def test_a_told_orientation_is_kept_exactly_by_the_overlay(plan, plan_segmentation):
    part_seg = segment(plan.free[:, : plan.free.shape[1] * 3 // 4], preset="default")
    for told in (0.0, 3.0):
        result = match(part_seg, plan_segmentation, config=MatchConfig(input_kind="metric", orientation=told))
        assert result.orientation == (told, False)


def test_the_overlay_answer_names_its_runner_up_reading(plan, plan_segmentation):
    # A corridor lined with rooms correlates nearly as well turned by a half turn (Halmstad E5_05):
    # the answer records every orientation's rank value, so `ursim match` and the app say how close
    # the call was (the runner-up reading and how much worse it ranked).
    rows, cols = plan.free.shape
    part_seg = segment(np.rot90(plan.free[:, : int(cols * 0.8)], 1), preset="default")
    result = match(part_seg, plan_segmentation, config=MatchConfig(input_kind="metric"))
    scan = result.orientation_scan
    assert len(scan) >= 2 and scan[result.orientation] == min(scan.values())
    runner_up = next_reading_record(result)["next_reading"]
    gap = (sorted(scan.values())[1] - scan[result.orientation]) / scan[result.orientation]
    assert runner_up["ranked_worse_by"] == pytest.approx(gap) and runner_up["ranked_worse_by"] > 0
    assert (runner_up["degrees"], runner_up["mirrored"]) != result.orientation
    # Told the orientation, or laid by a person's pairs, there is no other reading to name.
    told = match(
        part_seg, plan_segmentation, config=MatchConfig(input_kind="metric", orientation=result.orientation[0])
    )
    assert next_reading_record(told) == {}
    laid = match(
        part_seg,
        plan_segmentation,
        config=MatchConfig(input_kind="metric"),
        constraints=MatchConstraints(fixed=result.pairs[:2]),
    )
    assert laid.orientation_scan == {} and next_reading_record(laid) == {}


def test_pairs_need_the_overlap_threshold():
    labels = np.zeros((20, 30), np.int32)
    labels[2:18, 2:14] = 1
    labels[2:18, 16:28] = 2
    shifted = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 9.0]])  # most of region 1 now lies on region 2
    assert overlay_pairs(labels, labels, shifted, min_iou=0.9) == []
    assert (1, 2) in overlay_pairs(labels, labels, shifted, min_iou=0.2)
    assert overlay_pairs(np.zeros((5, 5), np.int32), labels, np.eye(2, 3)) == []


def test_the_answer_does_not_depend_on_m(plan_segmentation):
    prepared = prepare(plan_segmentation, plan_segmentation, OVERLAY)
    answers = {tuple(match_prepared(prepared, m).pairs) for m in (0.0, 0.2, None)}
    assert len(answers) == 1
    pairs = next(iter(answers))
    assert sorted(pairs) == [(n, n) for n in sorted(plan_segmentation.graph.nodes)]


def test_overlay_options_are_checked():
    with pytest.raises(ParameterError, match="scale"):
        MatchConfig(scale=0)
    with pytest.raises(ParameterError, match="overlay_min_iou"):
        MatchConfig(overlay_min_iou=-0.1)
    graph = nx.path_graph(3)
    nx.set_node_attributes(graph, 10, "size")
    nx.set_node_attributes(graph, 0.3, "pca_shape")
    nx.set_node_attributes(graph, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    with pytest.raises(ParameterError, match="label images"):
        match(graph, graph, config=OVERLAY)


def test_no_known_scale_fits_the_extents(plan, plan_segmentation):
    import cv2

    small = cv2.resize(plan.free.astype(np.uint8), None, fx=0.5, fy=0.5, interpolation=cv2.INTER_NEAREST) > 0
    result = match(segment(small, preset="default"), plan_segmentation, config=MatchConfig(matcher="overlay"))
    assert len(result.pairs) >= 0.8 * plan_segmentation.graph.number_of_nodes()


def test_the_automatic_matcher_overlays_when_the_scale_is_known(plan, plan_segmentation):
    rows, cols = slice(0, plan.free.shape[0]), slice(plan.free.shape[1] // 4, None)
    part = segment(plan.free[rows, cols], preset="default")
    told = prepare(part, plan_segmentation, MatchConfig(scale=1.0))
    assert (told.config.matcher, told.config.mirrored) == ("overlay", False)
    overlaid = match_prepared(told)
    assert overlaid.pairs == match(part, plan_segmentation, config=OVERLAY).pairs
    assert _identity_share(overlaid.pairs, part.labels, plan_segmentation.labels, rows, cols) >= 0.9
    # No scale: a sketch, and the planar matcher's answer, exactly.
    untold = prepare(part, plan_segmentation, MatchConfig())
    assert untold.config.matcher == "planar"
    assert match_prepared(untold).pairs == match(part, plan_segmentation, config=MatchConfig(matcher="planar")).pairs


def test_a_mirror_image_is_tried_by_the_overlay_only_when_asked():
    assert MatchConfig(matcher="overlay").resolved().mirrored is False
    assert MatchConfig(matcher="overlay", mirrored=True).resolved().mirrored is True
    assert MatchConfig(matcher="planar").resolved().mirrored is None


@pytest.mark.parametrize("factor", [0.6, 1.5])
def test_the_scale_of_a_rescaled_crop_is_estimated(plan, factor):
    import cv2

    from ursim_core.matching.overlay import estimate_scale

    part = plan.free[:, plan.free.shape[1] // 4 :].astype(np.uint8)
    rescaled = cv2.resize(part, None, fx=factor, fy=factor, interpolation=cv2.INTER_NEAREST) > 0
    estimated = estimate_scale(rescaled, plan.free, orientations=[(0.0, False), (90.0, False), (180.0, False)])
    assert abs(np.log(estimated * factor)) < np.log(1.1), estimated  # metric pixels per input pixel = 1 / factor


def test_a_metric_input_is_overlaid_by_the_automatic_matcher(plan, plan_segmentation):
    told = prepare(plan_segmentation, plan_segmentation, MatchConfig(input_kind="metric"))
    assert (told.config.matcher, told.config.mirrored) == ("overlay", False)
    assert sorted(match_prepared(told).pairs) == [(n, n) for n in sorted(plan_segmentation.graph.nodes)]
    assert MatchConfig(input_kind="sketch", scale=1.0).resolved().matcher == "planar"
    with pytest.raises(ParameterError, match="input_kind"):
        MatchConfig(input_kind="robot")
