"""Compiled Levenshtein table and backtrace (numba) for the long sequences of large maps.

:mod:`ursim_core.matching.edit_distance` calls :func:`levenshtein_codes` when both sequences are
long (a corridor of a building map has hundreds of neighbours, and aligning two such lists in
Python costs about 0.7 us per cell). The costs and the backtrace's tie rules are those of
:func:`ursim_core.matching.edit_distance.levenshtein`, so both give the same operations; a test
compares them on random inputs with many ties.

This module imports numba, so it is imported only when a long alignment is needed: small maps
(sketches, the KTH model) never load it. The kernel is compiled on its first use in an
environment (about a second) and cached on disk by numba.
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
