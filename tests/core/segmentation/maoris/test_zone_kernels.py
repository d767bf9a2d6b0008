"""The compiled zone-graph steps against plain-Python replays of the same rules.

The replays run on the dict form of :class:`ZoneGraph` through its public
mutations (``fuse``, ``remove``), with contact percentages counted here from
masks, so they share no code with the kernels (:mod:`ursim_core.segmentation.maoris.kernels`). They are slow, hence
small maps.
"""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np
import pytest

from ursim_core.segmentation.maoris import (
    PRESETS,
    ZoneGraph,
    flat_zones,
    inscribed_circle_image,
    mark_unbreakable_edges,
    merge_ripples,
    quantize,
    remove_doors,
    remove_small_zones,
    watershed_merge,
)

_SQUARE = np.ones((3, 3), np.uint8)


def mask_contact_percent(labels: np.ndarray, zone: int, other: int) -> int:
    """Percentage of ``zone``'s contour pixels (a 4-neighbour outside the zone,
    the image border counting as outside) with ``other`` in their 3x3 neighbourhood."""
    inside = np.pad(labels == zone, 1)
    all_four_inside = inside[:-2, 1:-1] & inside[2:, 1:-1] & inside[1:-1, :-2] & inside[1:-1, 2:]
    contour = (labels == zone) & ~all_four_inside
    near_other = cv2.dilate((labels == other).view(np.uint8), _SQUARE).astype(bool)
    size = int(contour.sum())
    return int((contour & near_other).sum()) * 100 // size if size else 0


def replay_remove_small_zones(graph: ZoneGraph, min_size: int) -> None:
    for zone in graph.vertices():
        if zone not in graph or graph.size(zone) >= min_size:
            continue
        neighbours = graph.neighbours(zone)
        if not neighbours:
            graph.remove(zone)
            continue
        gaps = [abs(graph.value(other) - graph.value(zone)) for other in neighbours]
        graph.fuse(zone, neighbours[gaps.index(min(gaps))])


def replay_merge_ripples(graph: ZoneGraph, ripples: float) -> None:
    queue = deque(sorted(graph.vertices(), key=lambda zone: (-graph.value(zone), graph.size(zone), zone)))
    while queue:
        zone = queue.popleft()
        if zone not in graph:
            continue
        candidates = [
            other
            for other in graph.neighbours(zone)
            if not graph.edge(zone, other).unbreakable and mask_contact_percent(graph.labels, zone, other) >= ripples
        ]
        if candidates:
            gaps = [abs(graph.value(other) - graph.value(zone)) for other in candidates]
            queue.extend(graph.neighbours(zone))
            graph.fuse(zone, candidates[gaps.index(min(gaps))])


def replay_remove_doors(graph: ZoneGraph, doors: float) -> None:
    def contact_sum(zone: int) -> int:
        return sum(mask_contact_percent(graph.labels, zone, other) for other in graph.neighbours(zone))

    sums = {zone: contact_sum(zone) for zone in graph.vertices()}
    for zone in graph.vertices():
        if zone not in graph or sums[zone] <= doors or not graph.neighbours(zone):
            continue
        below = [other for other in graph.neighbours(zone) if sums[other] < doors]
        target = below[-1] if below else graph.neighbours(zone)[0]
        graph.fuse(zone, target)
        sums[target] = contact_sum(target)


def graph_state(graph: ZoneGraph) -> tuple:
    """Everything later steps can observe: labels, sizes, and each neighbour list in order with its edge."""
    adjacency = {
        zone: [(other, graph.edge(zone, other).minimum, graph.edge(zone, other).unbreakable) for other in graph.neighbours(zone)]
        for zone in graph.vertices()
    }  # fmt: skip
    sizes = {zone: graph.size(zone) for zone in graph.vertices()}
    return graph.labels.tolist(), sizes, adjacency


def first_contact_adjacency(zones: np.ndarray) -> dict[int, list[int]]:
    """Neighbour lists in the raster order of first contact (left neighbour, then upper)."""
    adjacency: dict[int, list[int]] = {int(zone): [] for zone in np.unique(zones) if zone}
    rows, cols = zones.shape
    for row in range(rows):
        for col in range(cols):
            here = int(zones[row, col])
            for other_row, other_col in ((row, col - 1), (row - 1, col)):
                if here == 0 or other_row < 0 or other_col < 0:
                    continue
                other = int(zones[other_row, other_col])
                if other and other != here and other not in adjacency[here]:
                    low, high = min(here, other), max(here, other)
                    adjacency[low].append(high)
                    adjacency[high].append(low)
    return adjacency


