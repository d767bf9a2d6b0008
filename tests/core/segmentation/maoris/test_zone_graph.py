"""MAORIS step 3 (ursim_core.segmentation.maoris.zone_graph): flat zones, the zone graph, its contacts and memory."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import skimage.measure

from ursim_core.errors import SegmentationError
from ursim_core.segmentation.maoris import ZoneGraph, flat_zones

# --------------------------------------------------------------------------
# Reference implementation, deliberately naive


def contour_contacts_with_find_contours(labels: np.ndarray, zone: int) -> tuple[int, dict[int, int]]:
    """Contour size and contacts of one zone, with cv2.findContours as the C++ does."""
    mask = (labels == zone).astype(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    points = {(int(y), int(x)) for contour in contours for x, y in contour[:, 0, :]}
    padded = np.pad(labels, 1)
    counts: dict[int, int] = {}
    for row, col in points:
        seen = set(padded[row : row + 3, col : col + 3].ravel().tolist()) - {0, zone}
        for other in seen:
            counts[other] = counts.get(other, 0) + 1
    return len(points), counts


# --------------------------------------------------------------------------
# Step 3: flat zones, the zone graph, its contacts


def test_flat_zones_are_4_connected_in_raster_order():
    values = np.array(
        [
            [5, 0, 5],
            [0, 5, 5],
            [7, 7, 0],
        ]
    )
    # The diagonal contact does not join (0,0) with (1,1).
    assert flat_zones(values).tolist() == [[1, 0, 2], [0, 2, 2], [3, 3, 0]]


@pytest.mark.parametrize("seed", range(6))
def test_flat_zones_equal_scikit_image_labelling(seed):
    # Few levels make large winding zones whose provisional labels merge (U
    # shapes, spirals of one value), where the numbering order is easy to get wrong.
    rng = np.random.default_rng(seed)
    values = rng.integers(0, 3 + seed, size=(60, 70)).astype(np.uint8)
    values = np.repeat(np.repeat(values, 1 + seed % 3, axis=0), 1 + seed % 2, axis=1)
    expected = skimage.measure.label(values, connectivity=1, background=0)
    np.testing.assert_array_equal(flat_zones(values), expected)


def test_zone_graph_edges_are_4_adjacency_only():
    values = np.array([[10, 20], [20, 10]], np.uint8)
    graph = ZoneGraph(flat_zones(values), values)
    # Four zones; diagonal pairs touch only at a corner.
    assert graph.neighbours(1) == [2, 3]
    assert 4 not in graph.neighbours(1)


def test_contacts_match_find_contours():
    rng = np.random.default_rng(3)
    for _ in range(20):
        values = (rng.integers(1, 4, (12, 15)) * 10).astype(np.uint8)
        values = cv2.medianBlur(values, 3)
        values[rng.random(values.shape) < 0.1] = 0
        zones = flat_zones(values)
        graph = ZoneGraph(zones, values)
        for zone in graph.vertices():
            total, counts = contour_contacts_with_find_contours(zones, zone)
            for other, count in counts.items():
                assert graph.contact_percent(zone, other) == count * 100 // total


def test_contacts_stay_exact_through_fusions():
    rng = np.random.default_rng(5)
    values = (cv2.medianBlur((rng.integers(1, 6, (20, 24)) * 10).astype(np.uint8), 3)).astype(np.uint8)
    graph = ZoneGraph(flat_zones(values), values)
    graph.contact_percent(1, 2)  # start tracking contacts
    for _ in range(8):
        zone = graph.vertices()[0]
        if not graph.neighbours(zone):
            break
        graph.fuse(zone, graph.neighbours(zone)[-1])
        labels = graph.labels.copy()
        for checked in graph.vertices():
            total, counts = contour_contacts_with_find_contours(labels, checked)
            for other in graph.neighbours(checked):
                assert graph.contact_percent(checked, other) == counts.get(other, 0) * 100 // total


# --------------------------------------------------------------------------
# Fusions, and the labels laid out in the graph's memory


def test_fuse_records_minimum_on_new_edges_only():
    # Zones 1 (value 100), 2 (value 40), 3 (value 100), 4 (value 90) in a row,
    # and 1 also touches 4 directly below.
    values = np.array([[100, 40, 100], [90, 90, 90]], np.uint8)
    zones = np.array([[1, 2, 3], [4, 4, 4]])
    graph = ZoneGraph(zones, values)
    graph.fuse(2, 1)
    assert graph.edge(1, 3).minimum == 40  # new edge through the valley
    assert graph.edge(1, 4).minimum is None  # direct contact kept as is
    assert graph.size(1) == 2 and graph.labels[0, 1] == 1


@pytest.mark.parametrize(
    ("zones_shape", "shape", "origin"),
    [
        ((1, 1), (1, 1), (0, 0)),
        ((13, 8), (13, 8), (0, 0)),  # the window is the image
        ((13, 8), (20, 9), (5, 1)),  # narrower than the padded labels, a tall top margin
        ((13, 8), (14, 30), (0, 20)),  # much wider: every row moves on
        ((40, 30), (45, 33), (2, 1)),  # rows moving back, then rows moving on
        ((7, 1), (9, 12), (1, 11)),
        ((1, 9), (3, 10), (2, 0)),
    ],
)
def test_labels_placed_in_place_are_the_labels_in_a_fresh_image(zones_shape, shape, origin):
    from ursim_core.segmentation.maoris.zone_graph import _PAD, _pad_in_place, _place_in_place

    rng = np.random.default_rng(sum(zones_shape) + sum(shape))
    zones = rng.integers(1, 50, zones_shape).astype(np.int32)
    padded_size = (zones_shape[0] + 2 * _PAD) * (zones_shape[1] + 2 * _PAD)
    storage = np.full(max(padded_size, shape[0] * shape[1]) + 3, -1, np.int32)
    storage[: zones.size] = zones.ravel()
    padded = _pad_in_place(storage[: zones.size].reshape(zones_shape), storage)
    np.testing.assert_array_equal(padded, np.pad(zones, _PAD))
    want = np.zeros(shape, np.int32)
    want[origin[0] : origin[0] + zones_shape[0], origin[1] : origin[1] + zones_shape[1]] = zones
    placed = _place_in_place(padded, storage, shape, origin)
    np.testing.assert_array_equal(placed, want)
    assert placed.flags.c_contiguous and np.shares_memory(placed, storage)


def test_labels_that_do_not_fit_are_refused():
    from ursim_core.segmentation.maoris.zone_graph import _place_in_place

    storage = np.zeros(100, np.int32)
    with pytest.raises(SegmentationError, match="do not fit"):
        _place_in_place(storage[:36].reshape(6, 6), storage, (5, 5), (4, 0))
