"""MAORIS steps 4-7: the operations on the zone graph.

Each modifies a :class:`~ursim_core.segmentation.maoris.zone_graph.ZoneGraph` in place and
returns it: :func:`remove_small_zones`, :func:`merge_ripples` and :func:`mark_unbreakable_edges`
(step 4, ``GraphZone::removeRiplesv3``), :func:`watershed_merge` (step 5), :func:`remove_doors`
(step 6), :func:`remove_isolated_zones` (step 7, with :func:`remove_small_zones`).
"""

from __future__ import annotations

import numpy as np

from ursim_core.segmentation.maoris.compiled import kernels
from ursim_core.segmentation.maoris.contact_tracking import start_tracking
from ursim_core.segmentation.maoris.zone_graph import ZoneGraph

__all__ = [
    "remove_small_zones",
    "merge_ripples",
    "mark_unbreakable_edges",
    "watershed_merge",
    "remove_doors",
    "remove_isolated_zones",
]


def remove_small_zones(graph: ZoneGraph, *, min_size: int) -> ZoneGraph:
    """Fuse every zone smaller than ``min_size`` px into its closest-valued neighbour.

    One pass in vertex order, sizes as they are when a zone is visited; ties
    go to the first neighbour; a small zone without neighbours is deleted.
    Fusions transfer edges as :meth:`ZoneGraph.fuse` does.

    Examples
    --------
    >>> from ursim_core.segmentation.maoris import flat_zones
    >>> values = np.array([[10, 10, 10, 30]], np.uint8)
    >>> graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=2)
    >>> graph.labels.tolist()
    [[1, 1, 1, 1]]
    """
    compact = graph._run_compiled()
    # int32 from the start: np.where of an arange went through two int64 arrays of one entry per
    # zone (6.5 million at 8000 px), and at that size fresh memory costs as much as the loop.
    parent = np.arange(len(graph._value_array), dtype=np.int32)
    parent[~graph._alive] = 0
    kernels().remove_small_zones(int(min_size), graph._size, graph._alive, parent, compact)
    kernels().resolve_parents(parent, graph._alive)
    kernels().relabel(graph._labels.ravel(), parent)
    return graph


def merge_ripples(graph: ZoneGraph, *, ripples: float = 40, _renumber: bool = False) -> ZoneGraph:
    """Fuse ripple zones into the neighbour they wrap (``removeRiplesv3``).

    A zone z is a ripple of a neighbour B when ``contact_percent(z, B) >=
    ripples``. Zones are visited by decreasing value (smaller size first on
    ties, then by id); a ripple is fused into the candidate B of closest value
    (the first on ties) reached through a breakable edge, and its neighbours
    are queued again.

    Examples
    --------
    >>> from ursim_core.segmentation.maoris import flat_zones
    >>> values = np.full((7, 7), 100, np.uint8); values[2:5, 2:5] = 200
    >>> graph = merge_ripples(ZoneGraph(flat_zones(values), values))
    >>> len(graph)   # the ring touches the core on >= 40 % of its contour
    1

    ``_renumber`` (private, :func:`~ursim_core.segmentation.maoris.maoris_labels`): the zones
    that enter the step are renumbered 1..n in the order of their ids, so the zones left keep
    their order under new ids (every later order, hence the labels, unchanged). The steps after this one then work on arrays of the few hundred thousand zones
    that entered it rather than of the millions of flat zones (at 8000 x 8000 px, 6.5 million:
    150 MB of arrays no longer made).
    """
    compact = graph._run_compiled()
    zones = np.flatnonzero(graph._alive)
    order = zones[np.lexsort((graph._size[zones], -graph._value_array[zones]))].astype(np.int32)
    labels, width = graph._labels.ravel(), graph._labels.shape[1]
    original, compact_of, n = kernels()._compact_labels(labels, graph._alive)
    # The kernel runs on the live zones renumbered in id order (the same order, ties and
    # lists): their records and nodes in a few MB rather than scattered through the graph's
    # (kernels' compact_graph). So the tracking's compact ids are the zones' own.
    small = kernels().compact_graph(original, compact_of, compact)
    # The graph's own nodes (435 MB at 8000 px, most of them the edges of zones merged away as
    # small) are not read again: dropped before the contacts are counted, the peak memory's step.
    graph._compact = compact = (compact[0], small[1])
    original, compact_of, state = start_tracking(labels, width, graph._alive, compacted=(original, compact_of, n))
    size = np.zeros(len(original) + 1, np.int64)
    size[1:] = graph._size[original]
    alive = np.ones(len(original) + 1, bool)
    alive[0] = False
    identity = np.arange(len(original) + 1, dtype=np.int32)
    # Renumbered, the labels are restored as the compact ids themselves.
    restored_as = identity[1:] if _renumber else original
    kernels().merge_ripples(
        compact_of[order], float(ripples), labels, width, size, alive, small, (restored_as, identity, state)
    )
    if _renumber:
        graph._renumbered(original, size, alive, small)
        return graph
    kernels().expand_graph(original, small, compact[0])
    graph._size[original] = size[1:]
    graph._alive[original] = alive[1:]
    return graph


def mark_unbreakable_edges(graph: ZoneGraph, *, threshold: float) -> ZoneGraph:
    """Make an edge unbreakable if its recorded minimum is a deep enough valley.

    An edge (a, b) that carries a minimum becomes unbreakable when
    ``minimum <= max(value(a), value(b)) * (1 - threshold)``.
    """
    for a in graph.vertices():
        for b, edge in graph.adj[a].items():
            if (
                edge is not None
                and edge.minimum is not None
                and edge.minimum <= max(graph.value(a), graph.value(b)) * (1 - threshold)
            ):
                edge.unbreakable = True
    return graph


