"""plan_route(): a polyline on the sketch -> ordered, connected metric regions and waypoints."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.io.maps import Map
from ursim_core.navigation import plan_route, sample_polyline
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.interface import Segmentation


def seg_of(labels):
    labels = np.asarray(labels, dtype=np.int32)
    return Segmentation(labels=labels, graph=region_graph(labels))


def corridor(n_rooms, width=20):
    """Rooms 1..n in a row, each adjacent to the next."""
    labels = np.zeros((15, n_rooms * width), np.int32)
    for room in range(n_rooms):
        labels[:, room * width : (room + 1) * width] = room + 1
    return seg_of(labels)


def test_polyline_sampling_includes_every_crossed_region():
    sketch, metric = corridor(5), corridor(5)
    identity = [(r, r) for r in range(1, 6)]
    # Two vertices only, far apart: the rooms in between are still on the route.
    route = plan_route(identity, sketch, metric, None, [(7, 2), (7, 98)])
    assert route.metric_regions == (1, 2, 3, 4, 5)
    assert route.sketch_regions == (1, 2, 3, 4, 5)
    assert not any(w.filled for w in route.waypoints)


def test_consecutive_duplicates_are_removed_and_back_and_forth_kept():
    sketch, metric = corridor(3), corridor(3)
    identity = [(1, 1), (2, 2), (3, 3)]
    route = plan_route(identity, sketch, metric, None, [(3, 2), (10, 5), (7, 30), (7, 5)])
    assert route.metric_regions == (1, 2, 1)


def test_gaps_are_filled_along_the_metric_region_graph():
    sketch = corridor(2)
    metric = corridor(5)
    route = plan_route([(1, 1), (2, 5)], sketch, metric, None, [(7, 5), (7, 35)])
    assert route.metric_regions == (1, 2, 3, 4, 5)
    assert [w.filled for w in route.waypoints] == [False, True, True, True, False]
    assert route.waypoints[0].sketch_region == 1 and route.waypoints[1].sketch_region is None
    unfilled = plan_route([(1, 1), (2, 5)], sketch, metric, None, [(7, 5), (7, 35)], fill_gaps=False)
    assert unfilled.metric_regions == (1, 5)


def test_unreachable_regions_are_reported_as_gaps():
    labels = np.zeros((10, 41), np.int32)
    labels[:, :20], labels[:, 21:] = 1, 2  # separated by a wall: no edge
    metric = seg_of(labels)
    sketch = corridor(2)
    route = plan_route([(1, 1), (2, 2)], sketch, metric, None, [(5, 5), (5, 35)])
    assert route.metric_regions == (1, 2) and route.gaps == ((1, 2),)


def test_unmatched_sketch_regions_are_skipped():
    sketch, metric = corridor(3), corridor(3)
    route = plan_route([(1, 1), (3, 3)], sketch, metric, None, [(7, 2), (7, 58)])
    assert route.skipped == (2,)
    assert route.metric_regions == (1, 2, 3)  # 2 comes back as a filled connection
    assert route.waypoints[1].filled


def test_waypoint_poses_head_to_the_next_waypoint():
    metric = corridor(3)
    the_map = Map(free=metric.labels > 0, resolution=0.05, origin=(0.0, 0.0, 0.0))
    route = plan_route([(1, 1), (2, 2), (3, 3)], metric, metric, the_map, [(7, 2), (7, 58)])
    poses = [w.pose for w in route.waypoints]
    assert all(p is not None for p in poses)
    # East along +x in the map frame: heading 0; the last keeps the previous heading.
    assert [round(p[2], 9) for p in poses] == [0.0, 0.0, 0.0]
    reverse = plan_route([(1, 1), (2, 2), (3, 3)], metric, metric, the_map, [(7, 58), (7, 2)])
    assert [round(abs(p[2]), 9) for p in (w.pose for w in reverse.waypoints)] == [round(math.pi, 9)] * 3
    assert route.path == [w.pixel for w in route.waypoints]


def test_a_single_point_is_a_one_waypoint_route_and_no_point_is_an_error():
    metric = corridor(2)
    assert plan_route([(2, 2)], metric, metric, None, [(7, 30)]).metric_regions == (2,)
    with pytest.raises(ParameterError):
        plan_route([(2, 2)], metric, metric, None, [])


def test_sample_polyline_spacing():
    samples = sample_polyline([(0, 0), (3, 4), (3, 4), (0, 0)], step=1.0)
    steps = np.hypot(*np.diff(samples, axis=0).T)
    assert steps.max() <= 1.0 + 1e-9
    assert samples[0].tolist() == [0, 0] and samples[-1].tolist() == [0, 0]
