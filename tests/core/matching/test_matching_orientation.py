"""Orientation-free matching: candidates, turned graphs, and invariance on generated pairs."""

from __future__ import annotations

import functools

import networkx as nx
import numpy as np
import pytest

from ursim_core.correspondences import regions_at_points
from ursim_core.errors import ParameterError
from ursim_core.evaluation import augment
from ursim_core.evaluation.scoring import score_matches
from ursim_core.matching import MatchConfig, match, prepare
from ursim_core.matching.orientation import (
    UNRELATED_DOOR,
    broken_adjacencies,
    misplaced_doors,
    next_reading,
    orientation_candidates,
    oriented_graph,
    ranked_readings,
    region_outlines,
    same_reading,
    transform_points,
)
from ursim_core.matching.positions import region_positions
from ursim_core.segmentation import region_graph, segment_canonical
from ursim_core.segmentation.canonical import _turned
from ursim_core.synth import ground_truth_correspondences, make_pair


def test_candidates_cover_quarter_turns_and_mirrors_of_the_wall_difference():
    candidates = orientation_candidates(sketch_angle=20.0, metric_angle=5.0)
    assert len(candidates) == 8 and len(set(candidates)) == 8
    plain = sorted(d for d, m in candidates if not m)
    assert plain == pytest.approx([75.0, 165.0, 255.0, 345.0])
    mirrored = sorted(d for d, m in candidates if m)
    assert mirrored == pytest.approx([25.0, 115.0, 205.0, 295.0])
    assert orientation_candidates(orientation="upright") == [(0.0, False)]
    assert orientation_candidates(orientation=-90, mirrored=True) == [(270.0, True)]


def test_transform_points_turns_counter_clockwise_on_screen():
    # (row, col): a point to the right of the origin goes up (smaller row) when turned by 90 degrees.
    assert transform_points(np.array([[0.0, 1.0]]), degrees=90, mirrored=False).round(9).tolist() == [[-1.0, 0.0]]
    assert transform_points(np.array([[2.0, 1.0]]), degrees=0, mirrored=True).tolist() == [[2.0, -1.0]]


def test_oriented_graph_moves_positions_and_keeps_everything_else():
    graph = nx.Graph()
    graph.add_node(1, centroid=(10.0, 20.0), bbox=(0, 10, 20, 30), size=5)
    graph.add_node(2, centroid=(30.0, 20.0), bbox=(20, 10, 40, 30), size=7)
    graph.add_edge(1, 2, boundary=3)
    turned = oriented_graph(graph, degrees=90, mirrored=False)
    assert turned is not graph and graph.nodes[1]["centroid"] == (10.0, 20.0)
    assert turned.nodes[1]["size"] == 5 and turned.edges[1, 2]["boundary"] == 3
    expected = transform_points(np.array([[10.0, 20.0]]), degrees=90, mirrored=False)[0]
    assert turned.nodes[1]["centroid"] == pytest.approx(tuple(expected))
    assert oriented_graph(graph, degrees=0, mirrored=False) is graph


def _three_rooms() -> np.ndarray:
    labels = np.zeros((120, 200), np.int32)
    labels[10:110, 10:80] = 1  # a room
    labels[40:60, 80:150] = 2  # a corridor
    labels[20:100, 150:190] = 3  # another room
    labels[20:40, 120:150] = 3  # with a wing: not a rectangle
    return labels


def test_region_outlines_span_each_region_box():
    labels = _three_rooms()
    graph = region_graph(labels)
    outlines = region_outlines(graph, labels)
    assert sorted(outlines) == [1, 2, 3]
    for node, box in graph.nodes(data="bbox"):
        assert outlines[node].min(axis=0).tolist() == [box[0], box[1]]
        assert outlines[node].max(axis=0).tolist() == [box[2], box[3]]


def _span(graph) -> np.ndarray:
    """(rows, cols) of the union of a graph's region boxes: what the positions are normalised to."""
    boxes = np.array([box for _, box in graph.nodes(data="bbox")], float)
    return boxes[:, 2:].max(axis=0) - boxes[:, :2].min(axis=0)


