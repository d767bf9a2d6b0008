"""Compiled kernels of the MAORIS zone graph (numba).

A large map starts with millions of flat zones, almost all of them a few
pixels; the first two graph steps (small-zone removal, then ripple merging)
visit them one by one in an order that matters, so they cannot be
vectorised. These kernels run them on a compact array form of the graph:

* every zone keeps its neighbours in a doubly linked list of *nodes*, in
  insertion order (the order the C++ boost ``listS`` graph iterates in); a
  node (a -> b) has a *twin* (b -> a), and both carry the edge attributes
  (minimum, -1 for none, and unbreakability);
* fusing a zone frees its nodes before it allocates new ones, so the pool
  never grows beyond the initial two nodes per edge;
* the ripple step keeps the contact counts up to date: a fusion subtracts
  the contributions of the pixels around the absorbed zone, merges it, and
  adds them back. Zones are union-find sets of the labels (the image is
  relabelled once, at the end), each zone keeps a list of its pixels that may
  still be on its border, and its contact partners sit in a few slots of its
  own, with a shared hash table for zones that have more.

:class:`ursim_core.segmentation.maoris.ZoneGraph` owns the arrays; the
functions here only mutate them. Semantics are those documented on
``remove_small_zones``, ``merge_ripples`` and ``ZoneGraph.fuse``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

NO_MINIMUM = -1


@njit(cache=True)
def build_adjacency(zones, count):
    """Linked neighbour lists of the 4-adjacency of a zone image (0 = no zone).

    Edges are inserted in the raster order of their first contact: each pixel
    is compared with its left, then its upper neighbour.
    """
    rows, cols = zones.shape
    capacity = 16
    head = _filled(count, -1, np.int32)
    tail = _filled(count, -1, np.int32)
    degree = np.zeros(count, np.int32)
    neighbour = np.empty(capacity, np.int32)
    next_node = _filled(capacity, -1, np.int32)
    previous_node = _filled(capacity, -1, np.int32)
    twin = np.empty(capacity, np.int32)
    n_nodes = 0
    # The partner each zone met last: long boundaries repeat the same pair.
    last_partner = np.zeros(count, np.int32)
    for row in range(rows):
        last_left_a, last_left_b = -1, -1
        for col in range(cols):
            here = zones[row, col]
            if here == 0:
                continue
            for kind in range(2):
                other = zones[row, col - 1] if kind == 0 else zones[row - 1, col]
                if (kind == 0 and col == 0) or (kind == 1 and row == 0) or other == 0 or other == here:
                    continue
                a, b = min(here, other), max(here, other)
                if kind == 0:
                    # A run of contacts between the same two zones along a row.
                    if a == last_left_a and b == last_left_b:
                        continue
                    last_left_a, last_left_b = a, b
                elif row > 0 and col > 0 and zones[row, col - 1] == here and zones[row - 1, col - 1] == other:
                    continue  # same pair as the pixel to the left
                if last_partner[a] == b or last_partner[b] == a:
                    continue
                last_partner[a], last_partner[b] = b, a
                if _find(a, b, head, degree, neighbour, next_node, twin) != -1:
                    continue
                if n_nodes + 2 > capacity:
                    capacity *= 2
                    neighbour = _grown(neighbour, capacity, 0)
                    next_node = _grown(next_node, capacity, -1)
                    previous_node = _grown(previous_node, capacity, -1)
                    twin = _grown(twin, capacity, 0)
                _append(a, n_nodes, b, head, tail, degree, neighbour, next_node, previous_node)
                _append(b, n_nodes + 1, a, head, tail, degree, neighbour, next_node, previous_node)
                twin[n_nodes], twin[n_nodes + 1] = n_nodes + 1, n_nodes
                n_nodes += 2
    size = max(n_nodes, 2)
    neighbour, next_node, previous_node, twin = (
        neighbour[:size].copy(), next_node[:size].copy(), previous_node[:size].copy(), twin[:size].copy()
    )
    minimum = _filled(size, NO_MINIMUM, np.int32)
    unbreakable = np.zeros(size, np.bool_)
    free = np.empty(size, np.int32)
    return head, tail, degree, neighbour, next_node, previous_node, twin, minimum, unbreakable, free


@njit(cache=True)
def _filled(size, fill, dtype):
    # np.full and slice assignments cost seconds of compilation each; loops do not.
    array = np.empty(size, dtype)
    for i in range(size):
        array[i] = fill
    return array


@njit(cache=True)
def adjacency_from_entries(count, zone, other, minimum, unbreakable):
    """Linked neighbour lists from (zone, neighbour, minimum, unbreakable)
    entries, each zone's in list order: the inverse of :func:`adjacency_entries`.
    Every edge must appear in both directions, with the same attributes."""
    size = max(len(zone), 2)
    head = _filled(count, -1, np.int32)
    tail = _filled(count, -1, np.int32)
    degree = np.zeros(count, np.int32)
    neighbour = np.empty(size, np.int32)
    next_node = _filled(size, -1, np.int32)
    previous_node = _filled(size, -1, np.int32)
    for node in range(len(zone)):
        _append(zone[node], node, other[node], head, tail, degree, neighbour, next_node, previous_node)
    # The twin of (a -> b) is (b -> a): match the entries' keys with the reversed ones.
    keys = zone.astype(np.int64) * count + other
    order = np.argsort(keys)
    found = np.searchsorted(keys[order], other.astype(np.int64) * count + zone)
    twin = np.empty(size, np.int32)
    for node in range(len(zone)):
        twin[node] = order[found[node]]
    edge_minimum = _filled(size, NO_MINIMUM, np.int32)
    edge_unbreakable = np.zeros(size, np.bool_)
    for node in range(len(zone)):
        edge_minimum[node] = minimum[node]
        edge_unbreakable[node] = unbreakable[node]
    free = np.empty(size, np.int32)
    return head, tail, degree, neighbour, next_node, previous_node, twin, edge_minimum, edge_unbreakable, free


@njit(cache=True)
def _grown(array, capacity, fill):
    grown = np.empty(capacity, array.dtype)
    for i in range(capacity):
        grown[i] = array[i] if i < len(array) else fill
    return grown


@njit(cache=True)
def adjacency_entries(alive, graph):
    """Every (zone, neighbour, node, twin, minimum, unbreakable) of the live
    zones, zones in id order and each zone's neighbours in list order."""
    head, degree, neighbour, next_node, twin, minimum, unbreakable = (
        graph[0], graph[2], graph[3], graph[4], graph[6], graph[7], graph[8]
    )
    total = 0
    for zone in range(len(alive)):
        if alive[zone]:
            total += degree[zone]
    out = np.empty((total, 6), np.int64)
    k = 0
    for zone in range(len(alive)):
        if not alive[zone]:
            continue
        node = head[zone]
        while node != -1:
            out[k, 0] = zone
            out[k, 1] = neighbour[node]
            out[k, 2] = node
            out[k, 3] = twin[node]
            out[k, 4] = minimum[node]
            out[k, 5] = unbreakable[node]
            k += 1
            node = next_node[node]
    return out