def random_values(seed: int, shape=(40, 48)) -> np.ndarray:
    """A blobby free-space map's quantised inscribed-circle image: rings, ripples and tiny zones."""
    rng = np.random.default_rng(seed)
    free = cv2.GaussianBlur(rng.random(shape), (0, 0), 3) > 0.45
    free[rng.random(shape) < 0.02] = False
    return quantize(inscribed_circle_image(free))


@pytest.mark.parametrize("seed", range(12))
def test_initial_adjacency_is_in_first_contact_order(seed):
    values = random_values(seed)
    zones = flat_zones(values)
    graph = ZoneGraph(zones, values)
    expected = first_contact_adjacency(zones)
    assert graph.vertices() == sorted(expected)
    assert {zone: graph.neighbours(zone) for zone in graph.vertices()} == expected


@pytest.mark.parametrize("seed", range(12))
def test_compiled_small_zone_removal_equals_the_replay(seed):
    values = random_values(seed)
    compiled = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=10)
    replayed = ZoneGraph(flat_zones(values), values)
    replay_remove_small_zones(replayed, 10)
    assert graph_state(compiled) == graph_state(replayed)


@pytest.mark.parametrize("seed", range(12))
def test_compiled_ripple_merging_equals_the_replay(seed):
    values = random_values(seed)
    compiled = ZoneGraph(flat_zones(values), values)
    replayed = ZoneGraph(flat_zones(values), values)
    remove_small_zones(compiled, min_size=10)
    remove_small_zones(replayed, min_size=10)
    merge_ripples(compiled, ripples=PRESETS["default"].ripples)
    replay_merge_ripples(replayed, PRESETS["default"].ripples)
    assert graph_state(compiled) == graph_state(replayed)


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("doors", [20, 40, 60])
def test_compiled_door_removal_equals_the_replay(seed, doors):
    values = random_values(seed, shape=(56, 64))
    graphs = []
    for _ in range(2):
        graph = ZoneGraph(flat_zones(values), values)
        remove_small_zones(graph, min_size=10)
        merge_ripples(graph, ripples=40)
        mark_unbreakable_edges(graph, threshold=0.25)
        watershed_merge(graph, threshold=0.25, margin=0.10)
        graphs.append(graph)
    before = len(graphs[1])
    remove_doors(graphs[0], doors=doors)
    replay_remove_doors(graphs[1], doors)
    assert graph_state(graphs[0]) == graph_state(graphs[1])
    if doors == 20:
        assert len(graphs[1]) < before  # the maps do have doors to remove


def test_mask_contact_percent_matches_the_graph_contacts():
    values = random_values(4)
    graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=10)
    for zone in graph.vertices()[:20]:
        for other in graph.neighbours(zone):
            assert graph.contact_percent(zone, other) == mask_contact_percent(graph.labels, zone, other)


def test_a_graph_changed_in_dict_form_goes_back_to_the_compiled_steps():
    # Fusions made through the dict form (new edges with minima, an unbreakable
    # edge) must survive the conversion to arrays and back, in order.
    values = random_values(3)
    graphs = [ZoneGraph(flat_zones(values), values) for _ in range(2)]
    for graph in graphs:
        zone = graph.vertices()[len(graph) // 2]
        other = graph.neighbours(zone)[0]
        graph.edge(zone, other).unbreakable = True
        graph.fuse(graph.neighbours(zone)[-1], zone)
    remove_small_zones(graphs[0], min_size=10)
    replay_remove_small_zones(graphs[1], 10)
    assert graph_state(graphs[0]) == graph_state(graphs[1])


def test_vertices_and_membership_agree_in_both_forms():
    values = random_values(5)
    graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=10)
    compact_vertices, compact_length = graph.vertices(), len(graph)
    absent = next(zone for zone in range(1, int(flat_zones(values).max()) + 1) if zone not in compact_vertices)
    assert absent not in graph and compact_vertices[0] in graph
    graph.adj  # to the dict form
    assert graph.vertices() == compact_vertices and len(graph) == compact_length
    assert absent not in graph and compact_vertices[0] in graph