@pytest.mark.parametrize("degrees", [30.0, 45.0, 160.0])
def test_a_map_drawn_at_an_angle_turned_back_gets_its_upright_positions(degrees):
    # Drawn at an angle, each region's box (in the drawn frame) already holds the turned room; the
    # box around that box turned back grows again. The positions are normalised to the union of
    # the boxes, so they shrank towards the middle; from the outlines they are the upright ones.
    labels = _three_rooms()
    upright = region_graph(labels)
    drawn = augment.transform_image(labels, augment.Orientation(degrees), fill=0)
    graph = region_graph(drawn)
    back = (-degrees) % 360.0
    loose = oriented_graph(graph, degrees=back, mirrored=False)
    tight = oriented_graph(graph, degrees=back, mirrored=False, outlines=region_outlines(graph, drawn))
    expected = region_positions(upright)
    assert np.abs(region_positions(tight) - expected).max() < 0.02
    assert np.abs(region_positions(loose) - expected).max() > 0.05
    assert np.allclose(_span(tight), _span(upright), atol=3)


@pytest.mark.parametrize("degrees, mirrored", [(30.0, False), (161.5, True), (301.25, False)])
def test_the_boxes_of_turned_outlines_are_each_outlines_own(degrees, mirrored):
    """All outlines are turned together; each box is the one around that region's turned
    outline, bit for bit, and a region without an outline keeps the box around its turned box."""
    from ursim_core.matching.orientation import transform_points

    labels = _three_rooms()
    graph = region_graph(labels)
    outlines = region_outlines(graph, labels)
    missing = sorted(outlines)[0]
    del outlines[missing]
    turned = oriented_graph(graph, degrees=degrees, mirrored=mirrored, outlines=outlines)
    for node, outline in outlines.items():
        points = transform_points(outline, degrees=degrees, mirrored=mirrored)
        expected = (*points.min(axis=0).tolist(), *points.max(axis=0).tolist())
        assert turned.nodes[node]["bbox"] == expected
    plain = oriented_graph(graph, degrees=degrees, mirrored=mirrored)
    assert turned.nodes[missing]["bbox"] == plain.nodes[missing]["bbox"]


def test_outlines_leave_quarter_turns_and_mirrors_alone():
    labels = _three_rooms()
    graph = region_graph(labels)
    outlines = region_outlines(graph, labels)
    for degrees, mirrored in [(90.0, False), (180.0, True), (270.0, False), (0.0, True)]:
        plain = oriented_graph(graph, degrees=degrees, mirrored=mirrored)
        given = oriented_graph(graph, degrees=degrees, mirrored=mirrored, outlines=outlines)
        assert dict(plain.nodes(data="bbox")) == dict(given.nodes(data="bbox"))


def test_config_validates_orientation_and_mirrored():
    for bad in ("sideways", float("nan"), True):
        with pytest.raises(ParameterError, match="orientation"):
            MatchConfig(orientation=bad)
    with pytest.raises(ParameterError, match="mirrored"):
        MatchConfig(mirrored="yes")
    assert MatchConfig.paper().orientation == "upright" and MatchConfig.released().mirrored is False


@functools.cache
def _generated_segmentations(seed: int):
    plan, sketch = make_pair(seed=seed)
    return segment_canonical(sketch.free, preset="default"), segment_canonical(plan.free, preset="default")


def test_known_orientation_is_used_as_given():
    s, m = _generated_segmentations(1)
    prepared = prepare(s, m, MatchConfig(orientation=90, mirrored=True))
    assert prepared.orientation == (90.0, True) and prepared.orientation_scan == {}
    result = match(s, m)
    assert result.orientation in result.orientation_scan
    assert result.orientation_scan[result.orientation] == min(result.orientation_scan.values())


def test_config_validates_orientation_finalists():
    for bad in (0, -2, 2.5, True, "4"):
        with pytest.raises(ParameterError, match="orientation_finalists"):
            MatchConfig(orientation_finalists=bad)


def test_the_best_screened_orientations_get_the_full_sweep():
    sketch_seg, metric_seg = _generated_segmentations(1)
    tried = {
        finalists: prepare(sketch_seg, metric_seg, MatchConfig(orientation_finalists=finalists)).orientation_scan
        for finalists in (1, 3, 4, 8)
    }
    # Eight candidates (four turns, mirrored or not): the k best of one screening are finalists.
    assert [len(tried[k]) for k in (1, 3, 4, 8)] == [1, 3, 4, 8]
    assert set(tried[1]) < set(tried[3]) < set(tried[4]) < set(tried[8])
    assert MatchConfig().orientation_finalists == 4


