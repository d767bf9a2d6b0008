"""locate(): sketch point -> region -> clique -> metric goal (pixel and world pose)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences
from ursim_core.errors import ParameterError
from ursim_core.io.maps import Map, world_to_pixel
from ursim_core.navigation import MatchTable, locate, match_table
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.interface import Segmentation


def seg_of(labels):
    labels = np.asarray(labels, dtype=np.int32)
    return Segmentation(labels=labels, graph=region_graph(labels))


def three_rooms(width=30):
    """Rooms 1 | 2 | 3 side by side with one-pixel walls, 20 rows high."""
    labels = np.zeros((20, 3 * width + 2), np.int32)
    labels[:, :width] = 1
    labels[:, width + 1 : 2 * width + 1] = 2
    labels[:, 2 * width + 2 :] = 3
    return seg_of(labels)


def test_goal_is_the_interior_point_of_the_largest_matched_region():
    sketch = three_rooms()
    metric_labels = np.zeros((40, 60), np.int32)
    metric_labels[:, :20], metric_labels[:, 21:] = 5, 6  # region 6 is the larger
    metric = seg_of(metric_labels)
    goal = locate([(2, 5), (2, 6)], sketch, metric, None, 10, 45)
    assert goal.ok and goal.sketch_region == 2
    assert goal.metric_regions == (5, 6)
    assert goal.metric_region == 6 and goal.pixel == tuple(metric.graph.nodes[6]["interior"])
    assert goal.pose is None


def test_a_tap_on_a_wall_within_tolerance_uses_the_nearest_region():
    sketch = three_rooms()
    goal = locate([(1, 1), (2, 2)], sketch, sketch, None, 10, 30)  # column 30 is the wall
    assert goal.sketch_region in (1, 2) and goal.ok


def test_world_pose_when_the_metric_map_is_georeferenced():
    metric = three_rooms()
    the_map = Map(free=metric.labels > 0, resolution=0.1, origin=(2.0, -1.0, 0.5))
    goal = locate([(1, 3)], metric, metric, the_map, 5, 5, yaw=1.25)
    x, y, yaw = goal.pose
    assert yaw == 1.25
    assert world_to_pixel(the_map, x, y) == pytest.approx(goal.pixel)


def test_unmatched_tap_gives_a_reason_and_the_nearest_matched_region():
    sketch = three_rooms()
    goal = locate([(1, 1)], sketch, sketch, None, 10, 75)
    assert not goal.ok and goal.metric_region is None
    assert goal.reason == "sketch region 3 is not matched to any metric region"
    assert goal.nearest.sketch_region == 1
    assert goal.nearest.point == (10, 29) and goal.nearest.distance == pytest.approx(46.0)
    off = locate([(1, 1)], sketch, sketch, None, 200, 5)
    assert off.sketch_region == 0 and "no sketch region within 10 px" in off.reason
    assert off.nearest.sketch_region == 1
    assert locate([(1, 1)], sketch, sketch, None, 10, 75, suggest_nearest=False).nearest is None


def test_correspondences_give_clique_label_and_skip_rejected_cliques():
    sketch = three_rooms()
    corr = Correspondences(
        cliques=(
            Clique(id=4, sketch_regions=(1, 2), metric_regions=(3,), extra={"label": "kitchen"}),
            Clique(id=5, sketch_regions=(3,), metric_regions=(1,), status="rejected"),
        )
    )
    goal = locate(corr, sketch, sketch, None, 10, 40)
    assert (goal.metric_region, goal.clique_id, goal.label) == (3, 4, "kitchen")
    assert not locate(corr, sketch, sketch, None, 10, 80).ok


def test_match_table_forms_agree():
    class Result:
        pairs = ((1, 2), (3, 1))

    expected = {1: (2,), 3: (1,)}
    assert match_table(Result()).metric_of == expected
    assert match_table({1: 2, 3: [1]}).metric_of == expected
    table = match_table([(1, 2), (3, 1)])
    assert isinstance(table, MatchTable) and match_table(table) is table


def four_rooms():
    """A 2 x 2 block of rooms of different sizes (centroids not on one line)."""
    labels = np.zeros((41, 71), np.int32)
    labels[:20, :30], labels[:20, 31:], labels[21:, :30], labels[21:, 31:] = 1, 2, 3, 4
    return seg_of(labels)


def test_mirror_target_keeps_the_taps_place_in_the_region_under_rotation():
    sketch = four_rooms()
    # The metric map is the sketch turned by 90 degrees (rot90: (r, c) -> (C - 1 - c, r)) and scaled 2x.
    metric = seg_of(np.rot90(sketch.labels).repeat(2, axis=0).repeat(2, axis=1))
    pairs = [(1, 1), (2, 2), (3, 3), (4, 4)]
    cols = sketch.labels.shape[1]
    for row, col in [(3, 4), (16, 25), (10, 47), (38, 68), (30, 5)]:
        goal = locate(pairs, sketch, metric, None, row, col, target="mirror")
        expected = (2 * (cols - 1 - col), 2 * row)
        assert goal.metric_region == goal.sketch_region
        assert math.dist(goal.pixel, expected) <= 3.0
    # The interior target ignores where in the room the tap is.
    assert locate(pairs, sketch, metric, None, 3, 4).pixel == locate(pairs, sketch, metric, None, 16, 25).pixel


def test_mirror_target_with_a_mirrored_sketch():
    sketch = four_rooms()
    metric = seg_of(sketch.labels[:, ::-1])  # mirrored left-right, region ids kept
    pairs = [(1, 1), (2, 2), (3, 3), (4, 4)]
    cols = sketch.labels.shape[1]
    for row, col in [(4, 3), (35, 60)]:
        goal = locate(pairs, sketch, metric, None, row, col, target="mirror")
        assert goal.metric_region == goal.sketch_region
        assert math.dist(goal.pixel, (row, cols - 1 - col)) <= 2.0


def test_mirror_target_with_collinear_rooms_stays_in_the_room():
    sketch = three_rooms()
    metric = seg_of(sketch.labels[:, ::-1])
    goal = locate([(1, 1), (2, 2), (3, 3)], sketch, metric, None, 4, 3, target="mirror")
    assert goal.metric_region == 1 and metric.labels[goal.pixel] == 1


def test_mirror_target_with_few_pairs_stays_inside_the_matched_region():
    sketch = three_rooms()
    metric_labels = np.zeros((50, 50), np.int32)
    metric_labels[10:40, 5:45] = 7
    metric = seg_of(metric_labels)
    goal = locate([(1, 7)], sketch, metric, None, 0, 0, target="mirror")
    assert metric.labels[goal.pixel] == 7


def test_bad_target_is_a_parameter_error():
    sketch = three_rooms()
    with pytest.raises(ParameterError, match="target"):
        locate([(1, 1)], sketch, sketch, None, 1, 1, target="centre")
