"""The bit-parallel alignment of arcs of two packed neighbour orders gives the table's pairs."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.matching.edit_distance import PackedOrders, aligned_index_pairs


def _arc(order, start, count):
    return [order[(start + k) % len(order)] for k in range(count)]


@pytest.mark.parametrize("density", [0.03, 0.5, 0.97])
def test_packed_arcs_give_the_pairs_of_the_lists(density):
    # Orders longer than 64 and 128 elements span several machine words; arcs wrap around the
    # end of the order; dense and sparse relations make many backtrace ties.
    rng = np.random.default_rng(int(density * 100))
    for n_first, n_second in ((3, 5), (64, 64), (70, 200), (150, 129)):
        same = rng.random((n_first + 7, n_second + 7)) < density
        first = rng.permutation(n_first + 7)[:n_first].tolist()
        second = rng.permutation(n_second + 7)[:n_second].tolist()
        packed = PackedOrders(first, second, same)
        for _ in range(25):
            first_start, second_start = int(rng.integers(0, n_first)), int(rng.integers(0, n_second))
            rows, cols = int(rng.integers(0, n_first + 1)), int(rng.integers(0, n_second + 1))
            expected = aligned_index_pairs(
                _arc(first, first_start, rows), _arc(second, second_start, cols), same.tolist()
            )
            assert packed.aligned(first_start, rows, second_start, cols) == expected


def test_packed_codes_equal_the_table_kernel_codes():
    # The whole operation string, not only the aligned pairs: insertions and deletions too.
    from ursim_core.matching.edit_kernel import levenshtein_codes, pack_same, packed_codes

    rng = np.random.default_rng(7)
    for rows, cols in ((1, 1), (1, 90), (90, 1), (63, 65), (128, 128), (257, 191)):
        equal = rng.random((rows, cols)) < 0.6
        bits = pack_same(equal, np.arange(rows, dtype=np.intp), np.arange(cols, dtype=np.intp))
        _, codes = levenshtein_codes(equal)
        assert np.array_equal(packed_codes(bits, 0, rows, 0, cols), codes)
