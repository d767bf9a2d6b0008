"""The generated-pair invariance benchmark: transformations move the sketch and its points alike."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.bench.invariance import KINDS, _parameters, run_case, transformed_sketch, undoing_orientation
from ursim_core.synth import make_pair


@pytest.mark.parametrize("kind", KINDS)
def test_points_stay_on_the_place_they_were_on(kind):
    _, sketch = make_pair(seed=3)
    rows, cols = np.nonzero(sketch.rooms)
    pick = np.linspace(0, len(rows) - 1, 200).astype(int)
    points = list(zip(rows[pick].tolist(), cols[pick].tolist()))
    degrees, mirrored, scale, kept = _parameters(3, kind)
    # The place ids drawn as an image go through the same transformation as the free space.
    for place in np.unique(sketch.rooms[rows[pick], cols[pick]])[:6]:
        image, moved = transformed_sketch(
            sketch.rooms == place, points, degrees=degrees, mirrored=mirrored, scale=scale, kept=kept, seed=3
        )
        on_place = [p for p, q in zip(points, moved) if q is not None and sketch.rooms[p] == place]
        landed = [image[q] for p, q in zip(points, moved) if q is not None and sketch.rooms[p] == place]
        if on_place:
            # Nearest-pixel rounding can put a border point one pixel off its place.
            assert np.mean(landed) > 0.9, (kind, place)
    if kept < 1.0:
        assert any(q is None for q in moved) and any(q is not None for q in moved)
    else:
        assert all(q is not None for q in moved)


def test_parameters_are_reproducible_and_in_range():
    assert _parameters(5, "all") == _parameters(5, "all")
    degrees, mirrored, scale, kept = _parameters(5, "all")
    assert 0 <= degrees < 360 and mirrored and 0.5 <= scale <= 2 and 0.5 <= kept <= 0.8
    assert _parameters(5, "upright") == (0.0, False, 1.0, 1.0)


def test_an_upright_generated_pair_is_scored():
    case = run_case(1, "upright")
    assert case.f1 == pytest.approx(1.0) and case.place_accuracy == pytest.approx(1.0)


@pytest.mark.parametrize("kind", ["turned", "mirrored"])
def test_a_turned_or_mirrored_pair_is_read_in_the_orientation_that_undoes_it(kind):
    case = run_case(1, kind)
    assert case.read_right and case.f1 >= 0.9, case


def test_the_undoing_orientation_brings_the_points_back():
    from ursim_core.matching.alignment import orientation_matrix

    free = np.zeros((40, 60), bool)
    free[5:35, 5:55] = True
    points = [(10, 10), (30, 50), (20, 12)]
    for degrees, mirrored in [(30.0, False), (30.0, True), (250.0, True), (0.0, False)]:
        _, moved = transformed_sketch(free, points, degrees=degrees, mirrored=mirrored)
        # orientation_matrix maps (row, col) of the input to the metric frame, up to a shift.
        matrix = orientation_matrix(**dict(zip(("degrees", "mirrored"), undoing_orientation(degrees, mirrored))))
        back = np.asarray(moved, float) @ matrix.T
        offsets = back - np.asarray(points, float)
        np.testing.assert_allclose(offsets, offsets[:1].repeat(len(points), axis=0), atol=1.5)


@pytest.mark.parametrize("kind", ["cropped", "all"])
def test_told_the_orientation_the_matcher_reads_the_sketch_so(kind):
    # Seed 2 cropped is read as a mirror image when nothing is told (round 44); told, every case
    # is read in the orientation that undoes its transformation, whatever the matcher would rank.
    case = run_case(2, kind, told=True)
    assert case.read_right, case


def test_the_bench_prints_the_told_table_after_the_default_one(monkeypatch, capsys):
    import ursim_core.bench.invariance as invariance
    from ursim_core.bench.runner import run_bench

    calls = []

    shared = []

    def fake(seeds, kinds=KINDS, *, config=None, progress=None, plan_copy=False, told=False, segmentations=None):
        calls.append((tuple(seeds), told, plan_copy))
        shared.append(segmentations)
        return [invariance.InvarianceCase(seeds[0], kind, 0.0, False, 1.0, 1.0, 1.0, 1.0) for kind in kinds]

    monkeypatch.setattr(invariance, "bench_invariance", fake)
    assert run_bench("invariance", seeds=2, first_seed=4, told=True) == 0
    assert calls == [((4, 5), False, False), ((4, 5), True, False), ((4, 5), False, True)]
    assert "told each sketch's orientation" in capsys.readouterr().out
    # The told table reuses the first table's segmentations; the robot-map copies are other images.
    assert shared[0] is shared[1] and isinstance(shared[0], dict) and shared[2] is None
    calls.clear()
    run_bench("invariance", seeds=2, first_seed=4)
    assert [told for _, told, _ in calls] == [False, False]


def test_a_case_matched_again_reuses_its_segmentation_and_scores_the_same():
    kept = {}
    first = run_case(2, "turned", segmentations=kept)
    assert len(kept) == 1
    (segmentation,) = kept.values()
    again = run_case(2, "turned", segmentations=kept)
    assert kept == {next(iter(kept)): segmentation} and again == first
    told = run_case(2, "turned", told=True, segmentations=kept)
    assert len(kept) == 1 and told.read_right


def test_a_partial_sketch_read_as_its_mirror_image_is_read_right_once_broken_doors_count():
    # Seed 1 cropped (half of a corridor lined with rooms): its mirror image fits the room sizes
    # better, but joins rooms that are not neighbours (MatchConfig.adjacency_penalty, round 44).
    # Every partner the laying finds is kept, so that the reading alone is tested: with the default
    # elastic_partners two rooms keep the graph answer's wrong partners and lose the right ones,
    # walled off from them (F1 0.57 against 0.75).
    from ursim_core.matching import MatchConfig

    every = MatchConfig(elastic_partners="all")
    without = run_case(1, "cropped", config=every.replace(adjacency_penalty=0.0))
    default = run_case(1, "cropped", config=every)
    assert not without.read_right and without.f1 < 0.2
    assert default.read_right and default.f1 >= 0.7
    assert run_case(1, "cropped").read_right


def test_a_plan_symmetric_but_for_its_doors_is_read_right_once_the_doors_count():
    # Seed 37: the two rows of rooms are within a few pixels of each other, and the sketch leaves
    # out the corridor that told them apart. Its mirror image fits sizes and neighbours as well,
    # but puts every door at the other end of its wall (MatchConfig.door_penalty, round 46).
    from ursim_core.matching import MatchConfig

    without = run_case(37, "upright", config=MatchConfig(door_penalty=0.0))
    default = run_case(37, "upright")
    assert not without.read_right and without.f1 < 0.2
    assert default.read_right and default.f1 >= 0.9
    # A partial sketch too: seed 15 cropped, read as its half turn without the doors.
    assert not run_case(15, "cropped", config=MatchConfig(door_penalty=0.0)).read_right
    assert run_case(15, "cropped").read_right
