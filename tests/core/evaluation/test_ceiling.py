"""The one-to-one ceiling (ursim_core.evaluation.ceiling) against hand-worked cases and brute force."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from ursim_core.evaluation.ceiling import best_one_to_one
from ursim_core.evaluation.scoring import score_matches


def _brute_force(references) -> float:
    """The best mean F1 over every one-to-one subset of the clique pairs (and the empty answer)."""
    pairs = sorted({(a, b) for reference in references for s, m in reference for a in s for b in m if a and b})
    best = float(np.mean([score_matches((), reference).f1 for reference in references]))
    for size in range(1, len(pairs) + 1):
        for subset in itertools.combinations(pairs, size):
            if len({a for a, _ in subset}) < size or len({b for _, b in subset}) < size:
                continue
            best = max(best, float(np.mean([score_matches(subset, reference).f1 for reference in references])))
    return best


def test_annotators_who_read_the_sketch_opposite_ways_cap_the_mean_at_one_half():
    upright = [({1}, {10}), ({2}, {20})]
    turned = [({1}, {20}), ({2}, {10})]
    ceiling = best_one_to_one([upright, turned])
    assert ceiling.pairs == ((1, 10), (2, 20)) and ceiling.f1 == (1.0, 0.0)
    assert ceiling.mean_f1 == 0.5 and ceiling.exact


def test_one_pair_hits_a_clique_of_several_regions():
    ceiling = best_one_to_one([[({1}, {10, 11}), ({2, 3}, {20})]])
    assert ceiling.f1 == (1.0,) and len(ceiling.pairs) == 2


def test_one_annotator_alone_is_matched_perfectly():
    reference = [({1}, {10}), ({2}, {20}), ({3}, {30})]
    assert best_one_to_one([reference]).pairs == ((1, 10), (2, 20), (3, 30))


def test_no_usable_clique_gives_the_empty_answer_its_perfect_score():
    ceiling = best_one_to_one([[({1}, ()), ((), ())]])
    assert ceiling.pairs == () and ceiling.f1 == (1.0,)
    assert best_one_to_one([]).pairs == () and math.isnan(best_one_to_one([]).mean_f1)


def test_region_zero_is_no_region():
    assert best_one_to_one([[({0, 1}, {0, 10})]]).pairs == ((1, 10),)


@pytest.mark.parametrize("seed", range(60))
def test_the_search_finds_what_brute_force_finds(seed):
    rng = np.random.default_rng(seed)
    references = []
    for _ in range(int(rng.integers(1, 4))):
        cliques = []
        for _ in range(int(rng.integers(1, 5))):
            sketch = set(rng.integers(1, 6, size=int(rng.integers(0, 3))).tolist())
            metric = set(rng.integers(1, 6, size=int(rng.integers(0, 3))).tolist())
            cliques.append((sketch, metric))
        references.append(cliques)
    ceiling = best_one_to_one(references)
    assert ceiling.exact
    assert ceiling.mean_f1 == pytest.approx(_brute_force(references), abs=1e-12)
    assert len({a for a, _ in ceiling.pairs}) == len(ceiling.pairs) == len({b for _, b in ceiling.pairs})
    assert ceiling.f1 == tuple(score_matches(ceiling.pairs, reference).f1 for reference in references)


def test_a_search_cut_short_says_so_and_is_a_lower_bound():
    references = [[({a}, {10 + b}) for a in range(1, 6) for b in range(5) if (a + b) % 2], [({1}, {11})]]
    exact = best_one_to_one(references)
    short = best_one_to_one(references, node_budget=3)
    assert exact.exact and not short.exact
    assert short.mean_f1 <= exact.mean_f1


def test_a_map_with_more_regions_than_the_recursion_limit():
    reference = [({k}, {k}) for k in range(1, 3001)]
    ceiling = best_one_to_one([reference])
    assert ceiling.exact and ceiling.f1 == (1.0,) and len(ceiling.pairs) == 3000
