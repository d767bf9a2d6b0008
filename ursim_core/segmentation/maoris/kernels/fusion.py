"""MAORIS ripple merging and door removal, tracking contact counts across fusions (numba).

A fusion visits the pixels around the absorbed zone once and applies only the
changes of the counts (:func:`_contacts_fuse`), so the two steps that read
contact percentages while they fuse (:func:`merge_ripples`, :func:`remove_doors`)
never count from scratch.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.adjacency import ATTRIBUTE, DEGREE, HEAD, NEIGHBOUR, NEXT, VALUE, fuse_edges
from ursim_core.segmentation.maoris.kernels.contact_table import (
    _EMPTY,
    _contact_add,
    _probe,
    _table_reserve,
    contact_get,
)
from ursim_core.segmentation.maoris.kernels.contacts import (
    _is_inner,
    _neighbourhood,
    _recount,
    _restore_labels,
)
from ursim_core.segmentation.maoris.kernels.helpers import _bits, _filled, _grown, _prefetch, inner_kernel, loop_helper


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


# Border pixels of a fusion are loaded this many candidates ahead (_prefetch).
_AHEAD = 6


@inner_kernel
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
    n_changed = np.int64(0)
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


@inner_kernel
def _new_scratch():
    """Empty scratch arrays of :func:`_contacts_fuse`."""
    return (
        np.empty(1024, np.int32),
        np.empty(1024, np.int32),
        _filled(np.int64(4096), _EMPTY, np.int64),
        np.empty(1024, np.int32),
        np.empty(1024, np.int64),
        _filled(np.int64(4096), _EMPTY, np.int64),
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
