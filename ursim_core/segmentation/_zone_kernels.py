"""Compiled kernels of the MAORIS zone graph (numba).

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

:class:`ursim_core.segmentation.maoris.ZoneGraph` owns the arrays; the
functions here only mutate them. Semantics are those documented on
``flat_zones``, ``remove_small_zones``, ``merge_ripples``, ``remove_doors``
and ``ZoneGraph.fuse``. Compilation takes about 43 s the first time,
and numba caches it. The small helpers of the loops are ``loop_helper``
functions: compiled without reference counting, inlined by LLVM.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from ursim_core.segmentation._loop_helpers import loop_helper

NO_MINIMUM = -1


@intrinsic
def _prefetch(typingctx, array, index):
    """Ask the CPU to start loading the cache line of ``array[index]`` (no
    bounds check; a hint only, never faults). A fusion's border pixels lie on
    distinct rows of a label image far larger than the cache: loading a few
    pixels ahead overlaps their memory latencies."""
    signature = types.void(array, index)

    def codegen(context, builder, signature, args):
        array_type = signature.args[0]
        array_value = context.make_array(array_type)(context, builder, args[0])
        pointer = cgutils.get_item_pointer(context, builder, array_type, array_value, [args[1]], wraparound=False)
        i32 = ir.IntType(32)
        prefetch = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [pointer.type, i32, i32, i32]), "llvm.prefetch.p0"
        )
        builder.call(prefetch, [pointer, i32(0), i32(3), i32(1)])  # read, keep in all levels, data
        return context.get_dummy_value()

    return signature, codegen


@njit(cache=True)
def label_flat_zones(values):
    """4-connected components of equal non-zero value, numbered 1..N in the
    raster order of their first pixel (0 stays 0).

    One raster pass with union-find over provisional labels: a set's root is
    always its smallest label, i.e. the one its first pixel created, so
    numbering the roots in order numbers the zones in first-pixel order.
    """
    rows, cols = values.shape
    labels = np.zeros((rows, cols), np.int32)
    parent = np.empty(1024, np.int32)
    n = 0
    for row in range(rows):
        for col in range(cols):
            value = values[row, col]
            if value == 0:
                continue
            left = labels[row, col - 1] if col > 0 and values[row, col - 1] == value else 0
            up = labels[row - 1, col] if row > 0 and values[row - 1, col] == value else 0
            if left == 0 and up == 0:
                n += 1
                if n == len(parent):
                    parent = _grown(parent, 2 * n, 0)
                parent[n] = n
                labels[row, col] = n
            else:
                labels[row, col] = left if left != 0 else up
                if left != 0 and up != 0:
                    a, b = _zone_of(left, parent), _zone_of(up, parent)
                    if a < b:
                        parent[b] = a
                    elif b < a:
                        parent[a] = b
    final = np.zeros(n + 1, np.int32)
    zones = 0
    for label in range(1, n + 1):
        root = _zone_of(label, parent)
        if root == label:
            zones += 1
            final[label] = zones
        else:
            final[label] = final[root]
    relabel(labels, final)
    return labels


@njit(cache=True)
def zone_values_and_sizes(zones, values, count):
    """Each zone's value (of any of its pixels) and size, zones 0..count - 1."""
    value = np.zeros(count, np.int32)
    size = np.zeros(count, np.int64)
    for row in range(zones.shape[0]):
        for col in range(zones.shape[1]):
            zone = zones[row, col]
            value[zone] = values[row, col]
            size[zone] += 1
    return value, size


# Columns of the zone records (one row of 16 bytes per zone).
HEAD, TAIL, DEGREE, VALUE = 0, 1, 2, 3
# Columns of the node records (16 bytes; a node and its twin share 32 bytes).
# A node's twin is ``node ^ 1``; the edge attributes sit in the ATTRIBUTE
# column of the pair: the minimum in the even node, unbreakability in the odd one.
NEIGHBOUR, NEXT, PREVIOUS, ATTRIBUTE = 0, 1, 2, 3


@njit(cache=True)
def _contacts_in_order(zones, last_partner, records, nodes, count_only):
    """Scan the 4-contacts of a zone image in raster order (each pixel against
    its left, then its upper neighbour) and link the new edges; or, with
    ``count_only``, return how many pairs would be looked up (a bound on the
    number of edges). Returns the number of nodes used otherwise."""
    rows, cols = zones.shape
    n_candidates = 0
    n_nodes = 0
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


