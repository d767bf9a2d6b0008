"""From clicked points to region ids (ursim_core.correspondences.assignment): nearest region, cliques, pairs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    assign_regions,
    from_pairs,
    load_correspondences,
    regions_at_points,
    save_correspondences,
)
from ursim_core.errors import RegionsRecomputedWarning, SegmentationError

NOW = "2024-05-01T12:00:00Z"


# --------------------------------------------------------------------------- regions at points


def _two_rooms():
    labels = np.zeros((30, 40), dtype=np.int32)
    labels[0:10, 0:10] = 1  # region 1: rows 0-9, cols 0-9
    labels[0:10, 25:40] = 2  # region 2: rows 0-9, cols 25-39
    return labels


def test_point_on_a_region_gets_it():
    assert regions_at_points(_two_rooms(), [(0, 0), (9, 9), (5, 30)]) == [1, 1, 2]


def test_point_on_a_wall_within_tolerance_gets_nearest_region():
    labels = _two_rooms()
    # (5, 16): 7 px from region 1 (col 9), 9 px from region 2 (col 25).
    assert regions_at_points(labels, [(5, 16)]) == [1]
    # (5, 19): 10 px from region 1, 6 px from region 2.
    assert regions_at_points(labels, [(5, 19)]) == [2]
    # (19, 9): exactly 10 px below region 1 is still within the tolerance.
    assert regions_at_points(labels, [(19, 9)]) == [1]


def test_point_beyond_tolerance_is_dropped():
    labels = _two_rooms()
    assert regions_at_points(labels, [(20, 9)]) == [0]  # 11 px below region 1
    assert regions_at_points(labels, [(17, 16)]) == [0]  # sqrt(8^2 + 7^2) = 10.6 px
    assert regions_at_points(labels, [(20, 9)], tolerance=11) == [1]
    assert regions_at_points(labels, [(5, 16)], tolerance=0) == [0]


def test_point_outside_the_image():
    labels = _two_rooms()
    assert regions_at_points(labels, [(-3, 2)]) == [1]
    assert regions_at_points(labels, [(4, 45)]) == [2]
    assert regions_at_points(labels, [(-11, 2)]) == [0]
    assert regions_at_points(labels, [(5, 60)]) == [0]
    assert regions_at_points(labels, [(38, 9)], tolerance=30) == [1]  # 29 px below region 1
    assert regions_at_points(labels, [(40, 9)], tolerance=30) == [0]  # 31 px


def test_regions_at_points_edge_inputs():
    labels = _two_rooms()
    assert regions_at_points(labels, []) == []
    assert regions_at_points(np.zeros((5, 5), dtype=np.int32), [(2, 2)]) == [0]
    assert regions_at_points(labels, [(4.6, 9.4)]) == [1]
    assert regions_at_points(labels, np.array([[0, 0], [5, 30]])) == [1, 2]
    with pytest.raises(ValueError):
        regions_at_points(labels, [(1, 2, 3)])
    with pytest.raises(ValueError):
        regions_at_points(labels[0], [(0, 0)])


def test_many_points_give_a_nearest_region_like_brute_force(monkeypatch):
    from scipy import ndimage

    transforms = []
    real_transform = ndimage.distance_transform_edt

    def counting_transform(*args, **kwargs):
        transforms.append(1)
        return real_transform(*args, **kwargs)

    monkeypatch.setattr(ndimage, "distance_transform_edt", counting_transform)
    generator = np.random.default_rng(7)
    labels = np.zeros((60, 80), dtype=np.int32)
    for region in range(1, 9):
        row, col = generator.integers(0, 55), generator.integers(0, 75)
        labels[row : row + 5, col : col + 5] = region
    points = np.stack([generator.integers(-8, 68, 400), generator.integers(-8, 88, 400)], axis=1)
    tolerance = 6.5
    found = regions_at_points(labels, points, tolerance=tolerance)
    assert len(transforms) == 1
    one_by_one = [regions_at_points(labels, [point], tolerance=tolerance)[0] for point in points]  # window search
    assert len(transforms) == 1

    region_rows, region_cols = np.nonzero(labels)
    for (row, col), region, single in zip(points, found, one_by_one):
        distances = np.hypot(region_rows - row, region_cols - col)
        nearest = distances.min()
        if nearest > tolerance:
            assert region == 0 and single == 0
            continue
        candidates = set(labels[region_rows[distances == nearest], region_cols[distances == nearest]])
        assert region in candidates and single in candidates


# --------------------------------------------------------------------------- assign_regions / from_pairs


def test_assign_regions_dedupes_in_order_and_drops_misses():
    sketch = _two_rooms()
    metric = np.zeros((10, 10), dtype=np.int32)
    metric[:, 5:] = 3
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(5, 30), (1, 1), (6, 31), (29, 0)], metric_points=[(0, 9)]),
            Clique(id=2, sketch_points=[], metric_points=[(0, 0)], sketch_regions=[9]),
        )
    )
    done = assign_regions(corr, sketch, metric)
    assert done.cliques[0].sketch_regions == (2, 1)
    assert done.cliques[0].metric_regions == (3,)
    assert done.cliques[1].sketch_regions == ()
    assert done.cliques[1].metric_regions == (3,)  # (0, 0) is 5 px from region 3
    assert done.cliques[0].sketch_points == corr.cliques[0].sketch_points
    assert assign_regions(corr, sketch, metric, tolerance=2).cliques[1].metric_regions == ()


def test_assign_regions_refuses_labels_of_another_size():
    corr = Correspondences(sketch=MapRef(path="s.png", size=(30, 40)), metric=MapRef(size=(5, 5)))
    with pytest.raises(SegmentationError, match="metric label image is 10x10"):
        assign_regions(corr, _two_rooms(), np.zeros((10, 10), dtype=np.int32))


def test_from_pairs_builds_one_clique_per_pair():
    interior = {1: (4, 5), 2: (6, 30), 10: (1, 1), 11: (8, 8)}
    cliques = from_pairs(
        [(1, 10), (2, 11)],
        sketch_points_of=interior.__getitem__,
        metric_points_of=interior.__getitem__,
        scores=[0.1, 0.25],
        first_id=4,
    )
    assert [clique.id for clique in cliques] == [4, 5]
    assert cliques[0].sketch_points == ((4, 5),) and cliques[0].metric_points == ((1, 1),)
    assert cliques[1].sketch_regions == (2,) and cliques[1].metric_regions == (11,)
    assert [clique.score for clique in cliques] == [0.1, 0.25]
    assert all(clique.source == "auto" and clique.effective_status == "pending" for clique in cliques)
    manual = from_pairs([(1, 10)], sketch_points_of=interior.get, metric_points_of=interior.get, source="manual")
    assert manual[0].source == "manual" and manual[0].score is None
    with pytest.raises(ValueError):
        from_pairs([(1, 10)], sketch_points_of=interior.get, metric_points_of=interior.get, scores=[])


def test_regions_survive_a_json_round_trip_with_points(tmp_path):
    corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(5, 16)], metric_points=[(2, 30)]),))
    labelled = assign_regions(corr, _two_rooms(), _two_rooms())
    save_correspondences(labelled, tmp_path / "p.json", now=NOW)
    loaded = load_correspondences(tmp_path / "p.json")
    assert loaded.cliques[0].sketch_regions == (1,) and loaded.cliques[0].metric_regions == (2,)


# --------------------------------------------------------------------------- issue 12, item 14: say so


def test_region_ids_that_disagree_with_the_points_are_reported(tmp_path):
    labels = np.array([[1, 1, 0, 2, 2]], dtype=np.int32)
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(0, 0)], metric_points=[(0, 4)], sketch_regions=[1], metric_regions=[2]),
            Clique(id=7, sketch_points=[(0, 4)], metric_points=[(0, 0)], sketch_regions=[1], metric_regions=[1]),
        )
    )
    with pytest.warns(RegionsRecomputedWarning, match=r"clique 7\b"):
        done = assign_regions(corr, labels, labels)
    assert done.cliques[1].sketch_regions == (2,)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assign_regions(done, labels, labels)
        # Cliques without region ids yet (a .dat file) are filled in silently.
        assign_regions(
            done.with_cliques(Clique(id=c.id, sketch_points=c.sketch_points) for c in done.cliques), labels, labels
        )
