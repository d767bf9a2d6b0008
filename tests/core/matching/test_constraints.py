"""Matching under constraints: fixed pairs, forbidden pairs and excluded regions."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.correspondences import Clique
from ursim_core.errors import ParameterError
from ursim_core.matching import MatchConfig, MatchConstraints, constraints_from_cliques, match, prepare
from ursim_core.matching.constraints import index_constraints
from ursim_core.matching.planar import PlanarGraph, planar_match
from ursim_core.matching.single import match_at
from ursim_core.segmentation import Segmentation
from ursim_core.segmentation.graph import region_graph


def grid(n_rows=3, n_cols=3, room=20, wall=2):
    labels = np.zeros((n_rows * room + (n_rows + 1) * wall, n_cols * room + (n_cols + 1) * wall), np.int32)
    for index in range(n_rows * n_cols):
        row, col = divmod(index, n_cols)
        top, left = wall + row * (room + wall), wall + col * (room + wall)
        labels[top : top + room, left : left + room] = index + 1
    # Doors between horizontal and vertical neighbours: a connected 3 x 3 grid of rooms.
    for index in range(n_rows * n_cols):
        row, col = divmod(index, n_cols)
        top, left = wall + row * (room + wall), wall + col * (room + wall)
        if col + 1 < n_cols:
            labels[top + room // 2, left + room : left + room + wall] = index + 1
        if row + 1 < n_rows:
            labels[top + room : top + room + wall, left + room // 2] = index + 1
    return labels


@pytest.fixture(scope="module")
def pair():
    # The same plan at two sizes, with the corner room 9 enlarged so that the plan has one
    # reading (the grid's symmetries would otherwise give several equally good answers).
    segmentations = []
    for room in (20, 30):
        labels = grid(room=room)
        labels[labels == 8] = 9
        segmentations.append(Segmentation(labels=labels, graph=region_graph(labels), method="label-image"))
    return segmentations


UPRIGHT = MatchConfig(orientation="upright")


def test_without_constraints_the_plan_matches_itself(pair):
    result = match(*pair, config=UPRIGHT)
    assert sorted(result.pairs) == [(n, n) for n in (1, 2, 3, 4, 5, 6, 7, 9)]
    assert match(*pair, config=UPRIGHT, constraints=MatchConstraints()).pairs == result.pairs


@pytest.mark.parametrize("config", [UPRIGHT, MatchConfig(), MatchConfig(matcher="hungarian", orientation="upright")])
def test_fixed_pairs_are_in_every_answer(pair, config):
    constraints = MatchConstraints(fixed=[(1, 3), (3, 1)])
    result = match(*pair, config=config, constraints=constraints)
    assert {(1, 3), (3, 1)} <= set(result.pairs)
    sketch, metric = zip(*result.pairs)
    assert len(set(sketch)) == len(sketch) and len(set(metric)) == len(metric)
    # At every m, even one below every c (no seed at all).
    prepared = prepare(*pair, config=config.replace(orientation="upright"), constraints=constraints)
    for m in (0.0, 0.2, 0.5):
        assert {(1, 3), (3, 1)} <= set(match_at(prepared, m).pairs)


@pytest.mark.parametrize("matcher", ["planar", "hungarian"])
def test_forbidden_pairs_and_excluded_regions_are_never_proposed(pair, matcher):
    config = UPRIGHT.replace(matcher=matcher)
    constraints = MatchConstraints(forbidden=[(5, 5), (2, 2)], excluded_sketch=[4], excluded_metric=[6])
    result = match(*pair, config=config, constraints=constraints)
    assert result.pairs
    assert not {(5, 5), (2, 2)} & set(result.pairs)
    assert all(a != 4 and b != 6 for a, b in result.pairs)


def test_a_fixed_pair_steers_the_orientation(pair):
    # Told nothing, the plan reads upright; a person who pairs the corner rooms across says it
    # is a mirror image, and the rest of the answer follows that reading.
    mirrored = MatchConstraints(fixed=[(1, 3), (9, 7)])
    result = match(*pair, config=MatchConfig(m=0.3), constraints=mirrored)
    assert result.orientation[1] is True
    assert {(2, 2), (5, 5), (4, 6), (6, 4)} <= set(result.pairs)


def test_constraints_name_unknown_regions_and_matchers_that_cannot_take_them(pair):
    with pytest.raises(ParameterError, match=r"sketch region\(s\) 42 not in the sketch segmentation"):
        match(*pair, constraints=MatchConstraints(fixed=[(42, 1)]))
    with pytest.raises(ParameterError, match=r"metric region\(s\) 8 not in the metric segmentation"):
        match(*pair, constraints=MatchConstraints(excluded_metric=[8]))
    with pytest.raises(ParameterError, match="need the planar, Hungarian or overlay matcher, not 'vf2'"):
        match(*pair, config=MatchConfig(matcher="vf2"), constraints=MatchConstraints(fixed=[(1, 1)]))


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"fixed": [(1, 2), (3, 2)]}, "metric region 2 is in two fixed pairs"),
        ({"fixed": [(1, 2)], "forbidden": [(1, 2)]}, "both fixed and forbidden"),
        ({"fixed": [(1, 2)], "excluded_sketch": [1]}, "sketch region 1 is both fixed and excluded"),
    ],
)
def test_contradictory_constraints_are_refused(fields, message):
    with pytest.raises(ParameterError, match=message):
        MatchConstraints(**fields)


def test_planar_match_expands_from_the_fixed_pairs():
    # A path 0-1-2-3 against itself with no seed at all: the fixed middle pair brings its
    # neighbours, and they bring theirs.
    path = PlanarGraph(nodes=[0, 1, 2, 3], neighbours=[[1], [0, 2], [1, 3], [2]], edges=[(0, 1), (1, 2), (2, 3)])
    same = np.eye(4, dtype=bool)
    fixed = index_constraints(MatchConstraints(fixed=[(1, 1)]), path.nodes, path.nodes)
    result = planar_match(path, path, same, seeds=[], constraints=fixed)
    assert sorted(result.pairs) == [(0, 0), (1, 1), (2, 2), (3, 3)]
    blocked = index_constraints(MatchConstraints(fixed=[(1, 1)], forbidden=[(3, 3)]), path.nodes, path.nodes)
    assert sorted(planar_match(path, path, same, seeds=[], constraints=blocked).pairs) == [(0, 0), (1, 1), (2, 2)]


def test_constraints_from_a_review():
    cliques = [
        Clique(id=1, sketch_regions=(1,), metric_regions=(1,), source="auto", status="accepted"),
        Clique(id=2, sketch_regions=(2,), metric_regions=(3,), source="auto", status="rejected"),
        Clique(id=3, sketch_regions=(4,), metric_regions=(4,), source="auto"),
        Clique(id=4, sketch_regions=(5, 6), metric_regions=(5,), source="manual"),
        Clique(id=5, sketch_regions=(7,), metric_regions=(), source="manual"),
        Clique(id=6, sketch_regions=(1,), metric_regions=(8,), source="manual"),
    ]
    constraints = constraints_from_cliques(cliques, sizes={"sketch": {5: 10, 6: 30}, "metric": {}})
    # The larger region of clique 4 is its fixed pair; region 1's second clique cannot add a
    # second partner, so its metric region is left alone instead.
    assert constraints.fixed == ((1, 1), (6, 5))
    assert constraints.forbidden == {(2, 3)}
    assert constraints.excluded_sketch == {5, 7} and constraints.excluded_metric == {8}
    assert not constraints_from_cliques(cliques[2:3])


def test_right_fixed_pairs_keep_the_answer_right():
    """Pairs reached only through the fixed pairs used to consume the seeds they met, so the seed
    of the best hypothesis never started one: ten right pairs fixed cut 983 right pairs to 908."""
    from ursim_core.bench.matching import perturbed_copy, random_region_graph

    sketch = random_region_graph(1000, seed=3)
    metric, truth = perturbed_copy(sketch, seed=3)
    config = MatchConfig(m=0.2, orientation="upright")

    def right(constraints):
        pairs = match(sketch, metric, config=config, constraints=constraints).pairs
        return sum(truth.get(a) == b for a, b in pairs)

    alone = right(None)
    assert alone > 950
    for count in (10, 100):
        assert right(MatchConstraints(fixed=sorted(truth.items())[:count])) >= alone - 5


def test_two_fixed_pairs_lay_a_robot_map_as_control_points_do():
    # The same plan turned by 180 degrees, shifted and cut; told (wrongly) that it is upright, the
    # overlay search cannot find it. Two pairs a person gives lay it right, and every room follows.
    labels = grid(room=24)
    labels[labels == 8] = 9
    turned = np.zeros((labels.shape[0] + 30, labels.shape[1] + 20), labels.dtype)
    turned[20 : 20 + labels.shape[0], 5 : 5 + labels.shape[1]] = np.rot90(labels, 2)
    sketch = Segmentation(labels=labels, graph=region_graph(labels), method="label-image")
    metric_graph = region_graph(turned)
    metric = Segmentation(labels=turned, graph=metric_graph, method="label-image")
    # A room of the sketch is the metric region at its centroid turned by 180 degrees.
    partner = {}
    for region, (row, col) in sketch.graph.nodes(data="centroid"):
        spot = (20 + labels.shape[0] - 1 - round(row), 5 + labels.shape[1] - 1 - round(col))
        partner[region] = int(turned[spot])
    config = MatchConfig(matcher="overlay", orientation=0, mirrored=False, scale=1.0)
    told_upright = set(match(sketch, metric, config=config).pairs)
    assert len(told_upright & set(partner.items())) < len(partner) // 2
    fixed = [(1, partner[1]), (9, partner[9])]
    result = match(sketch, metric, config=config, constraints=MatchConstraints(fixed=fixed))
    assert set(result.pairs) == set(partner.items()) and round(result.orientation[0]) == 180
    forbidden = MatchConstraints(fixed=fixed, forbidden=[(5, partner[5])])
    assert (5, partner[5]) not in match(sketch, metric, config=config, constraints=forbidden).pairs
