"""MAORIS steps 4-7 (ursim_core.segmentation.maoris.steps) on small zone graphs with known answers."""

from __future__ import annotations

import numpy as np

from ursim_core.segmentation.maoris import (
    ZoneGraph,
    flat_zones,
    inscribed_circle_image,
    inscribed_circle_radii,
    mark_unbreakable_edges,
    merge_ripples,
    quantize,
    remove_doors,
    remove_isolated_zones,
    remove_small_zones,
    watershed_merge,
)


def test_mark_unbreakable_edges():
    def fused_graph(valley: int) -> ZoneGraph:
        values = np.array([[100, valley, 100]], np.uint8)
        graph = ZoneGraph(flat_zones(values), values)
        graph.fuse(2, 1)
        return graph

    # Unbreakable when minimum <= max(values) * (1 - t).
    assert mark_unbreakable_edges(fused_graph(50), threshold=0.5).edge(1, 3).unbreakable
    assert not mark_unbreakable_edges(fused_graph(51), threshold=0.5).edge(1, 3).unbreakable
    assert not mark_unbreakable_edges(fused_graph(80), threshold=0.25).edge(1, 3).unbreakable


def test_remove_small_zones_picks_closest_value_and_first_on_ties():
    values = np.array([[50, 50, 50, 60, 70, 70, 70]], np.uint8)
    graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=2)
    assert graph.labels.tolist() == [[1, 1, 1, 1, 3, 3, 3]]  # 60 ties 50/70: first neighbour
    values = np.array([[50, 50, 50, 68, 70, 70, 70]], np.uint8)
    graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=2)
    assert graph.labels.tolist() == [[1, 1, 1, 3, 3, 3, 3]]


def test_remove_small_zones_deletes_small_isolated_zones():
    values = np.array([[50, 0, 50, 50, 50]], np.uint8)
    graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=2)
    assert graph.labels.tolist() == [[0, 0, 2, 2, 2]]


def test_ripple_is_fused_into_its_base():
    values = np.zeros((14, 14), np.uint8)
    values[1:11, 1:13] = 200  # plateau, walls on three sides
    values[11:13, 1:13] = 100  # a 2-px band: half its contour touches the plateau
    graph = ZoneGraph(flat_zones(values), values)
    assert graph.contact_percent(2, 1) >= 40 > graph.contact_percent(1, 2)
    merge_ripples(graph)
    assert graph.vertices() == [1] and graph.value(1) == 200


def test_renumbering_after_the_ripples_changes_ids_only():
    # The pipeline renumbers the zones that enter ripple merging 1..n in id order, so the zones
    # left keep their order under smaller ids: every later step sees the same graph up to the
    # ids, and must decide alike.
    from ursim_core.segmentation.maoris.inscribed_circle import _quantization_table
    from ursim_core.synth import make_large_building

    free = make_large_building(400, seed=6).free
    radii = inscribed_circle_radii(free)
    lo, table = _quantization_table(radii, 5)
    values = table[radii - lo]
    # The table the segmentation labels through gives the quantised value image of step 2.
    np.testing.assert_array_equal(values, quantize(inscribed_circle_image(free), quantum=5))
    graphs = []
    for renumber in (False, True):
        graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=10)
        graphs.append(merge_ripples(graph, ripples=40, _renumber=renumber))
    kept, renumbered = graphs
    old_ids = kept.vertices()
    new_ids = renumbered.vertices()
    assert len(new_ids) == len(old_ids) > 5 and all(new <= old for new, old in zip(new_ids, old_ids))
    assert len(renumbered._value_array) < len(kept._value_array) / 5  # the arrays shrank
    new_of = dict(zip(old_ids, new_ids))
    np.testing.assert_array_equal(renumbered.label_image(), kept.label_image())
    for old in old_ids:
        new = new_of[old]
        assert renumbered.neighbours(new) == [new_of[n] for n in kept.neighbours(old)]
        assert renumbered.value(new) == kept.value(old) and renumbered.size(new) == kept.size(old)
        for other in kept.neighbours(old):
            edge, renumbered_edge = kept.edge(old, other), renumbered.edge(new, new_of[other])
            assert (edge.minimum, edge.unbreakable) == (renumbered_edge.minimum, renumbered_edge.unbreakable)
    for graph in graphs:  # and the steps after decide alike
        watershed_merge(mark_unbreakable_edges(graph, threshold=0.5), threshold=0.5)
        remove_small_zones(remove_doors(graph, doors=40), min_size=100)
    np.testing.assert_array_equal(renumbered.label_image(), kept.label_image())