@njit(cache=True)
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
    bound = _contacts_in_order(zones, last_partner, records, np.empty((2, 4), np.int32), True)
    for zone in range(count):
        last_partner[zone] = 0
    nodes = np.empty((max(2 * bound, 2), 4), np.int32)
    _contacts_in_order(zones, last_partner, records, nodes, False)
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
def adjacency_from_entries(zone, other, minimum, unbreakable, value):
    """Zone graph from (zone, neighbour, minimum, unbreakable) entries, each
    zone's in list order: the inverse of :func:`adjacency_entries`. Every edge
    must appear in both directions, with the same attributes."""
    count = len(value)
    records = _isolated_zones(value)
    # Entry i of an edge (low -> high) owns the node pair 2i, 2i + 1; the
    # reversed entry finds it by key.
    keys = zone.astype(np.int64) * count + other
    order = np.argsort(keys)
    sorted_keys = keys[order]
    nodes = np.empty((max(2 * len(zone), 2), 4), np.int32)
    for i in range(len(zone)):
        low, high = min(zone[i], other[i]), max(zone[i], other[i])
        owner = order[np.searchsorted(sorted_keys, np.int64(low) * count + high)]
        node = 2 * owner if zone[i] == low else 2 * owner + 1
        _append(records, nodes, zone[i], node, other[i])
        if zone[i] == low:
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
def _filled(size, fill, dtype):
    # np.full and slice assignments cost seconds of compilation each; loops do not.
    array = np.empty(size, dtype)
    for i in range(size):
        array[i] = fill
    return array


@njit(cache=True)
def _grown(array, capacity, fill):
    grown = np.empty(capacity, array.dtype)
    for i in range(capacity):
        grown[i] = array[i] if i < len(array) else fill
    return grown


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


# -- contact counts ------------------------------------------------------
#
# A hash table of int64 keys ``a * base + b`` -> count, open addressing with
# linear probing (much faster than a typed dict for millions of updates).
# ``meta`` holds [entries, bits]; a growing table is returned anew.

_EMPTY = -1
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MEMO = 64  # recently used keys -> slots: neighbouring pixels repeat the same few keys


@njit(cache=True)
def _new_table(bits):
    """Empty table with 2**bits slots: keys, counts and ``meta`` = [entries, bits,
    memo keys (_MEMO), memo slots (_MEMO)]."""
    meta = _filled(2 + 2 * _MEMO, _EMPTY, np.int64)
    meta[0], meta[1] = 0, bits
    return _filled(1 << bits, _EMPTY, np.int64), np.zeros(1 << bits, np.int64), meta


@loop_helper
def _probe(keys, key, bits):
    mask = len(keys) - 1
    slot = np.int64((np.uint64(key) * _GOLDEN) >> np.uint64(64 - bits))
    while keys[slot] != _EMPTY and keys[slot] != key:
        slot = (slot + 1) & mask
    return slot


@loop_helper
def _slot(keys, meta, key):
    memo = 2 + (key & (_MEMO - 1))
    if meta[memo] == key:
        return meta[memo + _MEMO]
    slot = _probe(keys, key, meta[1])
    if keys[slot] == key:
        meta[memo] = key
        meta[memo + _MEMO] = slot
    return slot


@loop_helper
def table_get(keys, counts, meta, key):
    """Count under ``key`` (0 when absent)."""
    slot = _slot(keys, meta, key)
    return counts[slot] if keys[slot] == key else 0


@loop_helper
def _table_add(keys, counts, meta, key, delta):
    slot = _slot(keys, meta, key)
    if keys[slot] == key:
        counts[slot] += delta
    else:
        keys[slot] = key
        counts[slot] = delta
        meta[0] += 1


@njit(cache=True)
def _table_reserve(keys, counts, meta, more):
    """The table itself, or a larger copy if ``more`` new keys could overfill it."""
    if 2 * (meta[0] + more) <= len(keys):
        return keys, counts
    bits = meta[1]
    while 2 * (meta[0] + more) > (1 << bits):
        bits += 1
    grown_keys, grown_counts, _ = _new_table(bits)
    for old in range(len(keys)):
        if keys[old] != _EMPTY:
            slot = _probe(grown_keys, keys[old], bits)
            grown_keys[slot] = keys[old]
            grown_counts[slot] = counts[old]
    meta[1] = bits
    for i in range(2, len(meta)):
        meta[i] = _EMPTY
    return grown_keys, grown_counts


# Each zone's contacts start in a row of its own in one int64 array (one cache
# line): [overflow flag, then up to 7 entries (partner << 32) + count, -1 = free].
# Partners beyond 7 go to the shared table.
_SLOTS = 8
_COUNT = np.int64(0xFFFFFFFF)


@loop_helper
def contact_get(slots, keys, counts, meta, base, a, b):
    """Contact count (a, b): from a's own row, else from the shared table."""
    start = a * _SLOTS
    for k in range(start + 1, start + _SLOTS):
        entry = slots[k]
        if entry >= 0 and (entry >> 32) == b:
            return entry & _COUNT
    if slots[start] != 0:
        return table_get(keys, counts, meta, a * base + b)
    return 0