def test_ranked_readings_are_the_chosen_one_then_one_orientation_per_other_reading_best_first():
    scan = {
        (90.3, False): 0.40,
        (89.8, False): 0.45,  # the same reading as the chosen one: not another
        (180.0, True): 0.60,
        (179.5, True): 0.50,  # the best of its reading stands for it
        (0.0, False): 0.44,
        (270.0, False): float("nan"),  # no rank value: left out
    }
    ranked = ranked_readings((90.0, False), scan)
    assert [reading for reading, _ in ranked] == [(90.0, False), (0.0, False), (179.5, True)]
    assert [gap for _, gap in ranked] == pytest.approx([0.0, 0.1, 0.25])
    # A vote by count may choose a reading another one outranks: its gap is negative.
    assert ranked_readings((0.0, False), scan)[1] == ((90.3, False), pytest.approx(-1 / 11))


def test_the_runner_up_is_the_second_ranked_reading():
    rng = np.random.default_rng(3)
    orientations = [(float(d), m) for d in (0.0, 0.4, 90.0, 180.0, 270.0) for m in (False, True)]
    for _ in range(200):
        kept = rng.choice(len(orientations), size=rng.integers(1, len(orientations)), replace=False)
        scan = {orientations[k]: float(rng.choice([0.0, rng.uniform(0.1, 1.0), np.inf])) for k in kept}
        chosen = orientations[kept[0]]
        ranked = ranked_readings(chosen, scan)
        assert next_reading(chosen, scan) == (ranked[1] if len(ranked) > 1 else None)
        values = [min(v for o, v in scan.items() if np.isfinite(v) and same_reading(o, r)) for r, _ in ranked[1:]]
        assert values == sorted(values)  # the others from the best ranked


def test_config_validates_adjacency_penalty():
    for bad in (-1, float("nan"), True, "2"):
        with pytest.raises(ParameterError, match="adjacency_penalty"):
            MatchConfig(adjacency_penalty=bad)
    # The paper's method and the released code's options rank by their own score alone.
    assert MatchConfig.paper().adjacency_penalty == 0 == MatchConfig.released().adjacency_penalty


def test_broken_adjacencies_counts_edges_whose_partners_are_not_neighbours():
    sketch = nx.Graph([(1, 2), (2, 3), (3, 4)])
    metric = nx.Graph([(10, 11), (11, 12)])
    # Region 4 is unpaired, so its edge does not count; one neighbouring partner of a region
    # paired twice is enough.
    assert broken_adjacencies([(1, 10), (2, 11), (2, 12), (3, 10)], sketch, metric) == 0.0
    # (1, 2) lands on 10 and 12, which do not touch; (2, 3) on 12 and 11, which do.
    assert broken_adjacencies([(1, 10), (2, 12), (3, 11)], sketch, metric) == pytest.approx(0.5)
    assert broken_adjacencies([(1, 12), (2, 10), (3, 12), (4, 10)], sketch, metric) == pytest.approx(1.0)
    assert broken_adjacencies([(1, 10)], sketch, metric) == 0.0


def test_config_validates_door_penalty():
    for bad in (-0.5, float("inf"), False, "1"):
        with pytest.raises(ParameterError, match="door_penalty"):
            MatchConfig(door_penalty=bad)
    assert MatchConfig.paper().door_penalty == 0 == MatchConfig.released().door_penalty


def _comb(doors_at: list[float]) -> nx.Graph:
    """A corridor (region 1, rows 10-20, columns 0-40) with rooms 2, 3, 4 above it (rows 0-10, ten
    columns each), each touching it at the column ``doors_at`` gives."""
    graph = nx.Graph()
    graph.add_node(1, centroid=(15.0, 20.0), bbox=(10, 0, 20, 40))
    for room, door in zip((2, 3, 4), doors_at):
        left = 10.0 * (room - 2)
        graph.add_node(room, centroid=(5.0, left + 5.0), bbox=(0, left, 10, left + 10))
        graph.add_edge(1, room, contact=(10.0, left + door))
    return graph