def _similar(a: int, b: int, threshold: float) -> bool:
    high, low = (a, b) if a >= b else (b, a)
    return low >= high * (1 - threshold)


def _close_neighbour(graph: ZoneGraph, current: int, candidate: int, threshold: float) -> bool:
    # closeNeigh: another neighbour of one of the two, reached through a
    # breakable edge (the only edges the watershed looks through), is within t
    # of the other one.
    value_current, value_candidate = graph.value(current), graph.value(candidate)
    for one, other_value, skip in ((candidate, value_current, current), (current, value_candidate, candidate)):
        for m, edge in graph.adj[one].items():
            if (
                m != skip
                and (edge is None or not edge.unbreakable)
                and _similar(graph.value(m), other_value, threshold)
            ):
                return True
    return False


def watershed_merge(graph: ZoneGraph, *, threshold: float, margin: float = 0.10) -> ZoneGraph:
    """Merge neighbouring zones of similar value into the highest one (``watershed``).

    Tops are visited by decreasing value (larger size first on ties). The
    flood from a top is the C++ recursion: a call on zone c first scans all
    of c's neighbours in edge order, marking each one not yet visited as
    visited, *whether its edge is breakable or not*; a neighbour reached
    through a breakable edge is absorbed if, with hi/lo the values of c and
    the neighbour, ``lo >= hi * (1 - t)``, or if ``lo >= hi * (1 - t -
    margin)`` and another neighbour of one of the two, through a breakable
    edge, is within t of the other. Only then does the recursion run on the
    zones absorbed from c, in that order. So a zone met first across an
    unbreakable edge, or rejected once, is not absorbed through another path
    of the same flood (a later top may still take it). All absorptions are
    decided on the graph as it was at the start, then fused.

    Examples
    --------
    >>> from ursim_core.segmentation.maoris import flat_zones
    >>> values = np.array([[200, 200, 180, 180, 60, 60]], np.uint8)
    >>> graph = watershed_merge(ZoneGraph(flat_zones(values), values), threshold=0.25)
    >>> graph.labels.tolist()
    [[1, 1, 1, 1, 3, 3]]
    """
    order = sorted(graph.vertices(), key=lambda zone: (-graph.value(zone), -graph.size(zone)))
    absorbed: set[int] = set()
    groups: list[tuple[int, list[int]]] = []
    low_factor = 1 - threshold - margin
    for top in order:
        if top in absorbed:
            continue
        absorbed.add(top)
        visited = {top}
        members: list[int] = []
        # Stack of the zones still to expand, one list per scanned zone (the
        # recursion of the C++, without Python's recursion limit).
        stack = [iter([top])]
        while stack:
            current = next(stack[-1], None)
            if current is None:
                stack.pop()
                continue
            taken = []
            for neighbour, edge in graph.adj[current].items():
                if neighbour in visited or neighbour in absorbed:
                    continue
                visited.add(neighbour)
                if edge is not None and edge.unbreakable:
                    continue
                a, b = graph.value(current), graph.value(neighbour)
                high, low = max(a, b), min(a, b)
                if low >= high * (1 - threshold) or (
                    low >= high * low_factor and _close_neighbour(graph, current, neighbour, threshold)
                ):
                    absorbed.add(neighbour)
                    members.append(neighbour)
                    taken.append(neighbour)
            if taken:
                stack.append(iter(taken))
        if members:
            groups.append((top, members))
    for top, members in groups:
        for member in members:
            graph.fuse(member, top)
    return graph


def remove_doors(graph: ZoneGraph, *, doors: float = 40) -> ZoneGraph:
    """Fuse door-like regions, whose contour mostly touches other regions (``removeDoors``).

    A region whose contact sum (:meth:`ZoneGraph.contact_sum`) exceeds ``doors``
    is fused into the last neighbour whose own sum is below ``doors``, else into
    its first neighbour; the receiver's sum is then recomputed. Zones are
    visited in id order, with the sums taken before the first fusion except
    for receivers. Runs compiled, tracking contacts as :func:`merge_ripples`.

    Examples
    --------
    >>> from ursim_core.segmentation.maoris import flat_zones
    >>> values = np.zeros((12, 24), np.uint8)
    >>> values[1:11, 1:11] = values[1:11, 13:23] = 200   # two rooms
    >>> values[4:8, 11:13] = 50                           # a door
    >>> graph = ZoneGraph(flat_zones(values), values)
    >>> graph.contact_sum(3), remove_doors(graph).vertices()
    (100, [1, 2])
    """
    compact = graph._run_compiled()
    labels, width = graph._labels.ravel(), graph._labels.shape[1]
    tracking = start_tracking(labels, width, graph._alive)
    kernels().remove_doors(float(doors), labels, width, graph._size, graph._alive, compact, tracking)
    return graph


def remove_isolated_zones(graph: ZoneGraph) -> ZoneGraph:
    """Delete zones without neighbours, when there is more than one zone
    (``removeLonelyVertices``).

    Examples
    --------
    >>> from ursim_core.segmentation.maoris import flat_zones
    >>> values = np.array([[10, 0, 20, 30]], np.uint8)
    >>> remove_isolated_zones(ZoneGraph(flat_zones(values), values)).vertices()
    [2, 3]
    """
    if len(graph) > 1:
        for zone in graph.vertices():
            if not graph.adj[zone]:
                graph.remove(zone)
    return graph