@loop_helper
def _contact_add(slots, keys, counts, meta, base, a, b, delta):
    start = a * _SLOTS
    free = -1
    for k in range(start + 1, start + _SLOTS):
        entry = slots[k]
        if entry >= 0:
            if (entry >> 32) == b:
                entry += delta
                slots[k] = entry if entry & _COUNT else -1
                return
        elif free == -1:
            free = k
    if slots[start] != 0:
        key = a * base + b
        slot = _slot(keys, meta, key)
        if keys[slot] == key:
            counts[slot] += delta
            return
    if free != -1:
        # A new contact only ever starts with a positive count.
        slots[free] = (np.int64(b) << 32) + delta
        return
    slots[start] = 1
    _table_add(keys, counts, meta, a * base + b, delta)


@loop_helper
def _zone_of(label, parent):
    """Current zone of an original label (union-find root, with path halving)."""
    while parent[label] != label:
        parent[label] = parent[parent[label]]
        label = parent[label]
    return label


@loop_helper
def _neighbourhood(labels, parent, pixel, width, around):
    """Write the zones of a pixel's 3x3 neighbourhood, row by row, into
    ``around`` (index 4: the pixel)."""
    # Written out: numba compiles loops over tuples of offsets into slow code.
    up, down = pixel - width, pixel + width
    around[0] = _zone_of(labels[up - 1], parent)
    around[1] = _zone_of(labels[up], parent)
    around[2] = _zone_of(labels[up + 1], parent)
    around[3] = _zone_of(labels[pixel - 1], parent)
    around[4] = _zone_of(labels[pixel], parent)
    around[5] = _zone_of(labels[pixel + 1], parent)
    around[6] = _zone_of(labels[down - 1], parent)
    around[7] = _zone_of(labels[down], parent)
    around[8] = _zone_of(labels[down + 1], parent)


@loop_helper
def _raw_neighbourhood(labels, pixel, width, around):
    """:func:`_neighbourhood` before any fusion (every label its own zone)."""
    up, down = pixel - width, pixel + width
    around[0], around[1], around[2] = labels[up - 1], labels[up], labels[up + 1]
    around[3], around[4], around[5] = labels[pixel - 1], labels[pixel], labels[pixel + 1]
    around[6], around[7], around[8] = labels[down - 1], labels[down], labels[down + 1]


@loop_helper
def _is_contour(around):
    """Whether the pixel whose 3x3 zones are ``around`` is a contour pixel: in a
    zone, with a 4-neighbour in another zone (or none)."""
    own = around[4]
    return own != 0 and not (around[1] == own and around[3] == own and around[5] == own and around[7] == own)


@loop_helper
def _distinct_others(around, partners, n):
    """Append the distinct zones of ``around`` other than 0 and the pixel's own
    to ``partners[n:]``; returns the new length."""
    own = around[4]
    start = n
    for k in range(9):
        other = around[k]
        if other == 0 or other == own:
            continue
        repeated = False
        for j in range(start, n):
            if partners[j] == other:
                repeated = True
                break
        if not repeated:
            partners[n] = other
            n += 1
    return n


@loop_helper
def _count(around, partners, total):
    """Contacts of a pixel whose 3x3 zones are ``around``: returns n, the
    count (``around[4]``, ``partners[i]``) growing by one for i < n (its
    contour size in ``total`` is counted here).

    A contour pixel counts once in its zone's contour size and once for every
    distinct other zone in its 3x3 neighbourhood.
    """
    if not _is_contour(around):
        return 0
    total[around[4]] += 1
    return _distinct_others(around, partners, 0)


@loop_helper
def _recount(around, here, into, partners, signs, total):
    """Changes of the contact counts of a pixel whose 3x3 zones are ``around``
    for the fusion of zone ``here`` into ``into``: returns ``(own, n)``, the
    count (own, ``partners[i]``) changing by ``signs[i]`` for i < n (contour
    sizes in ``total`` are updated here). ``around`` is rewritten to after.

    The counts of ``here`` itself are left as they are, since a fused zone is
    never queried again.
    """
    own = around[4]
    was_contour = _is_contour(around)
    n = 0
    if own == here:
        # The pixel moves to `into` with its contour status and contacts as after.
        for k in range(9):
            if around[k] == here:
                around[k] = into
        if not _is_contour(around):
            return own, 0
        own = into
        total[own] += 1
        n = _distinct_others(around, partners, 0)
        for i in range(n):
            signs[i] = 1
    elif own == into:
        if not was_contour:
            return own, 0
        had_here = False
        for k in range(9):
            if around[k] == here:
                had_here = True
                around[k] = into
        if not had_here:
            return own, 0
        partners[0], signs[0] = here, -1
        n = 1
        if not _is_contour(around):
            # No longer a contour pixel: it leaves every count of `into`.
            total[own] -= 1
            n = _distinct_others(around, partners, 1)
            for i in range(1, n):
                signs[i] = -1
    elif was_contour:
        had_here, had_into = False, False
        for k in range(9):
            if around[k] == here:
                had_here = True
            elif around[k] == into:
                had_into = True
        if not had_here:
            return own, 0
        partners[0], signs[0] = here, -1
        n = 1
        if not had_into:
            partners[1], signs[1] = into, 1
            n = 2
    return own, n