def test_misplaced_doors_measures_where_paired_regions_touch():
    metric = _comb([2.0, 2.0, 8.0])
    assert misplaced_doors([(1, 1), (2, 2), (3, 3), (4, 4)], _comb([2.0, 2.0, 8.0]), metric) == 0.0
    # The same rooms with room 2's door at the other end of its wall: 1.2 box halves off, seen
    # from the room and (1.2 x 5 px) / 20 px from the corridor; the mean over the six contacts.
    moved = misplaced_doors([(1, 1), (2, 2), (3, 3), (4, 4)], _comb([8.0, 2.0, 8.0]), metric)
    assert moved == pytest.approx((1.2 + 0.3) / 6)
    # A contact the answer does not carry to the map counts as an unrelated door.
    unpaired = misplaced_doors([(1, 1), (2, 2), (3, 3)], _comb([2.0, 2.0, 8.0]), metric)
    assert unpaired == pytest.approx(2 * UNRELATED_DOOR / 6)
    # No contacts at all (a graph from elsewhere): nothing to say.
    assert misplaced_doors([(1, 1)], nx.Graph([(1, 2)]), metric) == 0.0


def test_turned_graphs_carry_their_contacts_along():
    graph = _comb([2.0, 2.0, 8.0])
    turned = oriented_graph(graph, degrees=180, mirrored=False)
    assert turned.edges[1, 2]["contact"] == pytest.approx((-10.0, -2.0))
    # Turned alike, the doors are where they were from every region.
    assert misplaced_doors([(n, n) for n in graph], turned, oriented_graph(graph, degrees=180, mirrored=False)) == 0
    mirrored = oriented_graph(graph, degrees=0, mirrored=True)
    assert mirrored.edges[1, 4]["contact"] == pytest.approx((10.0, -28.0))
    # The mirror image read against the map puts every door at the other end of its wall.
    assert misplaced_doors([(n, n) for n in graph], mirrored, graph) > 0


def test_a_reading_that_breaks_adjacencies_ranks_worse_by_the_penalty():
    sketch_seg, metric_seg = _generated_segmentations(1)
    plain = prepare(sketch_seg, metric_seg, MatchConfig(adjacency_penalty=0.0)).orientation_scan
    penalised = prepare(sketch_seg, metric_seg, MatchConfig(adjacency_penalty=2.0)).orientation_scan
    assert set(penalised) == set(plain) and len(plain) > 1
    # The answers do not depend on the penalty, only their rank values: 1 to 3 times as high.
    for orientation, value in plain.items():
        assert value - 1e-12 <= penalised[orientation] <= 3 * value + 1e-12, orientation
    best = min(plain, key=plain.get)
    assert penalised[best] == pytest.approx(plain[best])  # the right reading keeps every door
    assert any(penalised[o] > plain[o] * 1.01 for o in plain)  # the others break some


# --- invariance of the whole pipeline on generated pairs (ground truth transformed alike) ---


def _moved(free: np.ndarray, points: list, kind: str):
    rows, cols = free.shape
    if kind.startswith("dihedral"):
        turn = augment.Orientation(90.0 * int(kind[-2]), mirrored=kind[-1] == "m")
        return augment.transform_image(free, turn), augment.transform_points(points, free.shape, turn)
    if kind.startswith("angle"):
        image, matrix = _turned(free, float(kind[5:]))
        xy = np.array([(c, r, 1.0) for r, c in points]) @ matrix.T
        return image, [(round(y), round(x)) for x, y in xy]
    scale = float(kind[5:])
    import cv2

    image = cv2.resize(free.astype(np.uint8) * 255, (round(cols * scale), round(rows * scale))) >= 128
    return image, [(int(r * scale), int(c * scale)) for r, c in points]


@functools.cache
def _f1(seed: int, kind: str) -> float:
    plan, sketch = make_pair(seed=seed)
    truth = ground_truth_correspondences(plan, sketch)
    flat = [p for clique in truth.cliques for p in clique.sketch_points]
    image, moved = _moved(sketch.free, flat, kind)
    s, m = segment_canonical(image, preset="default"), segment_canonical(plan.free, preset="default")
    result = match(s, m)
    points = iter(moved)
    reference = []
    for clique in truth.cliques:
        sketch_points = [next(points) for _ in clique.sketch_points]
        reference.append(
            (
                {r for r in regions_at_points(s.labels, sketch_points) if r},
                {r for r in regions_at_points(m.labels, clique.metric_points) if r},
            )
        )
    return score_matches(result.pairs, reference).f1