@njit(cache=True, inline="always")
def _append(zone, node, other, head, tail, degree, neighbour, next_node, previous_node):
    neighbour[node] = other
    next_node[node] = -1
    previous_node[node] = tail[zone]
    if tail[zone] == -1:
        head[zone] = node
    else:
        next_node[tail[zone]] = node
    tail[zone] = node
    degree[zone] += 1


@njit(cache=True, inline="always")
def _unlink(zone, node, head, tail, degree, next_node, previous_node):
    before, after = previous_node[node], next_node[node]
    if before == -1:
        head[zone] = after
    else:
        next_node[before] = after
    if after == -1:
        tail[zone] = before
    else:
        previous_node[after] = before
    degree[zone] -= 1


@njit(cache=True)
def _find(a, b, head, degree, neighbour, next_node, twin):
    """Node (a -> b), or -1; walks the shorter of the two lists."""
    if degree[a] <= degree[b]:
        node = head[a]
        while node != -1:
            if neighbour[node] == b:
                return node
            node = next_node[node]
        return -1
    node = head[b]
    while node != -1:
        if neighbour[node] == a:
            return twin[node]
        node = next_node[node]
    return -1


@njit(cache=True)
def fuse_edges(zone, into, value, graph, free_top):
    """Transfer the edges of ``zone`` to ``into`` (``ZoneGraph.fuse``, edges only).

    ``free_top`` is a one-element array: the size of the free-node stack.
    """
    head, tail, degree, neighbour, next_node, previous_node, twin, minimum, unbreakable, free = graph
    zone_value = value[zone]
    node = head[zone]
    while node != -1:
        following = next_node[node]
        other = neighbour[node]
        old_minimum = minimum[node]
        old_unbreakable = unbreakable[node]
        back = twin[node]
        _unlink(other, back, head, tail, degree, next_node, previous_node)
        free[free_top[0]] = back
        free[free_top[0] + 1] = node
        free_top[0] += 2
        if other != into:
            existing = _find(into, other, head, degree, neighbour, next_node, twin)
            if existing == -1:
                if old_minimum == NO_MINIMUM or zone_value < old_minimum:
                    new_minimum = zone_value
                else:
                    new_minimum = old_minimum
                forward = free[free_top[0] - 1]
                backward = free[free_top[0] - 2]
                free_top[0] -= 2
                _append(into, forward, other, head, tail, degree, neighbour, next_node, previous_node)
                _append(other, backward, into, head, tail, degree, neighbour, next_node, previous_node)
                twin[forward] = backward
                twin[backward] = forward
                minimum[forward] = minimum[backward] = new_minimum
                unbreakable[forward] = unbreakable[backward] = old_unbreakable
            elif old_unbreakable:
                unbreakable[existing] = True
                unbreakable[twin[existing]] = True
        node = following
    head[zone] = tail[zone] = -1
    degree[zone] = 0