@loop_helper
def _same_labels_around(labels, pixel, width):
    """Whether all 8 neighbours of ``pixel`` carry its own label."""
    raw = labels[pixel]
    up, down = pixel - width, pixel + width
    return (
        labels[up - 1] == raw and labels[up] == raw and labels[up + 1] == raw
        and labels[pixel - 1] == raw and labels[pixel + 1] == raw
        and labels[down - 1] == raw and labels[down] == raw and labels[down + 1] == raw
    )  # fmt: skip


@loop_helper
def _is_inner(labels, parent, pixel, width, own):
    """Whether all 8 neighbours of ``pixel`` are in zone ``own``."""
    if _same_labels_around(labels, pixel, width):
        return _zone_of(labels[pixel], parent) == own
    up, down = pixel - width, pixel + width
    return (
        _zone_of(labels[pixel], parent) == own
        and _zone_of(labels[up - 1], parent) == own and _zone_of(labels[up], parent) == own
        and _zone_of(labels[up + 1], parent) == own and _zone_of(labels[pixel - 1], parent) == own
        and _zone_of(labels[pixel + 1], parent) == own and _zone_of(labels[down - 1], parent) == own
        and _zone_of(labels[down], parent) == own and _zone_of(labels[down + 1], parent) == own
    )  # fmt: skip


@njit(cache=True)
def _compact_labels(labels, alive):
    """Renumber the live zones 1..n - 1 in id order, in place.

    Returns ``(original, compact_of, n)``: ``original[k - 1]`` is the id of
    compact zone k, ``compact_of`` the inverse (0 for dead ids).
    """
    original = np.flatnonzero(alive).astype(np.int32)
    n = len(original) + 1
    compact_of = np.zeros(len(alive), np.int32)
    for k in range(len(original)):
        compact_of[original[k]] = k + 1
    for pixel in range(labels.size):
        labels[pixel] = compact_of[labels[pixel]]
    return original, compact_of, n


@njit(cache=True)
def _restore_labels(labels, parent, original):
    """Undo :func:`_compact_labels`, each label replaced by its current zone."""
    lookup = np.zeros(len(parent), np.int32)
    for label in range(1, len(parent)):
        lookup[label] = original[_zone_of(label, parent) - 1]
    relabel(labels, lookup)


