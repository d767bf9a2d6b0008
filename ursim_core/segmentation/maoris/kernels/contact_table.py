"""Storage of the MAORIS contact counts (numba).

A count is kept per pair of zones (a, b): the contour pixels of a having b in
their 3x3 neighbourhood. Each zone has a row of slots of its own; zones with
many partners spill into a shared hash table.
"""

from __future__ import annotations

import numpy as np

from ursim_core.segmentation.maoris.kernels.helpers import _filled, inner_kernel, loop_helper

# A hash table of int64 keys ``a * base + b`` -> count, open addressing with
# linear probing (much faster than a typed dict for millions of updates).
# ``meta`` holds [entries, bits]; a growing table is returned anew.

_EMPTY = -1
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MEMO = 64  # recently used keys -> slots: neighbouring pixels repeat the same few keys


@inner_kernel
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


@inner_kernel
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
def _contact_add_live(slots, keys, counts, meta, base, a, b, delta, parent):
    """:func:`_contact_add` while zones fuse: an entry of a's row whose partner is a
    fused zone (not its own union-find root in ``parent``) counts as free.

    The fusions leave the counts having a fused zone as the partner as they are (never
    queried again, :func:`~.contacts._recount`): their entries are reused here, when
    the row has no free one, so that they do not push live partners into the shared
    table. Every pair still has at most one entry, so the counts read are the same.
    """
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
    if free == -1:
        for k in range(start + 1, start + _SLOTS):
            partner = slots[k] >> 32
            if parent[partner] != partner:
                free = k
                break
    if free != -1:
        # A new contact only ever starts with a positive count.
        slots[free] = (np.int64(b) << 32) + delta
        return
    slots[start] = 1
    _table_add(keys, counts, meta, a * base + b, delta)