@njit(cache=True)
def remove_small_zones(min_size, value, size, alive, parent, graph, free_top):
    """One pass in id order: fuse each zone below ``min_size`` px into its
    closest-valued neighbour (first on ties), delete it when it has none.

    ``parent[z]`` records where z went (0 = deleted); sizes are updated.
    """
    head, degree, neighbour, next_node = graph[0], graph[2], graph[3], graph[4]
    for zone in range(1, len(value)):
        if not alive[zone] or size[zone] >= min_size:
            continue
        alive[zone] = False
        if degree[zone] == 0:
            parent[zone] = 0
            continue
        zone_value = value[zone]
        closest, closest_gap = -1, 1 << 30
        node = head[zone]
        while node != -1:
            gap = abs(value[neighbour[node]] - zone_value)
            if gap < closest_gap:
                closest, closest_gap = neighbour[node], gap
            node = next_node[node]
        parent[zone] = closest
        size[closest] += size[zone]
        fuse_edges(zone, closest, value, graph, free_top)


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


@njit(cache=True, inline="always")
def _probe(keys, key, bits):
    mask = len(keys) - 1
    slot = np.int64((np.uint64(key) * _GOLDEN) >> np.uint64(64 - bits))
    while keys[slot] != _EMPTY and keys[slot] != key:
        slot = (slot + 1) & mask
    return slot


@njit(cache=True, inline="always")
def _slot(keys, meta, key):
    memo = 2 + (key & (_MEMO - 1))
    if meta[memo] == key:
        return meta[memo + _MEMO]
    slot = _probe(keys, key, meta[1])
    if keys[slot] == key:
        meta[memo] = key
        meta[memo + _MEMO] = slot
    return slot