SEEDS = (0, 1, 2, 3)
#: Mean F1 over SEEDS measured with this code (upright 0.988). Before the orientations were ranked
#: by score over free-space overlap, seed 0 turned by a free angle was a near tie between the right
#: turn and the half turn and lost: 0.746 and 0.694 for the two angles.
MEASURED = {"angle30": 0.960, "angle-65": 0.864, "scale0.5": 0.972, "scale1.6": 1.0}


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["dihedral1r", "dihedral2r", "dihedral3r", "dihedral0m", "dihedral1m", "dihedral2m"])
def test_turned_and_mirrored_sketches_match_exactly_as_upright(kind):
    for seed in SEEDS:
        assert _f1(seed, kind) == pytest.approx(_f1(seed, "dihedral0r"), abs=1e-9), seed


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["angle30", "angle-65", "scale0.5", "scale1.6"])
def test_sketches_turned_by_any_angle_or_rescaled_match_about_as_well(kind):
    # A free angle resamples the sketch (its segmentation changes a little) and a scale changes
    # MAORIS' pixel-sized thresholds, so these are not exact; measured per kind in MEASURED.
    upright = np.mean([_f1(seed, "dihedral0r") for seed in SEEDS])
    moved = np.mean([_f1(seed, kind) for seed in SEEDS])
    assert upright >= 0.9
    assert moved >= MEASURED[kind] - 0.05, (kind, moved, upright)


def test_a_partial_sketch_is_read_where_it_resembles_part_of_the_map():
    # Generated pair 22 cropped to 57 % of its sketch: the planar ranking reads it mirrored and
    # half turned (F1 0.10 in round 48's study); read upright it resembles a part of the plan
    # clearly better (best window correlation 0.89 against 0.69), and with the margin it is read so.
    # Every partner the laying finds is kept, so that the reading alone is tested: with the default
    # elastic_partners two rooms keep the graph answer's wrong partners and lose the right ones,
    # walled off from them (F1 0.78 against 0.90).
    from ursim_core.bench.invariance import run_case

    every = MatchConfig(elastic_partners="all")
    ranked = run_case(22, "cropped", config=every)
    windowed = run_case(22, "cropped", config=every.replace(window_reading_margin=0.1))
    assert windowed.read_right and windowed.f1 >= 0.85 and windowed.f1 >= ranked.f1
    assert run_case(22, "cropped", config=MatchConfig(window_reading_margin=0.1)).read_right
    # A whole sketch resembles no part of the plan better than the whole: read as before.
    whole = run_case(22, "mirrored", config=MatchConfig(window_reading_margin=0.1))
    assert whole.read_right and whole.f1 == run_case(22, "mirrored").f1


def test_the_window_reading_needs_a_window_laying_and_a_margin():
    from ursim_core.matching.oriented import window_reading

    windows = {"ranked": (0.70, 0.05), "partial": (0.85, 0.25), "weak": (0.95, 0.05)}
    # Only a reading in which the sketch looks partial (gain >= WINDOW_GAIN) is taken.
    assert window_reading(windows, "ranked", margin=0.1) == "partial"
    assert window_reading(windows, "ranked", margin=0.2) is None
    assert window_reading({"ranked": None, "partial": (0.9, 0.3)}, "ranked", margin=0.1) is None
    with pytest.raises(ParameterError, match="window_reading_margin"):
        MatchConfig(window_reading_margin=-1)


def test_a_partial_sketch_laid_in_its_window_starts_the_refit_there():
    # Generated pair 4 cropped (upright, 70 % of the sketch kept) is read flipped by the planar
    # ranking (F1 0.24 in round 50's study): its positions, normalised to each map's extent,
    # stretch the part over the whole plan. Laid in the window it resembles, the right reading
    # scores lower and is read so.
    from ursim_core.bench.invariance import run_case

    ranked = run_case(4, "cropped")
    laid = run_case(4, "cropped", config=MatchConfig(window_start=True))
    assert not ranked.read_right and laid.read_right and laid.f1 >= 0.9
    # A whole sketch resembles no part of the plan clearly better than the whole: as before.
    whole = run_case(4, "mirrored", config=MatchConfig(window_start=True))
    assert whole.read_right and whole.f1 == run_case(4, "mirrored").f1