def test_ripple_test_has_no_value_condition():
    # As in the C++, a zone whose contour lies on a lower ring is that ring's ripple.
    values = np.full((9, 9), 100, np.uint8)
    values[2:7, 2:7] = 200
    graph = merge_ripples(ZoneGraph(flat_zones(values), values))
    assert len(graph) == 1 and graph.value(graph.vertices()[0]) == 100


def test_zone_touching_little_of_its_contour_is_not_a_ripple():
    values = np.zeros((12, 30), np.uint8)
    values[1:11, 1:15] = 200
    values[1:11, 15:29] = 100  # shares one side of four: about 25 % of its contour
    graph = merge_ripples(ZoneGraph(flat_zones(values), values))
    assert len(graph) == 2


def test_watershed_merges_similar_values_chained():
    # 200 -> 160 -> 125 each within t = 0.25 of the previous, not of the top.
    values = np.array([[200, 200, 160, 160, 125, 125, 40, 40]], np.uint8)
    graph = watershed_merge(ZoneGraph(flat_zones(values), values), threshold=0.25)
    assert graph.labels.tolist() == [[1, 1, 1, 1, 1, 1, 4, 4]]


def test_watershed_margin_needs_a_close_neighbour():
    # 140 vs 200: outside t = 0.25 (150) but inside t + margin (130).
    values = np.array([[200, 200, 140, 140]], np.uint8)
    graph = watershed_merge(ZoneGraph(flat_zones(values), values), threshold=0.25, margin=0.10)
    assert len(graph) == 2
    # With a neighbour of 140 close to 200 (160), 140 is absorbed.
    values = np.array([[200, 200, 140, 140, 160]], np.uint8)
    graph = watershed_merge(ZoneGraph(flat_zones(values), values), threshold=0.25, margin=0.10)
    assert graph.labels[0, 2] == graph.labels[0, 0]


def test_watershed_does_not_cross_unbreakable_edges():
    values = np.array([[200, 40, 190]], np.uint8)
    graph = ZoneGraph(flat_zones(values), values)
    graph.fuse(2, 1)
    mark_unbreakable_edges(graph, threshold=0.25)
    watershed_merge(graph, threshold=0.25)
    assert len(graph) == 2


def door_values() -> np.ndarray:
    values = np.zeros((12, 24), np.uint8)
    values[1:11, 1:11] = 200  # room A (zone 1)
    values[1:11, 13:23] = 200  # room B (zone 2)
    values[4:8, 11:13] = 50  # door between them (zone 3)
    return values


def test_remove_doors_fuses_connector_into_the_last_calm_neighbour():
    graph = ZoneGraph(flat_zones(door_values()), door_values())
    assert graph.contact_sum(3) == 100 and graph.contact_sum(1) < 40
    remove_doors(graph, doors=40)
    assert graph.vertices() == [1, 2]
    assert graph.labels[5, 11] == 2  # neighbours in order [1, 2]: the last one below 40


def test_remove_doors_threshold_is_strict():
    graph = ZoneGraph(flat_zones(door_values()), door_values())
    remove_doors(graph, doors=100)  # sum 100 is not > 100
    assert len(graph) == 3


def test_remove_isolated_zones_keeps_a_single_zone():
    values = np.array([[10, 10]], np.uint8)
    assert len(remove_isolated_zones(ZoneGraph(flat_zones(values), values))) == 1
