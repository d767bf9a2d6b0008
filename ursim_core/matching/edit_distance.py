"""Levenshtein alignment of two region sequences and its normalised distance.

This is the edit distance the planar matcher uses to align the cyclic neighbour lists of two
regions (Mielle et al. 2019, Algorithm 1; released code ``edit_distance_cpp``, see
``original_code.md`` §1.11). Elements are compared through a boolean "same" relation, given as a
callable or a matrix: in URSIM two regions are "the same" when their signature distance is
``c <= m``.

Costs: insertion 1, deletion 1, substitution 0 when the elements are the same and 1 otherwise.
The operation string uses the released code's letters, read from the first elements to the last:

``n``  the two elements are aligned and the same (no change),
``s``  the two elements are aligned but differ (substitution),
``d``  an element of ``first`` is skipped (deletion),
``i``  an element of ``second`` is skipped (insertion).

The backtrace starts at the bottom-right cell and prefers the diagonal when it is ``<=`` both the
cell above and the cell to the left, then the left cell (``i``), then the cell above (``d``); on
the first row it moves left, on the first column up.  Ties are therefore broken exactly as the
released code does, which matters because the aligned pairs become matches.

The normalised distance (Yujian and Bo 2007) reduces to ``d_N = 2 d / (|X| + |Y| + d)`` because
every element is the same as itself; it lies in [0, 1], is 0 for two empty sequences and 1 when
exactly one is empty.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Alignment",
    "levenshtein",
    "normalised_distance",
    "align",
    "cyclic_align",
    "aligned_pairs",
    "aligned_index_pairs",
    "same_matrix",
    "PackedOrders",
]

SameRelation = Callable[[object, object], bool]


@dataclass(frozen=True)
class Alignment:
    """Result of aligning two sequences.

    Attributes
    ----------
    distance : int
        Levenshtein distance.
    normalised : float
        ``2 d / (|X| + |Y| + d)``, in [0, 1].
    operations : str
        Operation string over ``n``, ``s``, ``d``, ``i`` from the first elements to the last.
    rotation : int
        Offset of the rotation of the first sequence that was aligned (0 for a plain alignment).
    reflected : bool
        True when the first sequence was reversed before rotating.
    first : tuple
        The (rotated, possibly reversed) first sequence that ``operations`` refers to.
    second : tuple
        The second sequence.
    """

    distance: int
    normalised: float
    operations: str
    rotation: int = 0
    reflected: bool = False
    first: tuple = ()
    second: tuple = ()


def levenshtein(first: Sequence, second: Sequence, same) -> tuple[int, str]:
    """Levenshtein distance and the released code's backtrace.

    Parameters
    ----------
    first, second : sequence
        The sequences. When ``same`` is a matrix, their elements index its rows
        (``first``) and columns (``second``).
    same : callable or 2-D array-like of bool
        ``same(a, b)`` or ``same[a][b]``: True when element ``a`` of ``first`` and
        element ``b`` of ``second`` are equal (substitution cost 0). With a NumPy bool
        array, alignments of :data:`COMPILED_CELLS` cells or more run compiled (same result).

    Returns
    -------
    distance : int
    operations : str
        Letters ``n``, ``s``, ``d``, ``i`` (see the module docstring), first elements first.

    Examples
    --------
    >>> levenshtein("kitten", "sitting", lambda a, b: a == b)
    (3, 'snnnsni')
    >>> levenshtein([0, 1], [0], [[False], [True]])
    (1, 'dn')
    """
    rows, cols = len(first), len(second)
    if isinstance(same, np.ndarray):
        equal_array = _equal_array(first, second, same)
        if rows * cols >= COMPILED_CELLS:
            return _compiled_levenshtein(equal_array)
        equal = equal_array.tolist()
    elif callable(same):
        equal = [[bool(same(a, b)) for b in second] for a in first]
    else:  # a matrix: read its rows once instead of one call per cell (the matcher's hot loop)
        equal = [[same[a][b] for b in second] for a in first]
    table = [[0] * (cols + 1) for _ in range(rows + 1)]
    for i in range(rows + 1):
        table[i][0] = i
    for j in range(cols + 1):
        table[0][j] = j
    for i in range(1, rows + 1):
        equal_row = equal[i - 1]
        above, here = table[i - 1], table[i]
        for j in range(1, cols + 1):
            substitution = above[j - 1] + (0 if equal_row[j - 1] else 1)
            insertion, deletion = here[j - 1] + 1, above[j] + 1
            best = substitution if substitution < deletion else deletion
            here[j] = best if best < insertion else insertion
    operations = []
    i, j = rows, cols
    while i > 0 or j > 0:
        if i == 0:
            operations.append("i")
            j -= 1
        elif j == 0:
            operations.append("d")
            i -= 1
        else:
            diagonal, up, left = table[i - 1][j - 1], table[i - 1][j], table[i][j - 1]
            if diagonal <= up and diagonal <= left:
                operations.append("n" if table[i][j] == diagonal else "s")
                i -= 1
                j -= 1
            elif left <= up:
                operations.append("i")
                j -= 1
            else:
                operations.append("d")
                i -= 1
    return table[rows][cols], "".join(reversed(operations))


#: Alignments of at least this many cells (``len(first) * len(second)``) with a NumPy "same"
#: matrix run in the compiled kernel (:mod:`ursim_core.matching.edit_kernel`); smaller ones stay in
#: Python, so small maps never import numba. Both give the same operations.
COMPILED_CELLS = 400

_LETTERS = np.frombuffer(b"nsdi", dtype=np.uint8)


def _equal_array(first: Sequence[int], second: Sequence[int], same: np.ndarray) -> np.ndarray:
    """``same`` restricted to the rows ``first`` and the columns ``second``, in their order."""
    rows = np.asarray(first, dtype=np.intp)
    cols = np.asarray(second, dtype=np.intp)
    return np.ascontiguousarray(same[rows[:, None], cols[None, :]], dtype=np.bool_)


def _compiled_levenshtein(equal: np.ndarray) -> tuple[int, str]:
    from ursim_core.matching.edit_kernel import levenshtein_codes

    distance, codes = levenshtein_codes(equal)
    return int(distance), _LETTERS[codes].tobytes().decode("ascii")


def _compiled_aligned(first: Sequence[int], second: Sequence[int], equal: np.ndarray) -> list[tuple[int, int]]:
    """Aligned pairs from the compiled backtrace: the ``n`` and ``s`` steps."""
    from ursim_core.matching.edit_kernel import levenshtein_codes

    _, codes = levenshtein_codes(equal)
    first_positions = np.cumsum(codes != 3) - 1  # every step but an insertion advances in first
    second_positions = np.cumsum(codes != 2) - 1  # every step but a deletion advances in second
    aligned = codes <= 1
    first_items = np.asarray(first)[first_positions[aligned]].tolist()
    second_items = np.asarray(second)[second_positions[aligned]].tolist()
    return list(zip(first_items, second_items))


def normalised_distance(distance: int, first_length: int, second_length: int) -> float:
    """Normalised edit distance ``2 d / (|X| + |Y| + d)`` (0 for two empty sequences).

    Examples
    --------
    >>> normalised_distance(3, 6, 7)
    0.375
    >>> normalised_distance(0, 0, 0), normalised_distance(2, 2, 0)
    (0.0, 1.0)
    """
    denominator = first_length + second_length + distance
    if denominator == 0:
        return 0.0
    return 2.0 * distance / denominator


def align(first: Sequence, second: Sequence, same) -> Alignment:
    """Align two sequences: Levenshtein distance, normalised distance and operations.

    Examples
    --------
    >>> result = align("ab", "abc", lambda a, b: a == b)
    >>> result.distance, round(result.normalised, 3), result.operations
    (1, 0.333, 'nni')
    """
    distance, operations = levenshtein(first, second, same)
    return Alignment(
        distance=distance,
        normalised=normalised_distance(distance, len(first), len(second)),
        operations=operations,
        first=tuple(first),
        second=tuple(second),
    )


def cyclic_align(
    first: Sequence,
    second: Sequence,
    same,
    *,
    rotation_search: str = "min",
    reflections: bool = False,
) -> Alignment:
    """Align a cyclic sequence with another by trying rotations of the first.

    Parameters
    ----------
    first : sequence
        Cyclic sequence that is rotated (the sketch region's neighbours in the matcher).
    second : sequence
        Sequence kept as is (the metric region's neighbours).
    same : callable or 2-D array-like of bool
        Equality relation, see :func:`levenshtein`.
    rotation_search : {'min', 'first'}
        ``'min'`` keeps the rotation with the lowest normalised distance (ties: the
        smallest offset, non-reflected before reflected). ``'first'`` reproduces the
        released code, whose integer truncation of the best distance means the
        rotation at offset 0 is always kept (original_code.md §1.10).
    reflections : bool
        Also try the rotations of the reversed first sequence (mirror-image sketches).
        Ignored by ``rotation_search='first'``.

    Returns
    -------
    Alignment
        With ``rotation`` and ``reflected`` telling which version of ``first`` was used.

    Examples
    --------
    >>> same = lambda a, b: a == b
    >>> cyclic_align("bca", "abc", same).rotation
    2
    >>> cyclic_align("bca", "abc", same, rotation_search="first").operations
    'innd'
    >>> cyclic_align("cba", "abc", same, reflections=True).reflected
    True
    """
    if rotation_search not in ("min", "first"):
        raise ValueError(f"rotation_search must be 'min' or 'first', not {rotation_search!r}")
    sequence = list(first)
    if rotation_search == "first" or len(sequence) <= 1:
        return align(sequence, second, same)
    candidates = [(False, sequence)]
    if reflections:
        candidates.append((True, sequence[::-1]))
    # Every rotation has the same lengths, so the lowest normalised distance is the lowest
    # distance: only an improvement builds an Alignment (this runs for every seed of the matcher).
    best = None
    for reflected, base in candidates:
        for offset in range(len(base)):
            rotated = base[offset:] + base[:offset]
            distance, operations = levenshtein(rotated, second, same)
            if best is None or distance < best.distance:
                best = Alignment(
                    distance=distance,
                    normalised=normalised_distance(distance, len(rotated), len(second)),
                    operations=operations,
                    rotation=offset,
                    reflected=reflected,
                    first=tuple(rotated),
                    second=tuple(second),
                )
                if distance == 0:
                    return best
    return best


def aligned_pairs(alignment: Alignment) -> list[tuple]:
    """Pairs of elements that the operations align (``n`` and ``s`` both count).

    The released code turns every aligned position into a match, whether the two
    elements were the same (``n``) or substituted (``s``).

    Examples
    --------
    >>> aligned_pairs(align("abc", "axc", lambda a, b: a == b))
    [('a', 'a'), ('b', 'x'), ('c', 'c')]
    """
    pairs = []
    i = j = 0
    for operation in alignment.operations:
        if operation in "ns":
            pairs.append((alignment.first[i], alignment.second[j]))
            i += 1
            j += 1
        elif operation == "d":
            i += 1
        else:
            j += 1
    return pairs


def aligned_index_pairs(
    first: Sequence[int], second: Sequence[int], same: Sequence[Sequence[bool]] | np.ndarray
) -> list[tuple[int, int]]:
    """Pairs aligned by :func:`levenshtein` for integer sequences and a "same" matrix.

    Same result as ``aligned_pairs(align(first, second, same))`` (same costs, same
    backtrace ties), specialised for the matcher's inner loop: no operation string,
    no callable, and a shortcut for one-element sequences. ``same`` is nested lists or a
    NumPy bool array; with an array, alignments of :data:`COMPILED_CELLS` cells or more
    run compiled (the matcher passes an array, so the long neighbour lists of large maps
    cost microseconds instead of milliseconds).

    Examples
    --------
    >>> aligned_index_pairs([0, 1], [1, 0], [[False, True], [True, False]])
    [(0, 1), (1, 0)]
    """
    rows, cols = len(first), len(second)
    if rows == 0 or cols == 0:
        return []
    if rows == 1 and cols == 1:
        return [(first[0], second[0])]
    if isinstance(same, np.ndarray):
        equal_array = _equal_array(first, second, same)
        if rows * cols >= COMPILED_CELLS:
            return _compiled_aligned(first, second, equal_array)
        equal = equal_array.tolist()
    else:
        equal = [[same_row[b] for b in second] for same_row in (same[a] for a in first)]
    table = [list(range(cols + 1))]
    for i in range(1, rows + 1):
        equal_row = equal[i - 1]
        above = table[i - 1]
        here = [i]
        left = i
        for j in range(1, cols + 1):
            value = above[j - 1] + (0 if equal_row[j - 1] else 1)
            if above[j] + 1 < value:
                value = above[j] + 1
            if left + 1 < value:
                value = left + 1
            here.append(value)
            left = value
        table.append(here)
    pairs = []
    i, j = rows, cols
    while i > 0 and j > 0:
        diagonal, up, left = table[i - 1][j - 1], table[i - 1][j], table[i][j - 1]
        if diagonal <= up and diagonal <= left:
            i -= 1
            j -= 1
            pairs.append((first[i], second[j]))
        elif left <= up:
            j -= 1
        else:
            i -= 1
    pairs.reverse()
    return pairs


class PackedOrders:
    """Two cyclic orders and their "same" cells, packed once to align many arcs of them.

    A building's corridor borders thousands of rooms, and the planar matcher aligns arcs of the
    two corridors' neighbour lists many times over. :meth:`aligned` gives what
    :func:`aligned_index_pairs` gives for the same two arcs (same costs, same backtrace ties),
    with 64 rows per machine word (:func:`ursim_core.matching.edit_kernel.packed_codes`), after
    one pass over the ``len(first) x len(second)`` cells here. Imports numba.

    Parameters
    ----------
    first, second : sequence of int
        The two cyclic orders (rows and columns of ``same``).
    same : (n1, n2) NumPy bool array

    Examples
    --------
    >>> same = np.array([[True, False, False], [False, True, False], [False, False, True]])
    >>> packed = PackedOrders([0, 1, 2], [2, 0, 1], same)
    >>> packed.aligned(1, 2, 2, 2) == aligned_index_pairs([1, 2], [1, 2], same)
    True
    """

    def __init__(self, first: Sequence[int], second: Sequence[int], same: np.ndarray):
        from ursim_core.matching.edit_kernel import pack_same

        self._first = np.asarray(first, dtype=np.intp)
        self._second = np.asarray(second, dtype=np.intp)
        self._bits = pack_same(np.ascontiguousarray(same, dtype=np.bool_), self._first, self._second)

    def aligned(self, first_start: int, rows: int, second_start: int, cols: int) -> list[tuple[int, int]]:
        """Aligned pairs of ``rows`` elements of ``first`` from position ``first_start`` on (cyclic)
        and ``cols`` elements of ``second`` from ``second_start`` on."""
        from ursim_core.matching.edit_kernel import packed_codes

        if rows == 0 or cols == 0:
            return []
        codes = packed_codes(self._bits, first_start, rows, second_start, cols)
        first_positions = np.cumsum(codes != 3) - 1  # every step but an insertion advances in first
        second_positions = np.cumsum(codes != 2) - 1  # every step but a deletion advances in second
        aligned = codes <= 1
        first_items = self._first[(first_positions[aligned] + first_start) % self._first.size].tolist()
        second_items = self._second[(second_positions[aligned] + second_start) % self._second.size].tolist()
        return list(zip(first_items, second_items))


def same_matrix(c_matrix: np.ndarray, m: float) -> list[list[bool]]:
    """Boolean "same" relation ``c <= m`` as nested lists (fast indexing in the matcher).

    Examples
    --------
    >>> same_matrix(np.array([[0.0, 0.3]]), 0.1)
    [[True, False]]
    """
    return (np.asarray(c_matrix) <= m).tolist()
