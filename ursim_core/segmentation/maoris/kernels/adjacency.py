"""The compact MAORIS zone graph and its edge operations (numba).

A large map starts with millions of flat zones, almost all of them a few
pixels; the graph steps visit them one by one in an order that matters, so
they cannot be vectorised. These kernels run them on a compact array form of
the graph, laid out so that a step touches few cache lines (at 4000 px the
work is bound by memory latency, not arithmetic):

* a zone is a record of 16 bytes (first and last neighbour node, degree,
  value); its neighbours form a doubly linked list of *node* records, in
  insertion order (the order the C++ boost ``listS`` graph iterates in);
* the node (a -> b) and its twin (b -> a) are neighbours in memory, ``node``
  and ``node ^ 1``, and share the edge attributes (minimum, -1 for none, in
  the even node; unbreakability in the odd one); a new edge made by a fusion
  reuses the pair of the edge it replaces, so no node is ever allocated after
  the adjacency is built;
* the steps that need contact counts (ripple merging, door removal) keep them
  up to date: a fusion visits the pixels around the absorbed zone once and
  applies only the changes. Zones are union-find sets of compact labels (the
  image is relabelled once, at the end), each zone keeps a list of its pixels
  that may still be on its border, and its contact partners sit in a few
  slots of its own, with a shared hash table for zones that have more.

:class:`ursim_core.segmentation.maoris.zone_graph.ZoneGraph` owns the arrays; the
functions here only mutate them. Semantics are those documented on
``flat_zones``, ``remove_small_zones``, ``merge_ripples``, ``remove_doors``
and ``ZoneGraph.fuse``. The kernels called from Python are compiled once
for the signatures of :mod:`.signatures` and cached by numba. The small helpers of the loops are ``loop_helper``
functions: compiled without reference counting, inlined by LLVM.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.constants import NO_MINIMUM
from ursim_core.segmentation.maoris.kernels.helpers import inner_kernel, loop_helper

# Columns of the zone records (one row of 16 bytes per zone).
HEAD, TAIL, DEGREE, VALUE = 0, 1, 2, 3
# Columns of the node records (16 bytes; a node and its twin share 32 bytes).
# A node's twin is ``node ^ 1``; the edge attributes sit in the ATTRIBUTE
# column of the pair: the minimum in the even node, unbreakability in the odd one.
NEIGHBOUR, NEXT, PREVIOUS, ATTRIBUTE = 0, 1, 2, 3


@inner_kernel
def _contacts_in_order(zones, last_partner, records, nodes, count_only):
    """Scan the 4-contacts of a zone image in raster order (each pixel against
    its left, then its upper neighbour) and link the new edges; or, with
    ``count_only``, return how many pairs would be looked up (a bound on the
    number of edges). Returns the number of nodes used otherwise."""
    rows, cols = zones.shape
    n_candidates = 0
    n_nodes = np.int64(0)  # typed, not a literal: a literal argument compiles a callee twice
    for row in range(rows):
        last_left_a, last_left_b = -1, -1
        for col in range(cols):
            here = zones[row, col]
            if here == 0:
                continue
            for kind in range(2):
                if kind == 0:
                    if col == 0:
                        continue
                    other = zones[row, col - 1]
                else:
                    if row == 0:
                        continue
                    other = zones[row - 1, col]
                if other == 0 or other == here:
                    continue
                a, b = min(here, other), max(here, other)
                if kind == 0:
                    # A run of contacts between the same two zones along a row.
                    if a == last_left_a and b == last_left_b:
                        continue
                    last_left_a, last_left_b = a, b
                elif col > 0 and zones[row, col - 1] == here and zones[row - 1, col - 1] == other:
                    continue  # same pair as the pixel to the left
                # The partner each zone met last: long boundaries repeat the same pair.
                if last_partner[a] == b or last_partner[b] == a:
                    continue
                last_partner[a], last_partner[b] = b, a
                n_candidates += 1
                if count_only or _find(records, nodes, a, b) != -1:
                    continue
                _link_pair(records, nodes, n_nodes, a, b, NO_MINIMUM, 0)
                n_nodes += 2
    return n_candidates if count_only else n_nodes


@inner_kernel
def _isolated_zones(value):
    """Zone records without neighbours, zone z of value ``value[z]``."""
    records = np.empty((len(value), 4), np.int32)
    for zone in range(len(value)):
        records[zone, HEAD] = -1
        records[zone, TAIL] = -1
        records[zone, DEGREE] = 0
        records[zone, VALUE] = value[zone]
    return records


@njit(cache=True)
def build_adjacency(zones, value):
    """Zone graph of the 4-adjacency of a zone image (0 = no zone): ``(records, nodes)``.

    ``value[z]`` is zone z's value (``len(value)`` = largest label + 1). Edges
    are inserted in the raster order of their first contact. Two passes: the
    first bounds the number of edges, so the node records never move.
    """
    count = len(value)
    records = _isolated_zones(value)
    last_partner = np.zeros(count, np.int32)
    # np.bool_, not the literals True and False: one compile of _contacts_in_order, not two.
    bound = _contacts_in_order(zones, last_partner, records, np.empty((2, 4), np.int32), np.bool_(True))
    for zone in range(count):
        last_partner[zone] = 0
    nodes = np.empty((max(2 * bound, 2), 4), np.int32)
    _contacts_in_order(zones, last_partner, records, nodes, np.bool_(False))
    # Not trimmed to the nodes used: a slice would be typed as another array
    # layout, and every kernel taking the graph compiled twice.
    return records, nodes


@loop_helper
def _link_pair(records, nodes, node, a, b, minimum, unbreakable):
    """Append the edge (a, b) to both lists as the twin nodes ``node`` (a -> b,
    ``node`` even) and ``node + 1``."""
    _append(records, nodes, a, node, b)
    _append(records, nodes, b, node + 1, a)
    nodes[node, ATTRIBUTE] = minimum
    nodes[node + 1, ATTRIBUTE] = unbreakable


@njit(cache=True)
def _link_entries(zone, other, owner, minimum, unbreakable, value):
    """:func:`adjacency_from_entries` given each entry's owner entry."""
    records = _isolated_zones(value)
    nodes = np.empty((max(2 * len(zone), 2), 4), np.int32)
    for i in range(len(zone)):
        node = 2 * owner[i] if zone[i] < other[i] else 2 * owner[i] + 1
        _append(records, nodes, zone[i], node, other[i])
        if zone[i] < other[i]:
            nodes[node, ATTRIBUTE] = minimum[i]
            nodes[node + 1, ATTRIBUTE] = unbreakable[i]
    return records, nodes