def test_the_window_starts_are_found_once_and_carried_to_the_other_segmentations():
    from ursim_core.matching import prepare
    from ursim_core.segmentation import segment_canonical
    from ursim_core.synth import make_pair

    plan, sketch = make_pair(seed=43)
    from ursim_core.bench.invariance import transformed_sketch

    image, _ = transformed_sketch(sketch.free, [], degrees=40.0, kept=0.6, seed=43)
    sketch_seg = segment_canonical(image, preset="default", resampled=True)
    plan_seg = segment_canonical(plan.free, preset="default")
    prepared = prepare(sketch_seg, plan_seg, MatchConfig(window_start=True))
    starts = prepared.orientation_window_starts
    assert any(start is not None for start in starts.values())
    assert prepared.resampled is not None and prepared.resampled.variants
    for _, other in prepared.resampled.variants:
        for orientation, start in other.orientation_window_starts.items():
            nearest = min(
                (key for key in starts if key[1] == orientation[1]),
                key=lambda key: abs((key[0] - orientation[0] + 180) % 360 - 180),
            )
            assert (start is None and starts[nearest] is None) or start is starts[nearest]
    # Without the option nothing is found.
    assert not prepare(sketch_seg, plan_seg, MatchConfig()).orientation_window_starts
    with pytest.raises(ParameterError, match="window_start"):
        MatchConfig(window_start="yes")


def test_the_reading_and_the_refit_search_the_finalists_windows_once(monkeypatch):
    # With both window_reading_margin and window_start (as --partial), each finalist's window is
    # searched once for both; only the laying's own search comes on top.
    from ursim_core.bench.invariance import run_case
    from ursim_core.matching import template

    calls = []
    search = template.best_window
    monkeypatch.setattr(template, "best_window", lambda *a, **k: calls.append(1) or search(*a, **k))
    # (Not matched again as a partial sketch: that would search again, with the partial options.)
    run_case(4, "cropped", config=MatchConfig(window_start=True, auto_partial=False))
    alone = len(calls)
    calls.clear()
    both = run_case(4, "cropped", config=MatchConfig(window_start=True, window_reading_margin=0.1, auto_partial=False))
    assert len(calls) == alone and both.read_right
    calls.clear()
    run_case(4, "cropped", config=MatchConfig(window_reading_margin=0.1, auto_partial=False))
    assert len(calls) == alone


def test_a_sketch_laid_in_part_of_the_map_is_matched_again_as_a_partial_sketch():
    # Generated pair 72 cropped (upright, 54 % of the sketch kept) is laid in the window it
    # resembles, so it looks partial; matched again with --partial's options it is read right
    # (round 50: F1 0.13 -> 1.00). auto_partial=False keeps the first answer.
    from ursim_core.bench.invariance import _parameters, run_case, transformed_sketch
    from ursim_core.matching import match
    from ursim_core.matching.config import PARTIAL_SKETCH
    from ursim_core.matching.partial import PARTIAL_NOTE
    from ursim_core.segmentation import segment_canonical
    from ursim_core.synth import make_pair

    first = run_case(72, "cropped", config=MatchConfig(auto_partial=False))
    again = run_case(72, "cropped")
    assert not first.read_right and again.read_right and again.f1 >= 0.9
    plan, sketch = make_pair(seed=72)
    degrees, mirrored, scale, kept = _parameters(72, "cropped")
    image, _ = transformed_sketch(sketch.free, [], degrees=degrees, mirrored=mirrored, scale=scale, kept=kept, seed=72)
    plan_seg = segment_canonical(plan.free, preset="default")
    result = match(segment_canonical(image, preset="default", resampled=True), plan_seg)
    assert PARTIAL_NOTE in result.reason
    assert all(getattr(result.config, name) == value for name, value in PARTIAL_SKETCH.items())
    # A whole sketch is not laid in a window: the first answer stands, with the default options.
    whole = match(segment_canonical(sketch.free, preset="default", resampled=True), plan_seg)
    assert PARTIAL_NOTE not in whole.reason and whole.config.window_start is False
    with pytest.raises(ParameterError, match="auto_partial"):
        MatchConfig(auto_partial=1)
