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
    _contact_add_live,
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
# The smallest hash tables of a fusion (bits): small fusions use a prefix of the scratch tables.
_MIN_BITS = 8


@loop_helper
def _gather(head, following, pixels, here, walk, walk_pixels):
    """Copy the candidates of compact zone ``here`` and their pixels into ``walk`` /
    ``walk_pixels`` (as many as fit); returns how many there are."""
    n_walk = 0
    candidate = head[here]
    while candidate != -1:
        if n_walk < len(walk):
            walk[n_walk] = candidate
            walk_pixels[n_walk] = pixels[candidate]
        n_walk += 1
        candidate = following[candidate]
    return n_walk


@loop_helper
def _room_needed(n_walk, scratch, keys, meta):
    """Whether the scratch arrays or the contact table must grow before fusing a zone of
    ``n_walk`` candidates (:func:`_with_room`)."""
    walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed = scratch
    # At most 9 affected pixels per candidate, and 9 count changes per affected pixel.
    return (
        n_walk > len(walk) or 4 * 9 * n_walk > len(seen) or 2 * 81 * n_walk > len(change_keys)
        or 2 * (meta[0] + 81 * n_walk) > len(keys)
    )  # fmt: skip


@inner_kernel
def _with_room(n_walk, scratch, keys, counts, meta):
    """The scratch arrays and the contact table, grown for a fusion of ``n_walk`` candidates
    (seldom: the arrays only ever grow)."""
    walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed = scratch
    if n_walk > len(walk):
        walk = np.empty(2 * n_walk, np.int32)
        walk_pixels = np.empty(2 * n_walk, np.int32)
    if 4 * 9 * n_walk > len(seen):
        size = len(seen)
        while 4 * 9 * n_walk > size:
            size *= 2
        seen = _filled(size, _EMPTY, np.int64)
        affected = np.empty(size // 4, np.int32)
        used = np.empty(size // 4, np.int64)
    if 2 * 81 * n_walk > len(change_keys):
        size = len(change_keys)
        while 2 * 81 * n_walk > size:
            size *= 2
        change_keys = _filled(size, _EMPTY, np.int64)
        change_counts = np.zeros(size, np.int64)
        changed = np.empty(size // 2, np.int64)
    keys, counts = _table_reserve(keys, counts, meta, 81 * n_walk)
    return (walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed), keys, counts


@loop_helper
def _contacts_fuse(here, into, n_walk, labels, width, state, scratch, keys, counts, work):
    """Fuse compact zone ``here`` (``n_walk`` candidates, gathered by :func:`_gather`)
    into ``into`` in the contact state, whose arrays have room (:func:`_room_needed`).

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

    The hash sets are probed from a prefix sized for this fusion (their
    entries are cleared after it, so probing past it stays correct), which keeps
    a small fusion's probes in a few cache lines. Allocates nothing, so the
    loops calling it count no references (``loop_helper``); the arrays of
    ``state`` other than the table (``keys`` / ``counts``) never change.
    """
    parent, pixels, following, head, tail, _, _, meta, slots, total = state
    walk, walk_pixels, seen, affected, used, change_keys, change_counts, changed = scratch
    around, partners, signs = work
    base = np.int64(len(parent))
    seen_bits = max(_bits(4 * 9 * n_walk), _MIN_BITS)
    for i in range(min(n_walk, _AHEAD)):
        _prefetch_rows(labels, walk_pixels[i], width)
    n_affected = np.int64(0)  # typed, not a literal: a literal argument compiles a callee twice
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
    # At most 9 count changes per affected pixel; the prefix stays at most half full.
    change_bits = max(_bits(2 * 9 * n_affected), _MIN_BITS)
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
    for k in range(n_changed):
        slot = changed[k]
        if change_counts[slot] != 0:
            key = change_keys[slot]
            _contact_add_live(slots, keys, counts, meta, base, key // base, key % base, change_counts[slot], parent)
        change_keys[slot] = _EMPTY
    parent[here] = into
    if kept_head != -1:
        if tail[into] == -1:
            head[into] = kept_head
        else:
            following[tail[into]] = kept_head
        tail[into] = kept_tail
    head[here] = tail[here] = -1


@inner_kernel
def _new_scratch():
    """Empty scratch arrays of :func:`_contacts_fuse`, and its 3x3 work arrays."""
    scratch = (
        np.empty(1024, np.int32),
        np.empty(1024, np.int32),
        _filled(np.int64(4096), _EMPTY, np.int64),
        np.empty(1024, np.int32),
        np.empty(1024, np.int64),
        _filled(np.int64(4096), _EMPTY, np.int64),
        np.zeros(4096, np.int64),
        np.empty(2048, np.int64),
    )
    return scratch, (np.empty(9, np.int32), np.empty(9, np.int32), np.empty(9, np.int64))


@loop_helper
def _fuse_tracked(here, into, labels, width, state, scratch, keys, counts, work):
    """:func:`_contacts_fuse` when its arrays have room; returns False (nothing done) when
    they must grow first (the caller then calls :func:`_with_room` and again)."""
    n_walk = _gather(state[3], state[2], state[1], here, scratch[0], scratch[1])
    if _room_needed(n_walk, scratch, keys, state[7]):
        return False
    _contacts_fuse(here, into, n_walk, labels, width, state, scratch, keys, counts, work)
    return True


@loop_helper
def _contact_percent(state, keys, counts, zone, other):
    """Integer percentage of compact ``zone``'s contour pixels having ``other`` in their 3x3."""
    parent, _, _, _, _, _, _, meta, slots, total = state
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
    The loop reassigns no array but when one must grow (:func:`_fuse_tracked`):
    a tuple of arrays reassigned at every fusion made numba count references of
    each of its arrays at every zone visited (a sixth of the time).
    """
    records, nodes = graph
    original, compact_of, state = tracking
    keys, counts, total = state[5], state[6], state[9]
    scratch, work = _new_scratch()
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
                nodes[node | 1, ATTRIBUTE] == 0 and total[here] > 0
                and _contact_percent(state, keys, counts, here, compact_of[other]) >= ripples
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
        into = np.int64(compact_of[best])
        if not _fuse_tracked(np.int64(here), into, labels, width, state, scratch, keys, counts, work):
            n_walk = _gather(state[3], state[2], state[1], here, scratch[0], scratch[1])
            scratch, keys, counts = _with_room(n_walk, scratch, keys, counts, state[7])
            _fuse_tracked(np.int64(here), into, labels, width, state, scratch, keys, counts, work)
        alive[zone] = False
        size[best] += size[zone]
        fuse_edges(np.int64(zone), np.int64(best), graph)
    _restore_labels(labels, state[0], original)


@loop_helper
def _contact_sum(state, keys, counts, zone, here, compact_of, graph):
    """Sum of contact percentages of ``zone`` (compact id ``here``) over its neighbours."""
    records, nodes = graph
    result = 0
    node = records[zone, HEAD]
    while node != -1:
        result += _contact_percent(state, keys, counts, here, compact_of[nodes[node, NEIGHBOUR]])
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
    keys, counts = state[5], state[6]
    scratch, work = _new_scratch()
    sums = np.zeros(len(records), np.int64)
    for k in range(len(original)):
        zone = original[k]
        sums[zone] = _contact_sum(state, keys, counts, np.int64(zone), np.int64(k + 1), compact_of, graph)
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
        here, into = np.int64(k + 1), np.int64(compact_of[target])
        if not _fuse_tracked(here, into, labels, width, state, scratch, keys, counts, work):
            n_walk = _gather(state[3], state[2], state[1], here, scratch[0], scratch[1])
            scratch, keys, counts = _with_room(n_walk, scratch, keys, counts, state[7])
            _fuse_tracked(here, into, labels, width, state, scratch, keys, counts, work)
        alive[zone] = False
        size[target] += size[zone]
        fuse_edges(np.int64(zone), np.int64(target), graph)
        sums[target] = _contact_sum(state, keys, counts, np.int64(target), into, compact_of, graph)
    _restore_labels(labels, state[0], original)
