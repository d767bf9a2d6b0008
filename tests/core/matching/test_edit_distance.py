"""Edit distance, normalisation and backtrace against hand-worked cases; the packed (bit-parallel) alignment."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.matching.edit_distance import (
    PackedOrders,
    align,
    aligned_index_pairs,
    aligned_pairs,
    cyclic_align,
    levenshtein,
    normalised_distance,
)


def equal(a, b):
    return a == b


@pytest.mark.parametrize(
    "first, second, distance, operations",
    [
        ("kitten", "sitting", 3, "snnnsni"),
        ("abc", "abc", 0, "nnn"),
        ("", "", 0, ""),
        ("", "ab", 2, "ii"),
        ("ab", "", 2, "dd"),
        ("a", "b", 1, "s"),  # the diagonal is preferred over "di" / "id"
        ("ab", "ba", 2, "ss"),  # every cell ties: substitutions, not a shifted "ind"
        ("abc", "c", 2, "ddn"),
        ("ac", "abc", 1, "nin"),
    ],
)
def test_levenshtein_and_backtrace(first, second, distance, operations):
    assert levenshtein(first, second, equal) == (distance, operations)


def test_same_relation_as_matrix():
    # Rows index the first sequence's elements, columns the second's.
    same = [[True, False], [False, False]]
    assert levenshtein([0, 1], [0, 1], same) == (1, "ns")


@pytest.mark.parametrize(
    "distance, n_first, n_second, expected",
    [(3, 6, 7, 6 / 16), (0, 0, 0, 0.0), (2, 2, 0, 1.0), (2, 2, 2, 4 / 6), (0, 3, 3, 0.0)],
)
def test_normalised_distance(distance, n_first, n_second, expected):
    assert normalised_distance(distance, n_first, n_second) == pytest.approx(expected)


def test_normalised_distance_stays_in_unit_interval():
    for first in ("", "a", "ab", "abc", "xyz"):
        for second in ("", "a", "ba", "cab", "zz"):
            value = align(first, second, equal).normalised
            assert 0.0 <= value <= 1.0
            assert (value == 0.0) == (first == second)


def test_aligned_pairs_include_substitutions():
    result = align("abcd", "axd", equal)
    # Hand backtrace: (4,3) n; (3,2) diagonal 1 <= up 1, value 2 -> s (c with x); (2,1) up 0 < diagonal -> d.
    assert result.operations == "ndsn"
    assert aligned_pairs(result) == [("a", "a"), ("c", "x"), ("d", "d")]


def test_cyclic_minimum_rotation_versus_released_first_rotation():
    best = cyclic_align("bca", "abc", equal)
    assert (best.rotation, best.distance, best.operations) == (2, 0, "nnn")
    released = cyclic_align("bca", "abc", equal, rotation_search="first")
    assert (released.rotation, released.distance, released.operations) == (0, 2, "innd")
    assert released.normalised == pytest.approx(0.5)


def test_cyclic_ties_keep_the_smallest_offset():
    result = cyclic_align("aa", "ab", equal)
    assert result.rotation == 0 and result.operations == "ns"


def test_reflections_are_tried_only_when_asked():
    plain = cyclic_align("abcd", "dcba", equal)
    assert not plain.reflected and plain.distance > 0
    mirrored = cyclic_align("abcd", "dcba", equal, reflections=True)
    assert mirrored.reflected and mirrored.distance == 0
    assert aligned_pairs(mirrored) == [(x, x) for x in "dcba"]


def test_unknown_rotation_search_is_rejected():
    with pytest.raises(ValueError):
        cyclic_align("ab", "ab", equal, rotation_search="all")


@pytest.mark.parametrize("density", [0.05, 0.5, 0.95])
def test_compiled_alignment_gives_the_python_operations_and_pairs(density):
    # A NumPy "same" matrix sends long alignments (COMPILED_CELLS or more) to the numba kernel;
    # nested lists stay in Python. Dense and sparse relations make many backtrace ties.
    import numpy as np

    from ursim_core.matching.edit_distance import COMPILED_CELLS, aligned_index_pairs, levenshtein

    rng = np.random.default_rng(int(density * 100))
    same = rng.random((90, 90)) < density
    long_ones = 0
    for _ in range(60):
        first = rng.integers(0, 90, int(rng.integers(0, 70))).tolist()
        second = rng.integers(0, 90, int(rng.integers(0, 70))).tolist()
        long_ones += len(first) * len(second) >= COMPILED_CELLS
        assert levenshtein(first, second, same) == levenshtein(first, second, same.tolist())
        assert aligned_index_pairs(first, second, same) == aligned_index_pairs(first, second, same.tolist())
    assert long_ones > 10


@pytest.mark.parametrize("reflections", [False, True])
def test_cyclic_align_keeps_the_first_rotation_of_lowest_normalised_distance(reflections):
    # The definition, spelled out: every rotation (then every rotation of the reversed sequence)
    # aligned in turn, the first one of lowest normalised distance kept.
    import numpy as np

    rng = np.random.default_rng(7)
    for _ in range(300):
        first = rng.integers(0, 4, int(rng.integers(2, 8))).tolist()
        second = rng.integers(0, 4, int(rng.integers(0, 8))).tolist()
        candidates = [(False, first)] + ([(True, first[::-1])] if reflections else [])
        expected = None
        for reflected, base in candidates:
            for offset in range(len(base)):
                result = align(base[offset:] + base[:offset], second, equal)
                if expected is None or result.normalised < expected[0].normalised:
                    expected = (result, offset, reflected)
        got = cyclic_align(first, second, equal, reflections=reflections)
        result, offset, reflected = expected
        assert (got.distance, got.normalised, got.operations) == (result.distance, result.normalised, result.operations)
        assert (got.rotation, got.reflected, got.first, got.second) == (offset, reflected, result.first, result.second)


# --------------------------------------------------------------------------- packed orders
# The bit-parallel alignment of arcs of two packed neighbour orders gives the table's pairs.


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
