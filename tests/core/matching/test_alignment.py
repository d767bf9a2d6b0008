"""Free-space alignment of a sketch onto a metric map, and its use in choosing the orientation."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation import augment
from ursim_core.matching import MatchConfig, prepare
from ursim_core.matching.alignment import fit_alignment, fit_alignments, orientation_matrix
from ursim_core.matching.orientation import transform_points
from ursim_core.segmentation import segment_canonical
from ursim_core.synth import make_pair


@pytest.fixture(scope="module")
def plan_free():
    plan, _ = make_pair(seed=1)
    return plan.free


def test_a_map_fits_itself_upright_with_the_identity(plan_free):
    fitted = fit_alignment(plan_free, plan_free)
    # Not 1: the overlap is measured at about 96 px, the sketch resampled there, the map shrunk.
    assert fitted.overlap > 0.9
    np.testing.assert_allclose(fitted.matrix[:, :2], np.eye(2), atol=0.03)
    assert np.abs(fitted.matrix[:, 2]).max() < 0.03 * max(plan_free.shape)


@pytest.mark.parametrize("quarter_turns, mirrored", [(1, False), (2, False), (3, True), (0, True)])
def test_the_orientation_that_undoes_a_turn_overlaps_best(plan_free, quarter_turns, mirrored):
    turn = augment.Orientation(90.0 * quarter_turns, mirrored=mirrored)
    moved = augment.transform_image(plan_free, turn)
    candidates = [(90.0 * k, flag) for flag in (False, True) for k in range(4)]
    overlaps = [a.overlap for a in fit_alignments(moved, plan_free, candidates)]
    best = candidates[int(np.argmax(overlaps))]
    # Undoing "mirror, then turn by t" is "mirror, then turn by t" for a mirror image, else a turn by -t.
    undo = (90.0 * quarter_turns % 360.0, True) if mirrored else ((-90.0 * quarter_turns) % 360.0, False)
    assert best == undo, (overlaps, best, undo)
    assert max(overlaps) > 0.9
    assert sorted(overlaps)[-2] < max(overlaps) - 0.01


def test_a_rescaled_and_shifted_copy_is_fitted_back(plan_free):
    import cv2

    rows, cols = plan_free.shape
    small = cv2.resize(plan_free.astype(np.uint8), (cols // 2, rows // 2), interpolation=cv2.INTER_NEAREST) > 0
    framed = np.zeros((rows, cols), bool)
    framed[40 : 40 + small.shape[0], 70 : 70 + small.shape[1]] = small
    fitted = fit_alignment(framed, plan_free)
    assert fitted.overlap > 0.85
    np.testing.assert_allclose(np.diag(fitted.matrix[:, :2]), [2.0, 2.0], rtol=0.05)
    # A pixel of the copy lands where it came from.
    source = np.array([40 + 30, 70 + 50], float)
    landed = fitted.matrix[:, :2] @ source + fitted.matrix[:, 2]
    np.testing.assert_allclose(landed, [60.0, 100.0], atol=0.03 * max(rows, cols))


def test_orientation_matrix_is_transform_points():
    points = np.array([[3.0, 4.0], [-1.0, 2.0]])
    for degrees, mirrored in [(0, False), (90, False), (200, True), (33.5, False)]:
        np.testing.assert_allclose(
            points @ orientation_matrix(degrees=degrees, mirrored=mirrored).T,
            transform_points(points, degrees=degrees, mirrored=mirrored),
        )


def test_no_free_space_overlaps_nothing():
    free = np.zeros((30, 30), bool)
    free[5:20, 5:25] = True
    assert fit_alignment(np.zeros((30, 30), bool), free).overlap == 0.0
    assert fit_alignment(free, np.zeros((30, 30), bool)).overlap == 0.0


def test_overlap_ranking_is_an_option_and_needs_label_images():
    with pytest.raises(ParameterError, match="orientation_overlap"):
        MatchConfig(orientation_overlap=-1)
    graph = nx.path_graph(3)
    nx.set_node_attributes(graph, {0: 50, 1: 10, 2: 12}, "size")
    nx.set_node_attributes(graph, 0.3, "pca_shape")
    nx.set_node_attributes(graph, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    # Bare graphs have no free space to overlap: the score alone ranks, and nothing fails.
    assert prepare(graph, graph.copy()).chosen is not None


@pytest.mark.parametrize("seed", [0, 2])
def test_a_turned_generated_sketch_gets_its_orientation_back(seed):
    plan, sketch = make_pair(seed=seed)
    turn = augment.Orientation(270.0, mirrored=True)
    moved = segment_canonical(augment.transform_image(sketch.free, turn), preset="default")
    metric = segment_canonical(plan.free, preset="default")
    for power in (1.0, 0.0):
        prepared = prepare(moved, metric, MatchConfig(orientation_overlap=power))
        degrees, mirrored = prepared.orientation
        if power:
            # The orientation that undoes "mirror, then turn by 270": itself (up to the walls' angle).
            assert mirrored and abs((degrees - 270.0 + 180.0) % 360.0 - 180.0) < 10.0, prepared.orientation


def test_the_search_in_c_finds_what_the_python_search_finds(c_kernel, monkeypatch):
    """Overlap and matrix equal, bit for bit, with OpenCV's warp done in C as OpenCV does it: maps
    turned by any angle, mirrored, rescaled, cropped (a warp reaching past the sketch's edges),
    in all eight orientation candidates."""
    import cv2

    from ursim_core.matching import kernels

    cases = []
    for seed in range(4):
        plan, sketch = make_pair(seed=seed)
        for k, (degrees, mirrored) in enumerate([(0.0, False), (37.0, True), (151.5, False), (290.0, True)]):
            moved = augment.transform_image(sketch.free, augment.Orientation(degrees, mirrored=mirrored))
            if k % 2:
                moved = moved[: moved.shape[0] * 2 // 3]  # cropped: part of the plan
            scale = (0.6, 1.0, 1.7, 1.2)[(seed + k) % 4]
            size = (max(1, round(moved.shape[1] * scale)), max(1, round(moved.shape[0] * scale)))
            moved = cv2.resize(moved.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST)
            candidates = [((degrees + 90.0 * q) % 360.0, flag) for flag in (False, True) for q in range(4)]
            cases.append((moved, plan.free, candidates))
    compiled = [fit_alignments(*case) for case in cases]
    monkeypatch.setattr(kernels, "kernel", lambda: None)
    reference = [fit_alignments(*case) for case in cases]
    fits = [(a, b) for many_a, many_b in zip(compiled, reference) for a, b in zip(many_a, many_b)]
    assert len(fits) == 16 * 8
    for a, b in fits:
        assert a.overlap == b.overlap and np.array_equal(a.matrix, b.matrix)
    assert len({round(a.overlap, 6) for a, _ in fits}) > 50  # many different fits, not one


def test_the_search_in_c_refuses_bad_arguments(c_kernel):
    image = np.ones((10, 10), np.uint8)
    numbers = (1.0, 0.0, 0.0, 1.0), (1.0, 1.0), (5.0, 5.0), (5.0, 5.0), (10.0, 10.0)
    with pytest.raises(TypeError, match="13 arguments"):
        c_kernel.overlap_search(image, image, 100)
    with pytest.raises(TypeError, match="tuples of the documented sizes"):
        c_kernel.overlap_search(image, image, 100, (1.0,), *numbers[1:], 1.0, 1.0, (0.1,) * 5, 0.02, 60)
    with pytest.raises(ValueError, match="empty image"):
        c_kernel.overlap_search(np.ones((0, 10), np.uint8), image, 100, *numbers, 1.0, 1.0, (0.1,) * 5, 0.02, 60)
    with pytest.raises(TypeError, match="sketch"):
        c_kernel.overlap_search(image.astype(np.float32), image, 100, *numbers, 1.0, 1.0, (0.1,) * 5, 0.02, 60)
