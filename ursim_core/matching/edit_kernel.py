"""Compiled Levenshtein table and backtrace (numba) for the long sequences of large maps.

:mod:`ursim_core.matching.edit_distance` calls :func:`levenshtein_codes` when both sequences are
long (a corridor of a building map has hundreds of neighbours, and aligning two such lists in
Python costs about 0.7 us per cell). The costs and the backtrace's tie rules are those of
:func:`ursim_core.matching.edit_distance.levenshtein`, so both give the same operations; a test
compares them on random inputs with many ties.

This module imports numba, so it is imported only when a long alignment is needed: small maps
(sketches, the KTH model) never load it. The kernel is compiled on its first use in an
environment (about a second) and cached on disk by numba. The planar matcher's C loop aligns long
neighbour orders itself (``csrc/bitalign.c``, a port of :func:`pack_same` and :func:`packed_codes`
that a test compares with them), so ``ursim match`` of a building no longer imports numba for
this (about 0.9 s of the process): the Python matcher does, where it runs (constraints, alternatives
kept, no C compiler).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

__all__ = ["levenshtein_codes", "CODE_LETTERS"]

#: Operation codes of :func:`levenshtein_codes`, as the letters of the operation strings.
CODE_LETTERS = "nsdi"
_N, _S, _D, _I = 0, 1, 2, 3


@njit(types.Tuple((types.int64, types.int8[::1]))(types.boolean[:, ::1]), cache=True, nogil=True)
def levenshtein_codes(equal):
    """Levenshtein distance of two sequences and the released code's backtrace.

    ``equal[i, j]`` is True when element i of the first sequence and element j of the second
    are the same. Returns the distance and the operations from the first elements to the last
    as codes 0-3 (``CODE_LETTERS[code]`` is the letter).
    """
    rows, cols = equal.shape
    table = np.empty((rows + 1, cols + 1), np.int32)
    for j in range(cols + 1):
        table[0, j] = j
    for i in range(1, rows + 1):
        table[i, 0] = i
        left = i
        for j in range(1, cols + 1):
            value = table[i - 1, j - 1] + (0 if equal[i - 1, j - 1] else 1)
            up = table[i - 1, j] + 1
            if up < value:
                value = up
            if left + 1 < value:
                value = left + 1
            table[i, j] = value
            left = value
    codes = np.empty(rows + cols, np.int8)
    count = 0
    i, j = rows, cols
    while i > 0 or j > 0:
        if i == 0:
            codes[count] = _I
            j -= 1
        elif j == 0:
            codes[count] = _D
            i -= 1
        else:
            diagonal, up, left = table[i - 1, j - 1], table[i - 1, j], table[i, j - 1]
            if diagonal <= up and diagonal <= left:
                codes[count] = _N if table[i, j] == diagonal else _S
                i -= 1
                j -= 1
            elif left <= up:
                codes[count] = _I
                j -= 1
            else:
                codes[count] = _D
                i -= 1
        count += 1
    return np.int64(table[rows, cols]), codes[:count][::-1].copy()


# --------------------------------------------------------------------------- bit-parallel arcs
#
# A building map's corridor is one region bordering thousands of rooms, and the planar matcher
# aligns arcs of its neighbour list (thousands of elements on both sides) over and over. The table
# above costs rows x cols cells each time (about 18 million for two 4250-room corridors) plus the
# gather of the "same" cells. Below, the "same" bits of the two whole neighbour orders are packed
# once (:func:`pack_same`), and an arc pair is aligned by Myers' bit-parallel recurrence in the
# block form of Hyyrö (as in edlib), 64 rows per machine word. The per-column vertical and
# horizontal differences are kept, which gives back every table value the backtrace reads, so the
# backtrace (and its tie rules) is exactly that of :func:`levenshtein_codes`.

_U1 = np.uint64(1)
_U63 = np.uint64(63)
_U64 = np.uint64(64)


@njit(types.uint64[:, ::1](types.boolean[:, ::1], types.intp[::1], types.intp[::1]), cache=True, nogil=True)
def pack_same(same, first, second):
    """Bits of ``same[first[p % n1], second[q]]``: row q, bit p, for p in 0 .. 2 n1 - 1.

    The first order is packed twice over, so that any cyclic range of it is one straight run
    of bits; one spare word at the end lets a 64-bit window start at any bit.
    """
    n1, n2 = first.size, second.size
    words = (2 * n1 + 63) // 64 + 1
    bits = np.zeros((n2, words), np.uint64)
    # 64 rows of `same` at a time: every read is in one of 64 rows, so they stay in cache.
    for start in range(0, n1, 64):
        stop = min(start + 64, n1)
        word = start // 64
        for q in range(n2):
            column = second[q]
            value = np.uint64(0)
            for p in range(start, stop):
                if same[first[p], column]:
                    value |= _U1 << np.uint64(p - start)
            bits[q, word] = value
    # The second copy: bits 0 .. n1 - 1 again from bit n1 on.
    shift = np.uint64(n1 & 63)
    base = n1 >> 6
    used = (n1 + 63) // 64
    for q in range(n2):
        # Read before writing: the copy's first word is the original's last when n1 % 64 != 0.
        original = bits[q, :used].copy()
        for word in range(used):
            value = original[word]
            bits[q, base + word] |= value << shift
            if shift != 0:
                bits[q, base + word + 1] |= value >> (_U64 - shift)
    return bits


@njit(types.uint64(types.uint64[::1], types.int64), cache=True, nogil=True, inline="always")
def _window(row, offset):
    """The 64 bits of ``row`` from bit ``offset`` on."""
    word = offset >> 6
    shift = np.uint64(offset & 63)
    value = row[word] >> shift
    if shift != 0:
        value |= row[word + 1] << (_U64 - shift)
    return value


@njit(
    types.int8[::1](types.uint64[:, ::1], types.int64, types.int64, types.int64, types.int64),
    cache=True,
    nogil=True,
)
def packed_codes(bits, first_start, rows, second_start, cols):
    """Operation codes of the alignment of two cyclic ranges of the packed orders.

    The first sequence is positions ``first_start .. first_start + rows - 1`` (mod n1) of the
    first order, the second ``second_start .. second_start + cols - 1`` (mod n2) of the second
    (``first_start < n1``, ``rows <= n1``, ``cols <= n2``). The codes are those
    :func:`levenshtein_codes` gives for the same "same" matrix.
    """
    n2 = bits.shape[0]
    blocks = (rows + 63) // 64
    plus_v = np.empty((cols, blocks), np.uint64)
    minus_v = np.empty((cols, blocks), np.uint64)
    plus_h = np.empty((cols, blocks), np.uint64)
    minus_h = np.empty((cols, blocks), np.uint64)
    pv = np.full(blocks, ~np.uint64(0), np.uint64)  # column 0: D[i][0] = i, every step +1
    mv = np.zeros(blocks, np.uint64)
    for j in range(cols):
        row = bits[(second_start + j) % n2]
        # The horizontal difference carried into each block as two bits, +1 and -1 (never both):
        # the carry is OR-ed in without a branch, whose outcome the data decide (a mispredicted
        # branch per block cost about a third of the time). Row 0: D[0][j] = j, every step +1.
        carry_plus, carry_minus = _U1, np.uint64(0)
        for b in range(blocks):
            eq = _window(row, first_start + 64 * b)
            p, m = pv[b], mv[b]
            xv = eq | m
            eq |= carry_minus
            xh = (((eq & p) + p) ^ p) | eq
            ph = m | ~(xh | p)
            mh = p & xh
            plus_h[j, b] = ph
            minus_h[j, b] = mh
            out_plus, out_minus = ph >> _U63, mh >> _U63
            ph = (ph << _U1) | carry_plus
            mh = (mh << _U1) | carry_minus
            p = mh | ~(xv | ph)
            m = ph & xv
            pv[b], mv[b] = p, m
            plus_v[j, b] = p
            minus_v[j, b] = m
            carry_plus, carry_minus = out_plus, out_minus
    # D[rows][cols] from the last column's vertical differences (D[0][cols] = cols).
    value = cols
    for i in range(rows):
        bit = np.uint64(i & 63)
        value += np.int64((plus_v[cols - 1, i >> 6] >> bit) & _U1) - np.int64((minus_v[cols - 1, i >> 6] >> bit) & _U1)
    codes = np.empty(rows + cols, np.int8)
    count = 0
    i, j = rows, cols
    while i > 0 or j > 0:
        if i == 0:
            codes[count] = _I
            j -= 1
        elif j == 0:
            codes[count] = _D
            i -= 1
        else:
            word, bit = (i - 1) >> 6, np.uint64((i - 1) & 63)
            up = value - (np.int64((plus_v[j - 1, word] >> bit) & _U1) - np.int64((minus_v[j - 1, word] >> bit) & _U1))
            left = value - (
                np.int64((plus_h[j - 1, word] >> bit) & _U1) - np.int64((minus_h[j - 1, word] >> bit) & _U1)
            )
            if i == 1:
                diagonal = j - 1
            else:
                word, bit = (i - 2) >> 6, np.uint64((i - 2) & 63)
                diagonal = up - (
                    np.int64((plus_h[j - 1, word] >> bit) & _U1) - np.int64((minus_h[j - 1, word] >> bit) & _U1)
                )
            if diagonal <= up and diagonal <= left:
                codes[count] = _N if value == diagonal else _S
                value = diagonal
                i -= 1
                j -= 1
            elif left <= up:
                codes[count] = _I
                value = left
                j -= 1
            else:
                codes[count] = _D
                value = up
                i -= 1
        count += 1
    return codes[:count][::-1].copy()
