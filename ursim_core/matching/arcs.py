"""Expanding a hypothesis of the planar matcher: the arcs between locked neighbour pairs, aligned.

Step 3 of :func:`ursim_core.matching.planar.planar_match` (the released code's ``makeMatching``):
for a popped pair ``(v, v')``, the neighbours of ``v`` already matched to neighbours of ``v'`` are
locks; consecutive locks cut both cyclic neighbour orders into arcs, and each pair of arcs is
aligned by edit distance (:mod:`ursim_core.matching.edit_distance`). The aligned pairs are the
candidates the matcher queues.
"""

from __future__ import annotations

import numpy as np

from ursim_core.matching.alignment_memo import arc_pairs
from ursim_core.matching.edit_distance import COMPILED_CELLS, PackedOrders, aligned_index_pairs

__all__ = ["PACKED_CELLS", "arc", "expand_locked"]


def arc(order: list[int], start: int, stop: int) -> list[int]:
    """Elements strictly between positions ``start`` and ``stop`` walking forward (cyclic).

    ``start == stop`` gives every other element, starting after ``start``.

    Examples
    --------
    >>> arc([5, 6, 7, 8], 1, 3), arc([5, 6, 7, 8], 2, 1), arc([5, 6, 7, 8], 2, 2)
    ([7], [8, 5], [8, 5, 6])
    """
    if start < stop:
        return order[start + 1 : stop]
    return order[start + 1 :] + order[:stop]


#: Pairs of neighbour orders of at least this many cells (``len(first) * len(second)``) have their
#: "same" cells packed once (:class:`~ursim_core.matching.edit_distance.PackedOrders`) and their long
#: arcs aligned 64 rows per word: a building's corridor borders thousands of rooms, and its arcs
#: are aligned again for every hypothesis. Smaller orders align their arcs as lists (same pairs).
#: The planar matcher's C loop does the same (``csrc/bitalign.c``); this is its reference, and
#: runs where the C loop does not (constraints, alternatives kept, no C compiler).
PACKED_CELLS = 1 << 16


def expand_locked(first_order, second_order, matched, second_positions, same, cache, packed=None, key=None):
    """makeMatching: align the arcs between locked neighbour pairs; return candidate pairs.

    ``second_positions``: the position of every element of ``second_order``. ``packed``: a dict
    of :class:`PackedOrders` by ``key`` (the orders' identity), used when the orders are
    :data:`PACKED_CELLS` cells or more and ``same`` is an array.
    """
    locks = []  # (position in first_order, position in second_order), in first_order order
    partner_of, position_of = matched.get, second_positions.get  # once, not per neighbour
    for k, vertex in enumerate(first_order):
        partner = partner_of(vertex)
        if partner is not None:
            position = position_of(partner)
            if position is not None:
                locks.append((k, position))
    if not locks:
        return []
    size_first, size_second = len(first_order), len(second_order)
    if packed is not None and isinstance(same, np.ndarray) and size_first * size_second >= PACKED_CELLS:
        return _expand_packed(first_order, second_order, locks, same, cache, packed, key)
    candidates = []
    for index, (first_position, second_position) in enumerate(locks):
        next_first, next_second = locks[(index + 1) % len(locks)]
        first_arc = arc(first_order, first_position, next_first)
        second_arc = arc(second_order, second_position, next_second)
        if first_arc and second_arc:
            # Expansions from different seeds meet the same arcs again: align each pair of arcs
            # once per match (and once per content across matches, see alignment_memo).
            arc_key = (tuple(first_arc), tuple(second_arc))
            aligned = cache.get(arc_key)
            if aligned is None:
                aligned = cache[arc_key] = arc_pairs(first_arc, second_arc, same)
            candidates.extend(aligned)
    return candidates


def _expand_packed(first_order, second_order, locks, same, cache, packed, key):
    """:func:`expand_locked` for long orders: arcs as cyclic ranges of positions (same pairs)."""
    size_first, size_second = len(first_order), len(second_order)
    candidates = []
    for index, (first_position, second_position) in enumerate(locks):
        next_first, next_second = locks[(index + 1) % len(locks)]
        # Elements strictly between two locks, walking forward (all the others for one lock).
        rows = (next_first - first_position - 1) % size_first
        cols = (next_second - second_position - 1) % size_second
        if not rows or not cols:
            continue
        # Positions in the same two orders give the same arcs: one key per pair of ranges.
        arc_key = (key, first_position, next_first, second_position, next_second)
        aligned = cache.get(arc_key)
        if aligned is None:
            if rows * cols < COMPILED_CELLS:
                first_arc = arc(first_order, first_position, next_first)
                second_arc = arc(second_order, second_position, next_second)
                aligned = aligned_index_pairs(first_arc, second_arc, same)
            else:
                orders = packed.get(key)
                if orders is None:
                    orders = packed[key] = PackedOrders(first_order, second_order, same)
                aligned = orders.aligned(
                    (first_position + 1) % size_first, rows, (second_position + 1) % size_second, cols
                )
            cache[arc_key] = aligned
        candidates.extend(aligned)
    return candidates