@njit(cache=True, inline="always")
def table_get(keys, counts, meta, key):
    """Count under ``key`` (0 when absent)."""
    slot = _slot(keys, meta, key)
    return counts[slot] if keys[slot] == key else 0


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def _zone_of(label, parent):
    """Current zone of an original label (union-find root, with path halving)."""
    while parent[label] != label:
        parent[label] = parent[parent[label]]
        label = parent[label]
    return label


@njit(cache=True, inline="always")
def _neighbourhood(labels, parent, pixel, width, around):
    """Write the zones of a pixel's 3x3 neighbourhood, row by row, into
    ``around`` (index 4: the pixel)."""
    k = 0
    for d_row in (-width, 0, width):
        for d_col in (-1, 0, 1):
            around[k] = _zone_of(labels[pixel + d_row + d_col], parent)
            k += 1


@njit(cache=True, inline="always")
def _count(around, sign, slots, keys, counts, meta, total, base):
    """Add ``sign`` times the contact counts of a pixel whose 3x3 zones are ``around``.

    A contour pixel (a 4-neighbour in another zone) counts once in its zone's
    contour size and once for every distinct other zone in its 3x3
    neighbourhood.
    """
    own = around[4]
    if own == 0 or (around[1] == own and around[3] == own and around[5] == own and around[7] == own):
        return
    total[own] += sign
    for k in range(9):
        other = around[k]
        if other == 0 or other == own:
            continue
        repeated = False
        for j in range(k):
            if around[j] == other:
                repeated = True
                break
        if not repeated:
            _contact_add(slots, keys, counts, meta, base, own, other, sign)


@njit(cache=True, inline="always")
def _is_inner(labels, parent, pixel, width, own):
    """Whether all 8 neighbours of ``pixel`` are in zone ``own``."""
    raw = labels[pixel]
    up, down = pixel - width, pixel + width
    if (
        labels[up - 1] == raw and labels[up] == raw and labels[up + 1] == raw
        and labels[pixel - 1] == raw and labels[pixel + 1] == raw
        and labels[down - 1] == raw and labels[down] == raw and labels[down + 1] == raw
    ):  # fmt: skip
        return _zone_of(raw, parent) == own
    for d_row in (-width, 0, width):
        for d_col in (-1, 0, 1):
            if _zone_of(labels[pixel + d_row + d_col], parent) != own:
                return False
    return True