@njit(cache=True)
def adjacency_entries(alive, graph):
    """Every (zone, neighbour, node, twin, minimum, unbreakable) of the live
    zones, zones in id order and each zone's neighbours in list order."""
    records, nodes = graph
    total = 0
    for zone in range(len(alive)):
        if alive[zone]:
            total += records[zone, DEGREE]
    out = np.empty((total, 6), np.int64)
    k = 0
    for zone in range(len(alive)):
        if not alive[zone]:
            continue
        node = records[zone, HEAD]
        while node != -1:
            out[k, 0] = zone
            out[k, 1] = nodes[node, NEIGHBOUR]
            out[k, 2] = node
            out[k, 3] = node ^ 1
            out[k, 4] = nodes[node & ~1, ATTRIBUTE]
            out[k, 5] = nodes[node | 1, ATTRIBUTE]
            k += 1
            node = nodes[node, NEXT]
    return out


@loop_helper
def _append(records, nodes, zone, node, other):
    nodes[node, NEIGHBOUR] = other
    nodes[node, NEXT] = -1
    tail = records[zone, TAIL]
    nodes[node, PREVIOUS] = tail
    if tail == -1:
        records[zone, HEAD] = node
    else:
        nodes[tail, NEXT] = node
    records[zone, TAIL] = node
    records[zone, DEGREE] += 1


@loop_helper
def _unlink(records, nodes, zone, node):
    before, after = nodes[node, PREVIOUS], nodes[node, NEXT]
    if before == -1:
        records[zone, HEAD] = after
    else:
        nodes[before, NEXT] = after
    if after == -1:
        records[zone, TAIL] = before
    else:
        nodes[after, PREVIOUS] = before
    records[zone, DEGREE] -= 1


@loop_helper
def _find(records, nodes, a, b):
    """Node (a -> b), or -1; walks the shorter of the two lists."""
    if records[a, DEGREE] <= records[b, DEGREE]:
        node = records[a, HEAD]
        while node != -1:
            if nodes[node, NEIGHBOUR] == b:
                return node
            node = nodes[node, NEXT]
        return -1
    node = records[b, HEAD]
    while node != -1:
        if nodes[node, NEIGHBOUR] == a:
            return node ^ 1
        node = nodes[node, NEXT]
    return -1


