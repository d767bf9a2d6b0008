"""Alignments of small neighbour lists remembered by their content, across planar matches.

The planar matcher aligns the same few neighbour lists over and over: once per seed and once
per pair of arcs of every hypothesis, at each of the 20 values of m, in every orientation tried
and in each of the six segmentations of a turned sketch. On the 18 KTH sketches turned by 30
degrees, 56,334 seed alignments had 4,154 distinct inputs and 62,584 arc alignments 939. An
alignment reads nothing but its two sequences and the cells of "same" between them, so those
three determine it: :func:`seed_alignment` and :func:`arc_pairs` key their results on them and
return what :func:`~ursim_core.matching.edit_distance.cyclic_align` and
:func:`~ursim_core.matching.edit_distance.aligned_index_pairs` would.

Only the nested-list form of "same" that the matcher uses for sketch-sized graphs is remembered;
an array (a building's map) is aligned as before. Each memo keeps at most :data:`MEMO_LIMIT`
entries and starts again empty when full, so memory stays bounded in a long session. Results
are tuples, shared by every caller and never changed.
"""

from __future__ import annotations

from operator import itemgetter

from ursim_core.matching.edit_distance import aligned_index_pairs, aligned_pairs, cyclic_align

__all__ = ["MEMO_LIMIT", "arc_pairs", "seed_alignment", "forget"]

#: Entries each memo keeps before it is emptied (a KTH evaluation needs a few thousand).
MEMO_LIMIT = 1 << 16

_seeds: dict = {}
_arcs: dict = {}


def _cells(first, second, same) -> tuple:
    """The cells of ``same`` between the two sequences, row by row (a hashable key)."""
    if len(second) == 1:
        column = second[0]
        return tuple(same[a][column] for a in first)
    row_cells = itemgetter(*second)
    return tuple(row_cells(same[a]) for a in first)


def _remembered(memo: dict, key, compute):
    found = memo.get(key)
    if found is None:
        if len(memo) >= MEMO_LIMIT:
            memo.clear()
        found = memo[key] = compute()
    return found


def seed_alignment(first, second, same, *, rotation_search: str = "min", reflections: bool = False):
    """Whether the best rotation of ``first`` is reflected, and the pairs it aligns.

    What ``cyclic_align`` and ``aligned_pairs`` give for the same arguments, as
    ``(alignment.reflected, tuple(aligned_pairs(alignment)))``.

    Examples
    --------
    >>> same = [[False, True], [True, False]]
    >>> seed_alignment([0, 1], [0, 1], same)
    (False, ((1, 0), (0, 1)))
    """

    def compute():
        alignment = cyclic_align(first, second, same, rotation_search=rotation_search, reflections=reflections)
        return alignment.reflected, tuple(aligned_pairs(alignment))

    if not isinstance(same, list) or not first or not second:
        return compute()
    key = (tuple(first), tuple(second), _cells(first, second, same), rotation_search, reflections)
    return _remembered(_seeds, key, compute)


def arc_pairs(first_arc, second_arc, same) -> tuple:
    """The pairs :func:`~ursim_core.matching.edit_distance.aligned_index_pairs` aligns, as a tuple.

    Examples
    --------
    >>> arc_pairs([0, 1], [1, 0], [[False, True], [True, False]])
    ((0, 1), (1, 0))
    """

    def compute():
        return tuple(aligned_index_pairs(first_arc, second_arc, same))

    if not isinstance(same, list) or not first_arc or not second_arc:
        return compute()
    key = (tuple(first_arc), tuple(second_arc), _cells(first_arc, second_arc, same))
    return _remembered(_arcs, key, compute)


def forget() -> None:
    """Empty both memos (tests, or to measure the alignments' cost)."""
    _seeds.clear()
    _arcs.clear()