def _tracked_contacts(tracking) -> tuple[dict[tuple[int, int], int], list[list[int]]]:
    """Every non-zero contact count of a tracking state, and each zone's candidate list."""
    original, compact_of, state = tracking
    parent, pixels, following, head, tail, keys, counts, meta, slots, total = state
    n = len(parent)
    found: dict[tuple[int, int], int] = {(zone, 0): int(total[zone]) for zone in range(n) if total[zone]}
    for zone, row in enumerate(slots.reshape(n, -1)):
        for entry in row[1:]:
            if entry >= 0:
                found[(zone, int(entry >> 32))] = int(entry & 0xFFFFFFFF)
    for key, count in zip(keys.tolist(), counts.tolist()):
        if key != -1 and count:
            found[divmod(key, n)] = count
    lists = []
    for zone in range(n):
        walk, candidate = [], head[zone]
        while candidate != -1:
            walk.append(int(pixels[candidate]))
            candidate = following[candidate]
        lists.append(walk)
    return found, lists


@pytest.mark.parametrize("bands", [2, 3, 7])
def test_contacts_counted_in_bands_of_rows_equal_one_pass(bands):
    from ursim_core.segmentation.maoris import contact_tracking as _contacts
    from ursim_core.synth import make_large_building

    values = quantize(inscribed_circle_image(make_large_building(400, seed=bands).free), quantum=5)
    graph = ZoneGraph(flat_zones(values), values)
    remove_small_zones(graph, min_size=10)
    graph._run_compiled()
    results = []
    for count in (1, bands):
        labels = graph._labels.ravel().copy()
        results.append(
            _tracked_contacts(_contacts.start_tracking(labels, graph._labels.shape[1], graph._alive, bands=count))
        )
    assert len(results[0][0]) > 1000
    assert results[0] == results[1]


def test_segmentation_is_the_same_with_contacts_counted_in_bands(monkeypatch):
    from ursim_core.segmentation.maoris import contact_tracking as _contacts
    from ursim_core.segmentation.maoris import maoris_labels
    from ursim_core.synth import make_large_building

    free = make_large_building(600, seed=2).free
    expected = maoris_labels(free, PRESETS["robot"])
    monkeypatch.setattr(_contacts, "_BAND_PIXELS", 0)
    monkeypatch.setattr(_contacts, "usable_cpus", lambda: 3)
    np.testing.assert_array_equal(maoris_labels(free, PRESETS["robot"]), expected)


def test_grouped_candidates_are_each_zones_candidates_in_raster_order():
    """group_candidates against a stable sort by zone: each zone's list holds its candidates
    in raster order, stored contiguously."""
    from ursim_core.segmentation.maoris.compiled import kernels

    rng = np.random.default_rng(5)
    labels = np.pad(rng.integers(1, 7, (9, 11)).astype(np.int32), 2).ravel()
    n = 7
    pixels = np.flatnonzero(labels).astype(np.int32)[::2].copy()  # any raster-ordered subset
    used = len(pixels) - 3  # entries past ``used`` are ignored
    grouped, following, head, tail = kernels().group_candidates(labels, pixels, used, n)
    order = np.argsort(labels[pixels[:used]], kind="stable")
    np.testing.assert_array_equal(grouped[:used], pixels[:used][order])
    for zone in range(n):
        walk, candidate = [], head[zone]
        while candidate != -1:
            walk.append(int(grouped[candidate]))
            candidate = following[candidate]
        expected = [int(p) for p in pixels[:used] if labels[p] == zone]
        assert walk == expected
        assert (head[zone] == -1) == (not expected)
        if expected:
            assert tail[zone] - head[zone] == len(expected) - 1


def test_flat_zones_into_a_used_image_equal_fresh_ones():
    from ursim_core.synth import make_large_building

    values = quantize(inscribed_circle_image(make_large_building(300, seed=1).free), quantum=5)
    out = np.full(values.shape, 12345, np.int32)
    np.testing.assert_array_equal(flat_zones(values, out=out), flat_zones(values))