@njit(cache=True, nogil=True)
def count_contacts(labels, width, n, start, stop):
    """Contact counts of the pixels ``start..stop - 1`` of a compact, padded,
    flattened label image (``n`` zones; every label its own zone).

    Returns ``(pixels, following, head, tail, used, keys, counts, meta, slots,
    total)``: the border candidates of each zone as linked lists over the
    candidate arrays, in raster order (``pixels[k]`` a pixel, ``following[k]``
    the next candidate or -1, ``head`` / ``tail`` per zone, ``used`` entries
    in use); the contact counts (per-zone slots, the shared table, ``total`` =
    contour sizes). The pixels outside the range are only read, so bands of
    rows can be counted at the same time (:func:`start_tracking`).
    """
    pixels = np.empty(1024, np.int32)
    following = np.empty(1024, np.int32)
    head = _filled(n, -1, np.int32)
    tail = _filled(n, -1, np.int32)
    keys, counts, meta = _new_table(16)
    slots = _filled(n * _SLOTS, -1, np.int64)
    for zone in range(n):
        slots[zone * _SLOTS] = 0
    total = np.zeros(n, np.int64)
    around = np.empty(9, np.int32)
    partners = np.empty(9, np.int32)
    # Counts are gathered in a small cache of pairs first: a boundary repeats
    # its pair on every pixel, while the zones' counts are far apart in memory.
    pending_keys = _filled(1 << _PENDING_BITS, _EMPTY, np.int64)
    pending_counts = np.zeros(1 << _PENDING_BITS, np.int64)
    base = np.int64(n)
    n_candidates = 0
    for pixel in range(start, stop):
        zone = labels[pixel]
        # No fusion yet: every label is its own zone.
        if zone == 0 or _same_labels_around(labels, pixel, width):
            continue
        if n_candidates == len(pixels):
            pixels = _grown(pixels, 2 * n_candidates, 0)
            following = _grown(following, 2 * n_candidates, 0)
        pixels[n_candidates] = pixel
        following[n_candidates] = -1
        if tail[zone] == -1:
            head[zone] = n_candidates
        else:
            following[tail[zone]] = n_candidates
        tail[zone] = n_candidates
        n_candidates += 1
        _raw_neighbourhood(labels, pixel, width, around)
        own = around[4]
        for i in range(_count(around, partners, total)):
            key = own * base + partners[i]
            index = np.int64((np.uint64(key) * _GOLDEN) >> np.uint64(64 - _PENDING_BITS))
            if pending_keys[index] == key:
                pending_counts[index] += 1
                continue
            if pending_keys[index] != _EMPTY:
                if 2 * (meta[0] + 1) > len(keys):
                    keys, counts = _table_reserve(keys, counts, meta, 1)
                evicted = pending_keys[index]
                _contact_add(slots, keys, counts, meta, base, evicted // base, evicted % base, pending_counts[index])
            pending_keys[index] = key
            pending_counts[index] = 1
    keys, counts = _table_reserve(keys, counts, meta, len(pending_keys))
    for index in range(len(pending_keys)):
        if pending_keys[index] != _EMPTY:
            key = pending_keys[index]
            _contact_add(slots, keys, counts, meta, base, key // base, key % base, pending_counts[index])
    return pixels, following, head, tail, n_candidates, keys, counts, meta, slots, total


@njit(cache=True)
def join_counts(first, second):
    """The counts of two bands of rows (:func:`count_contacts`), ``second``
    below ``first``, as one: ``first``'s arrays, extended."""
    pixels, following, head, tail, used, keys, counts, meta, slots, total = first
    pixels_b, following_b, head_b, tail_b, used_b, keys_b, counts_b, meta_b, slots_b, total_b = second
    n = len(head)
    if used + used_b > len(pixels):
        pixels = _grown(pixels, used + used_b, 0)
        following = _grown(following, used + used_b, 0)
    for k in range(used_b):
        pixels[used + k] = pixels_b[k]
        following[used + k] = following_b[k] + used if following_b[k] != -1 else -1
    for zone in range(n):
        if head_b[zone] == -1:
            continue
        if tail[zone] == -1:
            head[zone] = head_b[zone] + used
        else:
            following[tail[zone]] = head_b[zone] + used
        tail[zone] = tail_b[zone] + used
        total[zone] += total_b[zone]
    base = np.int64(n)
    # Room for every count of the second band, wherever each one lands.
    more = meta_b[0]
    for k in range(len(slots_b)):
        if k % _SLOTS != 0 and slots_b[k] >= 0:
            more += 1
    keys, counts = _table_reserve(keys, counts, meta, more)
    for zone in range(n):
        for k in range(zone * _SLOTS + 1, zone * _SLOTS + _SLOTS):
            if slots_b[k] >= 0:
                _contact_add(slots, keys, counts, meta, base, zone, slots_b[k] >> 32, slots_b[k] & _COUNT)
    for slot in range(len(keys_b)):
        if keys_b[slot] != _EMPTY and counts_b[slot] != 0:
            _contact_add(slots, keys, counts, meta, base, keys_b[slot] // base, keys_b[slot] % base, counts_b[slot])
    return pixels, following, head, tail, used + used_b, keys, counts, meta, slots, total


@loop_helper
def _bits(size):
    """log2 of a power of two."""
    bits = 0
    while (1 << bits) < size:
        bits += 1
    return bits


@loop_helper
def _prefetch_rows(labels, pixel, width):
    """Start loading the three rows of ``pixel``'s 3x3 neighbourhood."""
    _prefetch(labels, pixel - width - 1)
    _prefetch(labels, pixel - 1)
    _prefetch(labels, pixel + width - 1)


@loop_helper
def _mark(pixel, labels, seen, bits, affected, used, n_affected):
    """Append ``pixel`` to ``affected`` unless it has no zone (no counts) or
    is already in ``seen`` (a hash set of this fusion's pixels)."""
    if labels[pixel] == 0:
        return n_affected
    slot = _probe(seen, np.int64(pixel), bits)
    if seen[slot] == pixel:
        return n_affected
    seen[slot] = pixel
    affected[n_affected] = pixel
    used[n_affected] = slot
    return n_affected + 1


# Size of the cache of pending counts when counting from scratch (count_contacts).
_PENDING_BITS = 14

# Border pixels of a fusion are loaded this many candidates ahead (_prefetch).
_AHEAD = 6


@njit(cache=True)
def _contacts_fuse(here, into, labels, width, state, scratch):
    """Fuse compact zone ``here`` into ``into`` in the contact state; returns
    the state (its table may have grown) and the scratch arrays, grown if needed.

    Only the pixels around ``here`` are visited: its border candidates (those
    now inside are dropped for good) and their 8-neighbours, each once. The
    scratch arrays are empty between fusions:

    * ``walk`` / ``walk_pixels``: the candidates and their pixels, gathered
      first so that their rows of the label image can be loaded a few
      candidates ahead;
    * ``seen``: a small hash set of the pixels met (``affected`` lists them,
      ``used`` their slots, to clear them): a flag per pixel would cost a cold
      cache line for each row a fusion touches;
    * ``change_keys`` / ``change_counts``: the count changes summed per pair
      (``changed`` lists their slots), so that each pair's count, in a table
      far larger than the cache, is updated once per fusion.
    """
    parent, pixels, following, head, tail, keys, counts, meta, slots, total = state
    walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed = scratch
    base = np.int64(len(parent))
    around = np.empty(9, np.int32)
    partners = np.empty(9, np.int32)
    signs = np.empty(9, np.int64)
    n_walk = 0
    candidate = head[here]
    while candidate != -1:
        if n_walk == len(walk):
            walk = _grown(walk, 2 * n_walk, 0)
            walk_pixels = _grown(walk_pixels, 2 * n_walk, 0)
        walk[n_walk] = candidate
        walk_pixels[n_walk] = pixels[candidate]
        n_walk += 1
        candidate = following[candidate]
    if 4 * 9 * n_walk > len(seen):
        size = len(seen)
        while 4 * 9 * n_walk > size:
            size *= 2
        seen = _filled(size, _EMPTY, np.int64)
        affected = np.empty(size // 4, np.int32)
        used = np.empty(size // 4, np.int64)
    seen_bits = _bits(len(seen))
    for i in range(min(n_walk, _AHEAD)):
        _prefetch_rows(labels, walk_pixels[i], width)
    n_affected = 0
    kept_head, kept_tail = -1, -1
    for i in range(n_walk):
        if i + _AHEAD < n_walk:
            _prefetch_rows(labels, walk_pixels[i + _AHEAD], width)
        candidate = walk[i]
        pixel = walk_pixels[i]
        if _is_inner(labels, parent, pixel, width, here):
            continue
        following[candidate] = -1
        if kept_tail == -1:
            kept_head = candidate
        else:
            following[kept_tail] = candidate
        kept_tail = candidate
        up, down = pixel - width, pixel + width
        n_affected = _mark(up - 1, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(up, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(up + 1, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(pixel - 1, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(pixel, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(pixel + 1, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(down - 1, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(down, labels, seen, seen_bits, affected, used, n_affected)
        n_affected = _mark(down + 1, labels, seen, seen_bits, affected, used, n_affected)
    # At most 9 count changes per affected pixel; the table stays at most half full.
    if 2 * 9 * n_affected > len(change_keys):
        size = len(change_keys)
        while 2 * 9 * n_affected > size:
            size *= 2
        change_keys = _filled(size, _EMPTY, np.int64)
        change_counts = np.zeros(size, np.int64)
        changed = np.empty(size // 2, np.int64)
    change_bits = _bits(len(change_keys))
    n_changed = 0
    for k in range(n_affected):
        _neighbourhood(labels, parent, affected[k], width, around)
        own, n = _recount(around, here, into, partners, signs, total)
        for i in range(n):
            key = own * base + partners[i]
            slot = _probe(change_keys, key, change_bits)
            if change_keys[slot] == _EMPTY:
                change_keys[slot] = key
                change_counts[slot] = 0
                changed[n_changed] = slot
                n_changed += 1
            change_counts[slot] += signs[i]
        seen[used[k]] = _EMPTY
    keys, counts = _table_reserve(keys, counts, meta, n_changed)
    for k in range(n_changed):
        slot = changed[k]
        if change_counts[slot] != 0:
            key = change_keys[slot]
            _contact_add(slots, keys, counts, meta, base, key // base, key % base, change_counts[slot])
        change_keys[slot] = _EMPTY
    parent[here] = into
    if kept_head != -1:
        if tail[into] == -1:
            head[into] = kept_head
        else:
            following[tail[into]] = kept_head
        tail[into] = kept_tail
    head[here] = tail[here] = -1
    state = (parent, pixels, following, head, tail, keys, counts, meta, slots, total)
    return state, (walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed)


def start_tracking(labels, width, alive, *, bands=None):
    """Compact the labels of a padded, flattened label image in place
    (:func:`_compact_labels`) and count their contacts: ``(original,
    compact_of, state)`` for the compiled steps that track contacts.

    The state is ``(parent, pixels, following, head, tail, keys, counts,
    meta, slots, total)``: union-find parents of the labels, then the arrays
    of :func:`count_contacts`. Large images are counted in ``bands`` of rows
    at the same time (default: one per CPU, at most 4), each on a thread.
    """
    original, compact_of, n = _compact_labels(labels, alive)
    if bands is None:
        bands = min(_usable_cpus(), 4) if labels.size >= _BAND_PIXELS else 1
    rows = labels.size // width
    edges = [row * width for row in np.linspace(0, rows, bands + 1).astype(int)]
    if bands == 1:
        counted = [count_contacts(labels, width, n, 0, labels.size)]
    else:
        with ThreadPoolExecutor(bands) as pool:
            counted = list(pool.map(lambda k: count_contacts(labels, width, n, edges[k], edges[k + 1]), range(bands)))
    joined = counted[0]
    for band in counted[1:]:
        joined = join_counts(joined, band)
    pixels, following, head, tail, _, keys, counts, meta, slots, total = joined
    parent = np.arange(n, dtype=np.int32)
    return original, compact_of, (parent, pixels, following, head, tail, keys, counts, meta, slots, total)


# Smaller images are counted on one thread: starting threads costs more.
_BAND_PIXELS = 1 << 20


def _usable_cpus() -> int:
    """CPUs this process may run on (a container or taskset may allow fewer than the machine has)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


@njit(cache=True)
def _new_scratch():
    """Empty scratch arrays of :func:`_contacts_fuse`."""
    return (
        np.empty(1024, np.int32),
        np.empty(1024, np.int32),
        _filled(4096, _EMPTY, np.int64),
        np.empty(1024, np.int32),
        np.empty(1024, np.int64),
        _filled(4096, _EMPTY, np.int64),
        np.zeros(4096, np.int64),
        np.empty(2048, np.int64),
    )


@loop_helper
def _contact_percent(state, zone, other):
    """Integer percentage of compact ``zone``'s contour pixels having ``other`` in their 3x3."""
    parent, pixels, following, head, tail, keys, counts, meta, slots, total = state
    if total[zone] == 0:
        return 0
    return contact_get(slots, keys, counts, meta, np.int64(len(parent)), zone, other) * 100 // total[zone]


@njit(cache=True)
def merge_ripples(order, ripples, labels, width, size, alive, graph, tracking):
    """Ripple merging (``removeRiplesv3``) on a padded flat label image.

    ``order`` is the initial work list (decreasing value, smaller size first,
    then id); ``labels`` is the flattened label image, padded by at least 2
    pixels of 0 and ``width`` wide, relabelled in place.

    Contacts are tracked on compact zone ids (the per-zone arrays stay in
    cache) as union-find sets of the labels, relabelled once at the end;
    ``tracking`` is :func:`start_tracking` of the labels (which compacts them).
    """
    records, nodes = graph
    original, compact_of, state = tracking
    scratch = _new_scratch()
    queue = np.empty(max(2 * len(order), 16), np.int32)
    for i in range(len(order)):
        queue[i] = order[i]
    start, end = 0, len(order)
    while start < end:
        zone = queue[start]
        start += 1
        if not alive[zone]:
            continue
        zone_value = records[zone, VALUE]
        here = compact_of[zone]
        best, best_gap = -1, 0
        node = records[zone, HEAD]
        while node != -1:
            other = nodes[node, NEIGHBOUR]
            if (
                nodes[node | 1, ATTRIBUTE] == 0 and state[9][here] > 0
                and _contact_percent(state, here, compact_of[other]) >= ripples
            ):  # fmt: skip
                gap = abs(records[other, VALUE] - zone_value)
                if best == -1 or gap < best_gap:
                    best, best_gap = other, gap
            node = nodes[node, NEXT]
        if best == -1:
            continue
        # Queue the neighbours again.
        if end + records[zone, DEGREE] > len(queue):
            queue = _grown(queue, 2 * (end + records[zone, DEGREE]), 0)
        node = records[zone, HEAD]
        while node != -1:
            queue[end] = nodes[node, NEIGHBOUR]
            end += 1
            node = nodes[node, NEXT]
        state, scratch = _contacts_fuse(np.int64(here), np.int64(compact_of[best]), labels, width, state, scratch)
        alive[zone] = False
        size[best] += size[zone]
        fuse_edges(np.int64(zone), np.int64(best), graph)
    _restore_labels(labels, state[0], original)


@loop_helper
def _contact_sum(state, zone, here, compact_of, graph):
    """Sum of contact percentages of ``zone`` (compact id ``here``) over its neighbours."""
    records, nodes = graph
    result = 0
    node = records[zone, HEAD]
    while node != -1:
        result += _contact_percent(state, here, compact_of[nodes[node, NEIGHBOUR]])
        node = nodes[node, NEXT]
    return result


@njit(cache=True)
def remove_doors(doors, labels, width, size, alive, graph, tracking):
    """Door removal (``removeDoors``) on a padded flat label image, relabelled in place.

    Zones in id order: one whose contact sum exceeds ``doors`` is fused into
    the last neighbour whose sum is below ``doors``, else into its first
    neighbour; the receiver's sum is then recomputed. Sums are taken once at
    the start otherwise. ``tracking`` as for :func:`merge_ripples`.
    """
    records, nodes = graph
    original, compact_of, state = tracking
    scratch = _new_scratch()
    sums = np.zeros(len(records), np.int64)
    for k in range(len(original)):
        zone = original[k]
        sums[zone] = _contact_sum(state, np.int64(zone), np.int64(k + 1), compact_of, graph)
    for k in range(len(original)):
        zone = original[k]
        if not alive[zone] or sums[zone] <= doors or records[zone, DEGREE] == 0:
            continue
        node = records[zone, HEAD]
        target = nodes[node, NEIGHBOUR]
        while node != -1:
            if sums[nodes[node, NEIGHBOUR]] < doors:
                target = nodes[node, NEIGHBOUR]
            node = nodes[node, NEXT]
        state, scratch = _contacts_fuse(np.int64(k + 1), np.int64(compact_of[target]), labels, width, state, scratch)
        alive[zone] = False
        size[target] += size[zone]
        fuse_edges(np.int64(zone), np.int64(target), graph)
        sums[target] = _contact_sum(state, np.int64(target), np.int64(compact_of[target]), compact_of, graph)
    _restore_labels(labels, state[0], original)


@njit(cache=True)
def contact_table(labels, width, alive):
    """Every contact count of a padded flat label image, as ``(zone, other,
    count)`` rows in original ids (other = 0: the zone's contour size)."""
    work = labels.copy()
    original, compact_of, n = _compact_labels(work, alive)
    pixels, following, head, tail, used, keys, counts, meta, slots, total = count_contacts(work, width, n, 0, work.size)
    rows = 0
    for zone in range(1, n):
        if total[zone] > 0:
            rows += 1
        for k in range(zone * _SLOTS + 1, zone * _SLOTS + _SLOTS):
            if slots[k] >= 0:
                rows += 1
    for slot in range(len(keys)):
        if keys[slot] != _EMPTY and counts[slot] != 0:
            rows += 1
    out = np.empty((rows, 3), np.int64)
    row = 0
    for zone in range(1, n):
        if total[zone] > 0:
            out[row, 0], out[row, 1], out[row, 2] = original[zone - 1], 0, total[zone]
            row += 1
        for k in range(zone * _SLOTS + 1, zone * _SLOTS + _SLOTS):
            if slots[k] >= 0:
                out[row, 0], out[row, 1] = original[zone - 1], original[(slots[k] >> 32) - 1]
                out[row, 2] = slots[k] & _COUNT
                row += 1
    for slot in range(len(keys)):
        if keys[slot] != _EMPTY and counts[slot] != 0:
            out[row, 0] = original[keys[slot] // n - 1]
            out[row, 1] = original[keys[slot] % n - 1]
            out[row, 2] = counts[slot]
            row += 1
    return out


@njit(cache=True)
def first_pixels(labels, count):
    """Flat index of the first pixel (raster order) of each label 1..count - 1, -1 if absent."""
    first = _filled(count, -1, np.int64)
    flat = labels.ravel()
    for i in range(len(flat)):
        if first[flat[i]] == -1:
            first[flat[i]] = i
    return first


@njit(cache=True)
def resolve_parents(parent, alive):
    """Follow fusion chains: ``parent[z]`` becomes the live zone z ended in (0 if deleted)."""
    for zone in range(1, len(parent)):
        if alive[zone]:
            parent[zone] = zone
    for zone in range(1, len(parent)):
        root = zone
        while root != 0 and not alive[root]:
            root = parent[root]
        walk = zone
        while walk != root and walk != 0 and not alive[walk]:
            following = parent[walk]
            parent[walk] = root
            walk = following
    parent[0] = 0


@njit(cache=True)
def relabel(labels, lookup):
    """``labels[i] = lookup[labels[i]]`` in place."""
    flat = labels.ravel()
    for i in range(len(flat)):
        flat[i] = lookup[flat[i]]