@loop_helper
def fuse_edges(zone, into, graph):
    """Transfer the edges of ``zone`` to ``into`` (``ZoneGraph.fuse``, edges only).

    Callers pass int64 ids: each other integer type would compile another copy.

    A new edge (into, n) reuses the node pair of the edge (zone, n) it
    replaces, so the node records never grow.
    """
    records, nodes = graph
    zone_value = records[zone, VALUE]
    node = records[zone, HEAD]
    while node != -1:
        following = nodes[node, NEXT]
        other = nodes[node, NEIGHBOUR]
        old_minimum = nodes[node & ~1, ATTRIBUTE]
        old_unbreakable = nodes[node | 1, ATTRIBUTE]
        _unlink(records, nodes, other, node ^ 1)
        if other != into:
            existing = _find(records, nodes, into, other)
            if existing == -1:
                if old_minimum == NO_MINIMUM or zone_value < old_minimum:
                    new_minimum = zone_value
                else:
                    new_minimum = old_minimum
                _append(records, nodes, into, node, other)
                _append(records, nodes, other, node ^ 1, into)
                nodes[node & ~1, ATTRIBUTE] = new_minimum
                nodes[node | 1, ATTRIBUTE] = old_unbreakable
            elif old_unbreakable:
                nodes[existing | 1, ATTRIBUTE] = 1
        node = following
    records[zone, HEAD] = records[zone, TAIL] = -1
    records[zone, DEGREE] = 0


@njit(cache=True)
def remove_small_zones(min_size, size, alive, parent, graph):
    """One pass in id order: fuse each zone below ``min_size`` px into its
    closest-valued neighbour (first on ties), delete it when it has none.

    ``parent[z]`` records where z went (0 = deleted); sizes are updated.
    """
    records, nodes = graph
    for zone in range(1, len(records)):
        if not alive[zone] or size[zone] >= min_size:
            continue
        alive[zone] = False
        if records[zone, DEGREE] == 0:
            parent[zone] = 0
            continue
        zone_value = records[zone, VALUE]
        closest, closest_gap = -1, 1 << 30
        node = records[zone, HEAD]
        while node != -1:
            other = nodes[node, NEIGHBOUR]
            gap = abs(records[other, VALUE] - zone_value)
            if gap < closest_gap:
                closest, closest_gap = other, gap
            node = nodes[node, NEXT]
        parent[zone] = closest
        size[closest] += size[zone]
        fuse_edges(np.int64(zone), np.int64(closest), graph)


@njit(cache=True)
def compact_graph(original, compact_of, graph):
    """The graph of the live zones renumbered 1..n - 1 (``compact_of``; ``original[k - 1]``
    is the id of compact zone k), in fresh arrays: ``(records, nodes)`` as
    :func:`build_adjacency` gives them, every list in the same order, each edge's
    attributes kept in the same parity of its pair.

    Ripple merging visits the few hundred thousand zones left of the millions a large map
    starts with, and at 8000 px their records lay in an array of 100 MB and their nodes
    anywhere in one larger still: each neighbour it looked at cost cache misses. Compact,
    the records take a few MB and each zone's first nodes sit together. The PREVIOUS
    links of ``graph``'s nodes are overwritten (they hold each twin's new node while the
    lists are copied): the graph must be replaced by :func:`expand_graph` of the result.
    """
    records, nodes = graph
    n = len(original) + 1
    total = 0
    for k in range(len(original)):
        total += records[original[k], DEGREE]
    compact_records = np.empty((n, 4), np.int32)
    for zone in range(n):
        compact_records[zone, HEAD] = -1
        compact_records[zone, TAIL] = -1
        compact_records[zone, DEGREE] = 0
        compact_records[zone, VALUE] = records[original[zone - 1], VALUE] if zone > 0 else 0
    compact_nodes = np.empty((max(total, 2), 4), np.int32)
    pairs = 0
    for k in range(len(original)):
        a = k + 1
        node = records[original[k], HEAD]
        while node != -1:
            b = compact_of[nodes[node, NEIGHBOUR]]
            if b > a:
                # The first end met of an edge takes the next pair, with the same parity.
                new = 2 * pairs + (node & 1)
                pairs += 1
                nodes[node ^ 1, PREVIOUS] = new ^ 1
                compact_nodes[new & ~1, ATTRIBUTE] = nodes[node & ~1, ATTRIBUTE]
                compact_nodes[new | 1, ATTRIBUTE] = nodes[node | 1, ATTRIBUTE]
            else:
                new = nodes[node, PREVIOUS]
            _append(compact_records, compact_nodes, a, new, b)
            node = nodes[node, NEXT]
    return compact_records, compact_nodes


@njit(cache=True)
def expand_graph(original, compact, records):
    """Undo :func:`compact_graph` after its zones changed: ``records`` (of every original
    zone) get the compact records of the live zones, the compact nodes (relabelled in place,
    in original ids) replace the nodes of the graph. Zones fused meanwhile have no neighbour
    left, and those already dead had none."""
    compact_records, compact_nodes = compact
    for k in range(len(original)):
        zone = original[k]
        records[zone, HEAD] = compact_records[k + 1, HEAD]
        records[zone, TAIL] = compact_records[k + 1, TAIL]
        records[zone, DEGREE] = compact_records[k + 1, DEGREE]
        node = compact_records[k + 1, HEAD]
        while node != -1:
            compact_nodes[node, NEIGHBOUR] = original[compact_nodes[node, NEIGHBOUR] - 1]
            node = compact_nodes[node, NEXT]
