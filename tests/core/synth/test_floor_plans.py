"""Generated floor plans (ursim_core.synth.floor_plans): seeds, connectivity, doors, sizes, interior points."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from scipy import ndimage

from ursim_core.errors import ParameterError
from ursim_core.synth import generate_floor_plan, interior_points, make_large_building, sketchify


def test_same_seed_same_plan_and_sketch_other_seed_other_plan():
    a, b, c = (generate_floor_plan(seed=s) for s in (5, 5, 6))
    assert np.array_equal(a.rooms, b.rooms) and a.places == b.places
    assert nx.utils.graphs_equal(a.graph, b.graph)
    assert not np.array_equal(a.rooms, c.rooms)
    sa, sb = sketchify(a, seed=1), sketchify(b, seed=1)
    assert np.array_equal(sa.rooms, sb.rooms) and sa.notes == sb.notes
    assert not np.array_equal(sa.rooms, sketchify(a, seed=2).rooms)


@pytest.mark.parametrize("seed", range(6))
def test_plan_is_one_connected_building_with_labelled_free_space(seed):
    plan = generate_floor_plan(seed=seed)
    assert plan.free.shape == plan.rooms.shape == (400, 512)
    assert plan.free.dtype == bool and plan.rooms.dtype == np.int32
    assert np.array_equal(plan.free, plan.rooms > 0)
    assert ndimage.label(plan.free)[1] == 1
    ids = [place.id for place in plan.places]
    assert ids == list(range(1, len(ids) + 1)) == sorted(set(np.unique(plan.rooms)) - {0})
    assert set(plan.graph.nodes) == set(ids) and nx.is_connected(plan.graph)
    assert {place.kind for place in plan.places} == {"room", "corridor"}
    for place in plan.places:
        assert plan.rooms[place.interior] == place.id


@pytest.mark.parametrize("seed", range(6))
def test_every_room_has_a_door_to_a_corridor(seed):
    plan = generate_floor_plan(seed=seed)
    kinds = plan.kinds
    for place in plan.places:
        if place.kind == "room":
            assert any(kinds[other] == "corridor" for other in plan.graph[place.id])


def test_graph_edges_are_exactly_the_touching_places():
    plan = generate_floor_plan(seed=4)
    labels = plan.rooms
    touching = set()
    for a, b in ((labels[:, :-1], labels[:, 1:]), (labels[:-1, :], labels[1:, :])):
        pairs = np.stack([a.ravel(), b.ravel()], axis=1)
        pairs = pairs[(pairs[:, 0] != pairs[:, 1]) & (pairs.min(axis=1) > 0)]
        touching |= {tuple(sorted(map(int, p))) for p in np.unique(pairs, axis=0)}
    assert touching == {tuple(sorted(edge)) for edge in plan.graph.edges}


def test_doors_are_clearly_narrower_than_rooms_and_corridors():
    plan = generate_floor_plan(seed=3, door_width=10, corridor_width=30)
    # Twice the distance to the nearest wall is the width of the widest disc that fits.
    distance = ndimage.distance_transform_edt(plan.free)
    for place in plan.places:
        assert 2 * distance[plan.rooms == place.id].max() >= 30, place
    # A disc wider than a door does not pass any door: it sees every place apart.
    wide = distance > 6
    assert ndimage.label(wide)[1] == sum(place.kind == "room" for place in plan.places) + 1


def test_n_rooms_is_exact_and_impossible_sizes_are_parameter_errors():
    for n in (1, 7, 20):
        plan = generate_floor_plan(seed=2, n_rooms=n)
        assert sum(place.kind == "room" for place in plan.places) == n
        assert ndimage.label(plan.free)[1] == 1
    with pytest.raises(ParameterError, match="n_rooms"):
        generate_floor_plan(seed=2, n_rooms=500)
    with pytest.raises(ParameterError, match="door_width"):
        generate_floor_plan(door_width=30, corridor_width=30)
    with pytest.raises(ParameterError, match="shape"):
        generate_floor_plan(shape=(100, 512))


def test_interior_points_are_the_middle_of_the_widest_part():
    labels = np.zeros((20, 40), np.int32)
    labels[2:18, 2:12] = 1  # 16 x 10: ridge along col 6..7, middle at row 9..10
    labels[2:18, 12:38] = 2  # 16 x 26, touching region 1 (a label change is a border)
    labels[9:11, 1:2] = 3  # a 2-pixel region still gets one of its pixels
    points = interior_points(labels)
    assert set(points) == {1, 2, 3}
    assert points[1][0] in (9, 10) and points[1][1] in (6, 7)
    assert points[2][0] in (9, 10) and points[2][1] in (24, 25)
    assert labels[points[3]] == 3


def test_large_building_has_hundreds_of_rooms():
    plan = make_large_building(2000)
    assert plan.free.shape == (2000, 2000)
    assert sum(place.kind == "room" for place in plan.places) >= 100
    assert ndimage.label(plan.free)[1] == 1
    # Two bands joined by two vertical corridors make a loop in the place graph.
    assert nx.cycle_basis(plan.graph)
