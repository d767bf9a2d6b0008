"""Counting the contacts of a MAORIS label image (numba).

:func:`count_contacts` counts every contact of a range of pixels (the bands of
:func:`ursim_core.segmentation.maoris.contact_tracking.start_tracking`); :func:`contact_table` gives all counts
as rows. The pixel-level rules (contour pixel, partners, the changes a fusion
makes) are the helpers here; :mod:`.fusion` applies them while fusing.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.contact_table import (
    _COUNT,
    _EMPTY,
    _GOLDEN,
    _SLOTS,
    _contact_add,
    _new_table,
    _table_reserve,
)
from ursim_core.segmentation.maoris.kernels.flat_zones import relabel
from ursim_core.segmentation.maoris.kernels.helpers import _filled, _grown, _zone_of, inner_kernel, loop_helper

# Size of the cache of pending counts when counting from scratch (count_contacts).
_PENDING_BITS = 14


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
    return _distinct_others(around, partners, np.int64(0))


@loop_helper
def _recount(around, here, into, partners, signs, total):
    """Changes of the contact counts of a pixel whose 3x3 zones are ``around``
    for the fusion of zone ``here`` into ``into``: returns ``(own, n)``, the
    count (own, ``partners[i]``) changing by ``signs[i]`` for i < n (contour
    sizes in ``total`` are updated here). ``around`` is rewritten to after.

    Only the counts of live zones with live partners change: those of ``here``
    itself, and every count with ``here`` as the partner, are left as they are,
    since a fused zone is never queried again (its partner entries are reused
    by :func:`~.contact_table._contact_add_live`). Two thirds of the changes a fusion
    made were the removal of such counts.
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
        n = _distinct_others(around, partners, np.int64(0))
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
        if had_here and not _is_contour(around):
            # No longer a contour pixel: it leaves every count of `into`.
            total[own] -= 1
            n = _distinct_others(around, partners, np.int64(0))
            for i in range(n):
                signs[i] = -1
    elif was_contour:
        had_here, had_into = False, False
        for k in range(9):
            if around[k] == here:
                had_here = True
            elif around[k] == into:
                had_into = True
        if had_here and not had_into:
            partners[0], signs[0] = into, 1
            n = 1
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
    """Renumber the live zones 1..n - 1 in id order, in place (:func:`_compacted`)."""
    return _compacted(labels, alive)


# The kernels that contact_table calls are compiled as helpers with one body each: an
# entry kernel called by another is compiled twice by the ahead-of-time build, once for
# the caller and once for its own export (a second or more of CPU for these two).
@inner_kernel
def _compacted(labels, alive):
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


@inner_kernel
def _restore_labels(labels, parent, original):
    """Undo :func:`_compact_labels`, each label replaced by its current zone."""
    lookup = np.zeros(len(parent), np.int32)
    for label in range(1, len(parent)):
        lookup[label] = original[_zone_of(label, parent) - 1]
    relabel(labels, lookup)


@njit(cache=True, nogil=True)
def count_contacts(labels, width, n, start, stop):
    """Contact counts of the pixels ``start..stop - 1`` of a compact, padded, flattened
    label image (:func:`_counted`)."""
    return _counted(labels, width, n, start, stop)


@inner_kernel
def _counted(labels, width, n, start, stop):
    """Contact counts of the pixels ``start..stop - 1`` of a compact, padded,
    flattened label image (``n`` zones; every label its own zone).

    Returns ``(pixels, used, keys, counts, meta, slots, total)``: the border
    candidates (pixels not surrounded by their own label) in raster order,
    ``used`` of them in use (:func:`group_candidates` links them into one list
    per zone); the contact counts (per-zone slots, the shared table, ``total`` =
    contour sizes). The pixels outside the range are only read, so bands of
    rows can be counted at the same time (:func:`start_tracking`).
    """
    # Room for every pixel of the range: pages never written are never faulted in, while
    # growing by doubling copied the candidates about twice over, into fresh pages.
    pixels = np.empty(max(stop - start, 1), np.int32)
    keys, counts, meta = _new_table(np.int64(16))
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
        pixels[n_candidates] = pixel
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
                    keys, counts = _table_reserve(keys, counts, meta, np.int64(1))
                evicted = pending_keys[index]
                _contact_add(slots, keys, counts, meta, base, evicted // base, evicted % base, pending_counts[index])
            pending_keys[index] = key
            pending_counts[index] = 1
    keys, counts = _table_reserve(keys, counts, meta, len(pending_keys))
    for index in range(len(pending_keys)):
        if pending_keys[index] != _EMPTY:
            key = pending_keys[index]
            _contact_add(slots, keys, counts, meta, base, key // base, key % base, pending_counts[index])
    return pixels, n_candidates, keys, counts, meta, slots, total


@njit(cache=True)
def join_counts(first, second):
    """The counts of two bands of rows (:func:`count_contacts`), ``second``
    below ``first``, as one: ``first``'s arrays, extended."""
    pixels, used, keys, counts, meta, slots, total = first
    pixels_b, used_b, keys_b, counts_b, meta_b, slots_b, total_b = second
    n = len(total)
    if used + used_b > len(pixels):
        pixels = _grown(pixels, used + used_b, 0)
    for k in range(used_b):
        pixels[used + k] = pixels_b[k]
    for zone in range(n):
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
    return pixels, used + used_b, keys, counts, meta, slots, total


@njit(cache=True, nogil=True)
def group_candidates(labels, pixels, used, n):
    """The border candidates ``pixels[:used]`` of :func:`count_contacts` (raster
    order, compact labels, every label its own zone) as one linked list per zone:
    ``(pixels, following, head, tail)``, ``pixels[k]`` a pixel, ``following[k]``
    the next candidate of its zone or -1, ``head`` / ``tail`` per zone (-1: none).

    Each zone's candidates are stored contiguously, in raster order: a fusion
    walks the list of the zone it absorbs, and on a map of 8000 px a side, with
    the candidates in raster order of the whole image, every row of a zone cost
    a cache miss in arrays far larger than the cache, each waiting for the last.
    """
    start = np.zeros(n + 1, np.int64)
    for k in range(used):
        start[labels[pixels[k]] + 1] += 1
    for zone in range(n):
        start[zone + 1] += start[zone]
    grouped = np.empty(max(used, 1), np.int32)
    following = np.empty(max(used, 1), np.int32)
    head = _filled(n, -1, np.int32)
    tail = _filled(n, -1, np.int32)
    for zone in range(n):
        if start[zone + 1] > start[zone]:
            head[zone] = start[zone]
            tail[zone] = start[zone + 1] - 1
    # ``start`` becomes each zone's next free position.
    for k in range(used):
        zone = labels[pixels[k]]
        grouped[start[zone]] = pixels[k]
        start[zone] += 1
    for k in range(used):
        following[k] = k + 1
    for zone in range(n):
        if tail[zone] != -1:
            following[tail[zone]] = -1
    return grouped, following, head, tail


@njit(cache=True)
def contact_table(labels, width, alive):
    """Every contact count of a padded flat label image, as ``(zone, other,
    count)`` rows in original ids (other = 0: the zone's contour size)."""
    work = labels.copy()
    original, compact_of, n = _compacted(work, alive)
    pixels, used, keys, counts, meta, slots, total = _counted(work, width, n, np.int64(0), work.size)
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
