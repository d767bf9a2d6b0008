"""Qt-free rendering of label images (ursim_gui.model.region_style): colours, overlay, outlines, label positions."""

from __future__ import annotations

import numpy as np
from conftest import three_room_labels

from ursim_core.segmentation.graph import region_graph
from ursim_gui.model.region_style import (
    outline_mask,
    overlay_rgba,
    palette_colour,
    region_colour_table,
    region_label_positions,
    region_mask,
)


def test_colour_table_makes_background_transparent_and_regions_distinct():
    table = region_colour_table(20, alpha=200)
    assert table.shape == (21, 4) and table.dtype == np.uint8
    assert tuple(table[0]) == (0, 0, 0, 0)
    assert (table[1:, 3] == 200).all()
    assert len({tuple(row[:3]) for row in table[1:]}) == 20
    assert palette_colour(7) == tuple(table[7, :3])


def test_overlay_is_one_lookup_per_pixel():
    labels = three_room_labels()
    table = region_colour_table(3, {2: (1, 2, 3)}, default=(9, 9, 9), alpha=255)
    rgba = overlay_rgba(labels, table)
    assert rgba.shape == labels.shape + (4,)
    assert tuple(rgba[10, 60]) == (1, 2, 3, 255)
    assert tuple(rgba[10, 10]) == (9, 9, 9, 255)
    assert tuple(rgba[0, 0]) == (0, 0, 0, 0)


def test_overlay_tolerates_labels_beyond_the_table():
    labels = np.array([[0, 1], [5, 2]], np.int32)
    rgba = overlay_rgba(labels, region_colour_table(2))
    assert tuple(rgba[1, 0]) == (0, 0, 0, 0)


def test_outline_marks_only_region_borders():
    labels = np.zeros((6, 6), np.int32)
    labels[1:5, 1:3] = 1
    labels[1:5, 3:5] = 2
    mask = outline_mask(labels)
    assert mask[2, 2] and mask[2, 3]  # the shared border
    assert mask[1, 1]  # border with the wall
    assert not mask[0, 0]  # walls stay clean
    labels_big = np.ones((6, 6), np.int32)
    labels_big[2:4, 2:4] = 2
    assert not outline_mask(labels_big)[0, 0]


def test_outline_follows_its_definition_across_bands_of_rows():
    # The mask is made in bands of rows with a row of context each side: on an image of several
    # bands (and on a single long row) it must be the pixel-by-pixel definition.
    rng = np.random.default_rng(4)
    for shape in ((700, 900), (2, 300000), (1, 7)):
        labels = rng.integers(0, 4, shape).astype(np.int32)
        expected = np.zeros(shape, bool)
        expected[1:] |= labels[1:] != labels[:-1]
        expected[:-1] |= labels[1:] != labels[:-1]
        expected[:, 1:] |= labels[:, 1:] != labels[:, :-1]
        expected[:, :-1] |= labels[:, 1:] != labels[:, :-1]
        assert np.array_equal(outline_mask(labels), expected & (labels > 0)), shape


def test_label_positions_use_interior_points_and_masks_are_cropped():
    labels = three_room_labels()
    graph = region_graph(labels)
    positions = region_label_positions(graph)
    assert set(positions) == {1, 2, 3}
    for region, (row, col) in positions.items():
        assert labels[int(row), int(col)] == region
    mask, (row0, col0) = region_mask(labels, 2, graph.nodes[2]["bbox"])
    assert (row0, col0) == (5, 52)
    assert mask.sum() == (labels == 2).sum()