@njit(cache=True)
def merge_ripples(order, ripples, labels, width, value, size, alive, graph, free_top):
    """Ripple merging (``removeRiplesv3``) on a padded flat label image.

    ``order`` is the initial work list (decreasing value, smaller size first,
    then id); ``labels`` is the flattened label image, padded by at least 2
    pixels of 0 and ``width`` wide, relabelled in place.

    A fusion only touches the pixels around the absorbed zone: zones are
    union-find sets of the labels (relabelled once, at the end), numbered
    compactly so that the per-zone arrays stay in cache, and each zone keeps
    a list of its pixels that may still be on its border (a pixel found with
    all 8 neighbours inside is dropped for good).
    """
    head, degree, neighbour, next_node, unbreakable = graph[0], graph[2], graph[3], graph[4], graph[8]
    # Compact ids: the live zones in id order are 1..n - 1.
    original = np.flatnonzero(alive).astype(np.int32)
    n = len(original) + 1
    compact_of = np.zeros(len(value), np.int32)
    for k in range(len(original)):
        compact_of[original[k]] = k + 1
    for pixel in range(labels.size):
        labels[pixel] = compact_of[labels[pixel]]
    base = np.int64(n)
    parent = np.arange(n).astype(np.int32)
    # Border candidates of each zone, as linked lists; and the contact counts
    # (the table is grown outside `_count`, so that it can be inlined).
    border_next = _filled(labels.size, -1, np.int32)
    border_head = _filled(n, -1, np.int32)
    border_tail = _filled(n, -1, np.int32)
    keys, counts, meta = _new_table(16)
    slots = _filled(n * _SLOTS, -1, np.int64)
    for zone in range(n):
        slots[zone * _SLOTS] = 0
    total = np.zeros(n, np.int64)
    around = np.empty(9, np.int32)
    for pixel in range(labels.size):
        zone = labels[pixel]
        if zone == 0 or _is_inner(labels, parent, pixel, width, zone):
            continue
        if border_tail[zone] == -1:
            border_head[zone] = pixel
        else:
            border_next[border_tail[zone]] = pixel
        border_tail[zone] = pixel
        if 2 * (meta[0] + 8) > len(keys):
            keys, counts = _table_reserve(keys, counts, meta, 8)
        _neighbourhood(labels, parent, pixel, width, around)
        _count(around, 1, slots, keys, counts, meta, total, base)

    queue = np.empty(max(2 * len(order), 16), np.int32)
    for i in range(len(order)):
        queue[i] = order[i]
    start, end = 0, len(order)
    stamp = np.zeros(labels.size, np.int32)
    stamp_id = 0
    affected = np.empty(1024, np.int32)
    while start < end:
        zone = queue[start]
        start += 1
        if not alive[zone]:
            continue
        zone_value = value[zone]
        here = compact_of[zone]
        contour = total[here]
        best, best_gap = -1, 0
        node = head[zone]
        while node != -1:
            other = neighbour[node]
            if not unbreakable[node] and contour > 0:
                percent = contact_get(slots, keys, counts, meta, base, here, compact_of[other]) * 100 // contour
                if percent >= ripples:
                    gap = abs(value[other] - zone_value)
                    if best == -1 or gap < best_gap:
                        best, best_gap = other, gap
            node = next_node[node]
        if best == -1:
            continue
        # Queue the neighbours again.
        if end + degree[zone] > len(queue):
            queue = _grown(queue, 2 * (end + degree[zone]), 0)
        node = head[zone]
        while node != -1:
            queue[end] = neighbour[node]
            end += 1
            node = next_node[node]
        # Pixels whose counts may change: the zone's border pixels and their
        # neighbours. Border candidates now inside are dropped from the list.
        into = compact_of[best]
        stamp_id += 1
        n_affected = 0
        kept_head, kept_tail = -1, -1
        pixel = border_head[here]
        while pixel != -1:
            following = border_next[pixel]
            if not _is_inner(labels, parent, pixel, width, here):
                border_next[pixel] = -1
                if kept_tail == -1:
                    kept_head = pixel
                else:
                    border_next[kept_tail] = pixel
                kept_tail = pixel
                for d_row in (-width, 0, width):
                    for d_col in (-1, 0, 1):
                        near = pixel + d_row + d_col
                        if stamp[near] != stamp_id:
                            stamp[near] = stamp_id
                            if n_affected == len(affected):
                                affected = _grown(affected, 2 * len(affected), 0)
                            affected[n_affected] = near
                            n_affected += 1
            pixel = following
        keys, counts = _table_reserve(keys, counts, meta, 8 * n_affected)
        for k in range(n_affected):
            _neighbourhood(labels, parent, affected[k], width, around)
            _count(around, -1, slots, keys, counts, meta, total, base)
        parent[here] = into
        for k in range(n_affected):
            _neighbourhood(labels, parent, affected[k], width, around)
            _count(around, 1, slots, keys, counts, meta, total, base)
        if kept_head != -1:
            if border_tail[into] == -1:
                border_head[into] = kept_head
            else:
                border_next[border_tail[into]] = kept_head
            border_tail[into] = kept_tail
        border_head[here] = border_tail[here] = -1

        alive[zone] = False
        size[best] += size[zone]
        fuse_edges(zone, best, value, graph, free_top)
    lookup = np.zeros(n, np.int32)
    for label in range(1, n):
        lookup[label] = original[_zone_of(label, parent) - 1]
    relabel(labels, lookup)


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
