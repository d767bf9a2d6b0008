"""The clearance watershed with saddle-ratio doors, and the leave-one-map-out figures."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.segmentation import SEGMENTERS, segment
from ursim_core.segmentation.presets_cv import BenchmarkMap, Candidate, cross_validate
from ursim_core.segmentation.watershed import watershed_labels


def _two_rooms(door_width: int) -> np.ndarray:
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = free[5:55, 70:125] = True
    free[30 - door_width // 2 : 30 + (door_width + 1) // 2, 60:70] = True
    return free


def test_a_narrow_door_separates_two_rooms_and_a_wide_opening_does_not():
    assert int(watershed_labels(_two_rooms(6)).max()) == 2
    assert int(watershed_labels(_two_rooms(48)).max()) == 1


def test_a_long_corridor_is_one_region_and_obstacles_stay_zero():
    free = np.zeros((40, 400), bool)
    free[10:30, 5:395] = True
    labels = watershed_labels(free)
    assert int(labels.max()) == 1
    assert not labels[~free].any()
    assert labels[free].all()


def test_door_ratio_one_keeps_every_basin_and_zero_merges_all_touching_ones():
    free = _two_rooms(6)
    assert int(watershed_labels(free, door_ratio=0.0).max()) == 1
    assert int(watershed_labels(free, door_ratio=1.0, min_size=0).max()) >= 2


def test_small_regions_join_a_neighbour_and_isolated_specks_are_dropped():
    free = _two_rooms(6)
    free[0, 0] = True  # an isolated free pixel
    labels = watershed_labels(free, min_size=200)
    assert labels[0, 0] == 0
    assert sorted(np.unique(labels).tolist()) == [0, 1, 2]


def test_empty_map_and_bad_parameters():
    assert not watershed_labels(np.zeros((5, 5), bool)).any()
    with pytest.raises(ParameterError, match="door_ratio"):
        watershed_labels(_two_rooms(6), door_ratio=1.5)
    with pytest.raises(ParameterError, match="unknown watershed parameter"):
        watershed_labels(_two_rooms(6), doors=40)
    with pytest.raises(ParameterError, match="preset"):
        segment(_two_rooms(6), method="watershed", preset="icra")


def test_registered_behind_the_interface():
    seg = segment(_two_rooms(6), method="watershed", preset="robot")
    assert seg.method == "watershed" and seg.n_regions == 2 and seg.graph.number_of_edges() == 1
    assert seg.params == {"door_ratio": seg.params["door_ratio"], "min_size": seg.params["min_size"]}


def test_cross_validation_chooses_each_maps_candidate_on_the_other_maps(monkeypatch):
    # Candidate "split" cuts every map in two halves, "whole" keeps it whole; the
    # ground truths of maps 0 and 1 are whole, of map 2 split.
    def fake(free, *, split):
        labels = np.ones(free.shape, np.int32)
        if split:
            labels[:, free.shape[1] // 2 :] = 2
        return labels

    monkeypatch.setitem(SEGMENTERS, "fake", fake)
    whole = np.ones((4, 8), np.int32)
    halves = whole.copy()
    halves[:, 4:] = 2
    benchmark = [
        BenchmarkMap(f"m{i}", np.ones((4, 8), bool), {"a": gt, "b": gt}) for i, gt in enumerate((whole, whole, halves))
    ]
    candidates = [Candidate("fake", {"split": False}), Candidate("fake", {"split": True})]
    cv = cross_validate(benchmark=benchmark, selections={"p": candidates}, fixed={})
    rows = {(r["map"], r["annotator"]): r for r in cv.rows}
    assert rows["m2", "a"]["in_sample_f1"] < 1.0  # chosen on all maps: "whole"
    assert rows["m2", "a"]["cv_choice"] == "fake(split=False)"
    assert rows["m0", "a"]["cv_f1"] == rows["m0", "a"]["in_sample_f1"] == 1.0
    summary = {row["preset"]: row for row in cv.summary()}
    assert summary["p"]["cv_worst"] < summary["p"]["cv_mean"] <= 1.0
    assert summary["annotators' agreement"]["cv_mean"] == 1.0  # a and b agree everywhere


def test_raster_renumbering_is_that_of_the_scoring_module():
    from ursim_core.segmentation.scoring import relabel_in_raster_order
    from ursim_core.segmentation.watershed import _in_raster_order

    rng = np.random.default_rng(1)
    for shape in ((1, 1), (6, 1), (1, 7), (30, 41)):
        labels = rng.choice(np.array([0, 3, 4, 9], np.int32), size=shape)
        assert np.array_equal(_in_raster_order(labels), relabel_in_raster_order(labels))


# Digests of the label images before the speed-up of the basin peaks (np.maximum.at instead
# of ndimage.maximum): a speed change must leave every label where it was.
_ROBOT_MAPS_DIGEST = "4170346fbeb837cea91083c30960d78331d12bbb7d7592dcfbeb710944e4bd30"
_BUILDING_600_DIGEST = "59a6cd8abf64bd5b8f9c8f4ed954bba14e0171e2c6808becacdce63fc8323535"


def test_labels_of_a_generated_building_are_those_before_the_speed_up():
    import hashlib

    from ursim_core.synth import make_large_building

    labels = watershed_labels(make_large_building(600).free)
    assert hashlib.sha256(labels.tobytes()).hexdigest() == _BUILDING_600_DIGEST


def test_labels_of_the_robot_maps_are_those_before_the_speed_up():
    import hashlib

    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
    from ursim_core.segmentation.presets_cv import load_benchmark

    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    digest = hashlib.sha256()
    for item in load_benchmark(root, "robot_maps"):
        digest.update(watershed_labels(item.free).tobytes())
    assert digest.hexdigest() == _ROBOT_MAPS_DIGEST
