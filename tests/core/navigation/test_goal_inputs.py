"""locate() with a loaded correspondence file (points decide the regions) and with wrong inputs."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    assign_regions,
    load_correspondences,
    load_dat,
    save_correspondences,
)
from ursim_core.errors import ParameterError, RegionsRecomputedWarning
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.io.maps import Map
from ursim_core.navigation import locate, match_table
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.interface import Segmentation


def seg_of(labels):
    labels = np.asarray(labels, dtype=np.int32)
    return Segmentation(labels=labels, graph=region_graph(labels))


def rooms(ids, width=30):
    """Rooms side by side (one-pixel walls), 20 rows high, numbered ``ids`` from left to right."""
    labels = np.zeros((20, len(ids) * (width + 1) - 1), np.int32)
    for index, region in enumerate(ids):
        labels[:, index * (width + 1) : index * (width + 1) + width] = region
    return seg_of(labels)


def saved_and_loaded(tmp_path, made_with_sketch, made_with_metric):
    """A file whose cliques' ids are those of the segmentations it was made with.

    Clique 1: sketch room 1 (left) <-> metric room 3 (right); clique 2: sketch 2 <-> metric 1.
    """
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(10, 5)], metric_points=[(10, 75)]),
            Clique(id=2, sketch_points=[(10, 40)], metric_points=[(10, 5)]),
        )
    )
    corr = assign_regions(corr, made_with_sketch.labels, made_with_metric.labels)
    save_correspondences(corr, tmp_path / "corr.json")
    return load_correspondences(tmp_path / "corr.json")


def test_a_loaded_file_is_located_by_its_points_in_the_given_segmentations(tmp_path):
    # The file was made with rooms numbered 1 2 3; the robot segments the same maps and numbers
    # them 3 1 2 (another segmenter, another run): the stored ids name other rooms now.
    loaded = saved_and_loaded(tmp_path, rooms([1, 2, 3]), rooms([1, 2, 3]))
    assert loaded.cliques[0].metric_regions == (3,)
    sketch, metric = rooms([3, 1, 2]), rooms([3, 1, 2])
    the_map = Map(free=metric.labels > 0, resolution=0.1, origin=(0.0, 0.0, 0.0))
    with pytest.warns(RegionsRecomputedWarning, match="recomputed from the points"):
        goal = locate(loaded, sketch, metric, the_map, 10, 5)
    # Clique 1's metric point lies in the right-hand room, whatever its id.
    assert goal.ok and goal.clique_id == 1
    assert goal.metric_region == 2 and metric.labels[goal.pixel] == metric.labels[10, 75]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RegionsRecomputedWarning)
        expected = locate(assign_regions(loaded, sketch.labels, metric.labels), sketch, metric, the_map, 10, 5)
    assert goal.pose == expected.pose and goal.pixel == expected.pixel


def test_the_table_of_a_file_is_built_from_points_when_given_the_segmentations(tmp_path):
    loaded = saved_and_loaded(tmp_path, rooms([1, 2, 3]), rooms([1, 2, 3]))
    sketch, metric = rooms([3, 1, 2]), rooms([2, 3, 1])
    with pytest.warns(RegionsRecomputedWarning):
        table = match_table(loaded, sketch, metric)
    # Sketch room left (3) -> metric room right (1); sketch room middle (1) -> metric room left (2).
    assert table.metric_of == {3: (1,), 1: (2,)}
    assert table.clique_of == {3: 1, 1: 2}
    # Without segmentations the stored ids are all there is.
    assert match_table(loaded).metric_of == {1: (3,), 2: (1,)}
    # A table is not re-assigned: it is what locate is given when called many times.
    assert match_table(table, sketch, metric) is table


def test_a_file_made_with_these_segmentations_gives_no_warning(tmp_path):
    sketch, metric = rooms([1, 2, 3]), rooms([1, 2, 3])
    loaded = saved_and_loaded(tmp_path, sketch, metric)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        goal = locate(loaded, sketch, metric, None, 10, 40)
    assert (goal.clique_id, goal.metric_region) == (2, 1)


def test_cliques_without_points_keep_their_region_ids():
    from ursim_core.navigation.goal import clique_regions

    sketch = rooms([1, 2, 3])
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_regions=(1,), metric_regions=(3,)),
            Clique(id=2, sketch_points=[(10, 40)], metric_points=[(10, 5)], sketch_regions=(9,), metric_regions=(9,)),
        )
    )
    with pytest.warns(RegionsRecomputedWarning, match="clique 2"):
        assigned = clique_regions(corr, sketch, sketch)
    assert [(c.sketch_regions, c.metric_regions) for c in assigned.cliques] == [((1,), (3,)), ((2,), (1,))]
    assert clique_regions(corr.with_cliques(corr.cliques[:1]), sketch, sketch).cliques == corr.cliques[:1]


@pytest.mark.parametrize("row, col", [(math.nan, 3), (3, math.inf), ("x", 3), (None, 3)])
def test_a_point_that_is_not_a_finite_number_is_a_parameter_error(row, col):
    sketch = rooms([1, 2])
    with pytest.raises(ParameterError, match="finite number"):
        locate([(1, 1)], sketch, sketch, None, row, col)


@pytest.mark.parametrize("tolerance", [math.nan, -1, math.inf])
def test_a_tolerance_that_is_not_a_finite_number_of_pixels_is_a_parameter_error(tolerance):
    sketch = rooms([1, 2])
    with pytest.raises(ParameterError, match="tolerance"):
        locate([(1, 1)], sketch, sketch, None, 300, 300, tolerance=tolerance)


def test_a_nan_yaw_is_a_parameter_error():
    sketch = rooms([1, 2])
    with pytest.raises(ParameterError, match="yaw"):
        locate([(1, 1)], sketch, sketch, None, 5, 5, yaw=math.nan)


def test_segmentations_swapped_with_the_metric_map_are_a_parameter_error():
    sketch = rooms([1, 2])  # 20 x 61
    metric = seg_of(np.ones((50, 40), np.int32))
    the_map = Map(free=metric.labels > 0, resolution=0.1, origin=(0.0, 0.0, 0.0))
    assert locate([(1, 1)], sketch, metric, the_map, 5, 5).ok
    with pytest.raises(ParameterError, match=r"metric_map is 50x40 but metric_seg is 20x61"):
        locate([(1, 1)], metric, sketch, the_map, 5, 5)


def test_a_map_given_for_a_segmentation_is_a_parameter_error():
    sketch = rooms([1, 2])
    the_map = Map(free=sketch.labels > 0)
    with pytest.raises(ParameterError, match=r"sketch_seg.*must be a Segmentation .*, got Map"):
        locate([(1, 1)], the_map, sketch, None, 5, 5)


ROOT = dataset_root()


@pytest.mark.dataset
@pytest.mark.slow
@pytest.mark.skipif(ROOT is None, reason=MISSING_REASON)
def test_kth_goals_of_a_file_made_with_other_segmentations_follow_the_points(tmp_path):
    # The audit's case: a KTH ground truth assigned with one pair of presets and saved; the robot
    # segments with others. Before, a goal went to the file's region ids (metres off).
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import segment

    folder = ROOT / "ursim_kth_sketches"
    sketch_map, metric_map = load_map(folder / "sketches" / "00.png"), load_map(folder / "model" / "model_simple.png")
    dat = load_dat(folder / "gt_correspondences" / "malcolm" / "gt_00_model_simple.dat")
    made = assign_regions(dat, segment(sketch_map, preset="sketch").labels, segment(metric_map, preset="robot").labels)
    save_correspondences(made, tmp_path / "gt_00.json")
    loaded = load_correspondences(tmp_path / "gt_00.json")
    sketch_seg, metric_seg = segment(sketch_map, preset="default"), segment(metric_map, preset="default")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RegionsRecomputedWarning)
        table = match_table(assign_regions(loaded, sketch_seg.labels, metric_seg.labels))
        points = [point for clique in loaded.cliques for point in clique.sketch_points]
        got = [locate(loaded, sketch_seg, metric_seg, metric_map, r, c).pixel for r, c in points]
    assert got == [locate(table, sketch_seg, metric_seg, metric_map, r, c).pixel for r, c in points]
    assert sum(pixel is not None for pixel in got) >= len(points) - 1


def test_a_route_over_a_loaded_file_follows_its_points_too(tmp_path):
    # plan_route used a file's stored region ids whatever segmentations it was given.
    from ursim_core.correspondences import Clique, Correspondences
    from ursim_core.navigation.route import plan_route
    from ursim_core.segmentation.graph import region_graph
    from ursim_core.segmentation.interface import Segmentation

    labels = np.zeros((10, 30), np.int32)
    labels[:, :10], labels[:, 10:20], labels[:, 20:] = 1, 2, 3
    seg = Segmentation(labels=labels, graph=region_graph(labels))
    # Points in regions 1 and 3 of these segmentations; the ids stored are another's (3 and 1).
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(5, 2)], metric_points=[(5, 2)], sketch_regions=(3,), metric_regions=(1,)),
            Clique(id=2, sketch_points=[(5, 28)], metric_points=[(5, 28)], sketch_regions=(1,), metric_regions=(3,)),
        )
    )
    with pytest.warns(RegionsRecomputedWarning):
        route = plan_route(corr, seg, seg, None, [(5, 2), (5, 28)])
    assert route.metric_regions == (1, 2, 3)
