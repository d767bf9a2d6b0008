"""The region table (no networkx) and the Segmentation that builds its graph from it on first use."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from ursim_core.segmentation import Segmentation, segment
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.regions import RegionTable, region_table


def _rooms() -> np.ndarray:
    rng = np.random.default_rng(3)
    labels = np.repeat(np.repeat(rng.integers(0, 7, (6, 8)), 9, axis=0), 7, axis=1).astype(np.int32)
    labels[20:30, 10:40] = 0
    return labels


def _as_lists(graph):
    return list(graph.nodes(data=True)), list(graph.edges(data=True))


def test_the_table_is_the_graph_in_the_same_order():
    labels = _rooms()
    table = region_table(labels)
    assert _as_lists(table.to_graph()) == _as_lists(region_graph(labels))
    assert _as_lists(RegionTable.from_graph(region_graph(labels)).to_graph()) == _as_lists(region_graph(labels))
    assert list(table.edges) == sorted(table.edges)
    assert table.number_of_edges() == region_graph(labels).number_of_edges() > 5
    graph = region_graph(labels)
    assert table.neighbours() == {region: sorted(graph.neighbors(region)) for region in graph.nodes}
    assert (3 in table) == (3 in graph) and 0 not in table


def test_contacts_are_where_two_regions_touch_and_travel_with_the_graph():
    labels = np.zeros((6, 9), np.int32)
    labels[:, :4], labels[:, 5:] = 1, 2
    labels[4, 4] = 2  # a door at row 4: 1 and 2 touch there only
    labels[:2, 5:] = 3  # 3 above 2, along their whole width
    table = region_table(labels)
    assert table.contacts[1, 2] == (4.0, 3.5)  # between column 3 and the door pixel, at row 4
    assert table.contacts[2, 3] == (1.5, 6.5)  # between rows 1 and 2, over columns 5-8
    graph = table.to_graph()
    assert graph.edges[1, 2]["contact"] == (4.0, 3.5) and graph.edges[2, 3]["boundary"] == 4
    assert RegionTable.from_graph(graph).contacts == table.contacts
    # A graph made elsewhere, without contacts, gives a table without them.
    graph.edges[1, 2].pop("contact")
    assert (1, 2) not in RegionTable.from_graph(graph).contacts


def test_negative_labels_are_refused_by_name():
    from ursim_core.errors import ParameterError

    labels = np.zeros((6, 6), np.int32)
    labels[1:3, 1:3], labels[3:5, 3:5] = -1, 2
    with pytest.raises(ParameterError, match="negative labels"):
        region_table(labels)


def test_an_empty_label_image_has_no_regions():
    table = region_table(np.zeros((4, 5), np.int32))
    assert len(table) == 0 and table.edges == {} and table.to_graph().number_of_nodes() == 0


def test_a_segmentation_builds_its_graph_once_on_first_use():
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    seg = segment(free, preset="default")
    assert seg._graph is None
    assert seg.n_regions == 2 and seg._graph is None
    graph = seg.graph
    assert seg.graph is graph and _as_lists(graph) == _as_lists(region_graph(seg.labels))


def test_a_segmentation_measures_its_wall_angle_once(monkeypatch):
    import cv2

    from ursim_core.segmentation import canonical

    labels = np.zeros((120, 160), np.int32)  # a room turned by about 20 degrees
    corners = cv2.boxPoints(((80, 60), (100, 50), -20.0)).astype(np.int32)
    cv2.fillPoly(labels, [corners], 1)
    expected = canonical.wall_angle(labels)
    assert abs(expected) > 10
    calls = []
    monkeypatch.setattr(canonical, "wall_angle", lambda image: calls.append(image) or expected)
    seg = Segmentation(labels, regions=region_table(labels))
    assert seg.wall_angle == expected and seg.wall_angle == expected
    assert len(calls) == 1 and calls[0] is labels
    assert seg.with_resampled(()).wall_angle == expected and len(calls) == 1  # the same labels
    again = pickle.loads(pickle.dumps(seg))  # measured again from its own labels
    assert again.wall_angle == expected and len(calls) == 2


def test_a_segmentation_is_immutable_and_survives_pickling_and_copies():
    labels = _rooms()
    seg = Segmentation(labels=labels, regions=region_table(labels), method="label-image", params={"a": 1})
    with pytest.raises(AttributeError, match="immutable"):
        seg.labels = labels
    with pytest.raises(AttributeError, match="immutable"):
        del seg.method
    for again in (pickle.loads(pickle.dumps(seg)), copy.deepcopy(seg), copy.copy(seg)):
        assert np.array_equal(again.labels, labels) and again.params == {"a": 1}
        assert _as_lists(again.graph) == _as_lists(seg.graph)
    given = Segmentation(labels, region_graph(labels))
    assert given.regions.nodes == region_table(labels).nodes
    with pytest.raises(TypeError, match="graph or the region table"):
        Segmentation(labels)


def test_why_no_region_names_what_to_change():
    from ursim_core.segmentation import why_no_region

    assert "no walls" in why_no_region(np.ones((10, 10), bool))
    closed = np.zeros((20, 41), bool)
    closed[2:18, 2:20] = closed[2:18, 21:39] = True
    assert "2 separate areas" in why_no_region(closed)
    assert "separate areas" not in why_no_region(closed, method="watershed")  # MAORIS' rule only
    closed[9, 20] = True  # a door: one area
    assert "minimum size" in why_no_region(closed)


def _direct_table(labels):
    """The region table by its definitions, pixel by pixel and region by region."""
    import cv2

    from ursim_core.segmentation.regions import contour_pca_shape

    nodes = {}
    for region in range(1, int(labels.max()) + 1):
        mask = labels == region
        if not mask.any():
            continue
        rows, cols = np.nonzero(mask)
        box = (int(rows.min()), int(cols.min()), int(rows.max()) + 1, int(cols.max()) + 1)
        crop = mask[box[0] : box[2], box[1] : box[3]]
        inside = cv2.distanceTransform(np.pad(crop.astype(np.uint8), 1), cv2.DIST_L2, 5)[1:-1, 1:-1]
        peak = np.unravel_index(int(np.argmax(inside)), inside.shape)
        nodes[region] = {
            "size": int(mask.sum()),
            "centroid": (float(rows.sum() / mask.sum()), float(cols.sum() / mask.sum())),
            "interior": (box[0] + int(peak[0]), box[1] + int(peak[1])),
            "bbox": box,
            "pca_shape": contour_pca_shape(crop),
        }
    edges: dict = {}
    sums: dict = {}
    rows, cols = np.indices(labels.shape)
    # Side by side, the midpoint half a column right of the left pixel; one above the other, half a row down.
    for (a, b), (down, right), (r, c) in (
        ((labels[:, :-1], labels[:, 1:]), (0.0, 0.5), (rows[:, :-1], cols[:, :-1])),
        ((labels[:-1], labels[1:]), (0.5, 0.0), (rows[:-1], cols[:-1])),
    ):
        for x, y, row, col in zip(a.ravel().tolist(), b.ravel().tolist(), r.ravel().tolist(), c.ravel().tolist()):
            if x != y and x and y:
                key = (min(x, y), max(x, y))
                edges[key] = edges.get(key, 0) + 1
                sums[key] = (sums.get(key, (0.0, 0.0))[0] + row + down, sums.get(key, (0.0, 0.0))[1] + col + right)
    contacts = {key: (sums[key][0] / edges[key], sums[key][1] / edges[key]) for key in sorted(edges)}
    return nodes, dict(sorted(edges.items())), contacts


@pytest.mark.parametrize("shape", [(700, 1100), (1300, 240), (3, 90000), (9, 9)])
def test_the_table_follows_the_definitions_across_bands_of_rows(shape):
    # Sizes come from runs of labels along rows, adjacency and runs are counted in bands of
    # rows, and the interior point is the argmax of the padded transform: all must give what
    # the pixel-by-pixel definitions give, on images of several bands and of one thin band.
    rng = np.random.default_rng(sum(shape))
    coarse = rng.integers(0, 9, (max(1, shape[0] // 50), max(1, shape[1] // 50)))
    labels = cv2_resize_nearest(coarse, shape).astype(np.int32)
    specks = rng.random(shape) < 0.02
    labels[specks] = rng.integers(0, 9, int(specks.sum()))  # holes, and specks touching on every row
    labels[labels == 4] = 0  # an id with no pixels
    table = region_table(labels)
    nodes, edges, contacts = _direct_table(labels)
    assert table.nodes == nodes and table.edges == edges
    assert table.contacts.keys() == contacts.keys()
    for pair, (row, col) in contacts.items():
        assert table.contacts[pair] == pytest.approx((row, col), abs=1e-9), pair
    assert all(
        type(v) is int for node in table.nodes.values() for v in (*node["interior"], *node["bbox"], node["size"])
    )


def cv2_resize_nearest(coarse, shape):
    import cv2

    return cv2.resize(coarse.astype(np.int32), (shape[1], shape[0]), interpolation=cv2.INTER_NEAREST)


# The bounding boxes of the region table.
def test_region_graph_boxes_are_those_of_scipy_find_objects():
    from scipy import ndimage

    from ursim_core.segmentation.regions import _bounding_boxes

    rng = np.random.default_rng(0)
    for shape in ((1, 1), (7, 1), (1, 9), (40, 33)):
        labels = rng.choice(np.array([0, 1, 2, 5], np.int32), size=shape)  # ids 3 and 4 absent
        count = int(labels.max()) + 1
        boxes = _bounding_boxes(labels, count)
        for index, box in enumerate(ndimage.find_objects(labels), start=1):
            if box is not None:
                assert tuple(boxes[index]) == (box[0].start, box[1].start, box[0].stop, box[1].stop)


@pytest.mark.parametrize("pad", [((0, 0), (0, 0)), ((5, 0), (0, 9)), ((0, 7), (11, 0)), ((13, 4), (6, 21))])
def test_the_table_of_labels_in_a_larger_empty_image_is_theirs_moved(pad):
    # The runs are found in the box of the non-zero labels: the same table as the pixels give,
    # labels on the image's edges or not.
    rng = np.random.default_rng(sum(map(sum, pad)))
    labels = cv2_resize_nearest(rng.integers(0, 6, (4, 5)), (37, 45)).astype(np.int32)
    labels[rng.random(labels.shape) < 0.03] = 3
    padded = np.pad(labels, pad)
    table = region_table(padded)
    nodes, edges, _ = _direct_table(padded)
    assert table.nodes == nodes and table.edges == edges
