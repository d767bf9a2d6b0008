"""Regression on the 18 KTH sketches (needs ../shared/datasets and the MAORIS segmenter).

Bars, a little below what was measured (``ursim evaluate`` figures in ursim_core.matching.auto_m):
- default configuration, automatic m, correct scoring: measured 0.653 (malcolm) / 0.710
  (vasiliki), mean 0.681; asserted >= 0.62 per annotator and >= 0.65 for their mean (the bar of
  the brief).
- released options on the released pipeline, oracle m, fnfix scoring: the authors' binary gives
  0.568 / 0.562; measured 0.528 / 0.541 (pooled 0.535) with the current MAORIS port, whose
  released-parameter segmentation gives the model 6 regions as the C++ does. The brief's bar is
  0.05 of 0.565, asserted.
- the paper's method (MatchConfig.paper()) with the oracle m: measured 0.68 pooled; asserted >= 0.60.
"""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.evaluation import datasets
from ursim_core.evaluation.kth_protocol import f1_table, kth_pairs, summarise
from ursim_core.matching import M_GRID, MatchConfig

pytestmark = [pytest.mark.dataset, pytest.mark.slow]


@pytest.fixture(scope="module")
def root():
    found = datasets.dataset_root()
    if found is None:
        pytest.skip(datasets.MISSING_REASON)
    pytest.importorskip("ursim_core.segmentation.maoris", reason="MAORIS segmenter not available")
    return found


def test_default_configuration_with_automatic_m(root):
    cases = kth_pairs(root, pipeline="recommended")
    summary = summarise(f1_table(cases, MatchConfig()))
    means = [summary[annotator]["first"][0] for annotator in ("malcolm", "vasiliki")]
    assert min(means) >= 0.62, means
    assert np.mean(means) >= 0.65, means


def test_paper_method_with_oracle_m(root):
    cases = kth_pairs(root, pipeline="recommended")
    summary = summarise(f1_table(cases, MatchConfig.paper(), M_GRID))
    assert min(summary[a]["oracle"][0] for a in ("malcolm", "vasiliki")) >= 0.60


def test_released_options_reproduce_the_released_accuracy(root):
    cases = kth_pairs(root, pipeline="released")
    summary = summarise(f1_table(cases, MatchConfig.released(), M_GRID, legacy="fnfix"))
    oracle = np.mean([summary[a]["oracle"][0] for a in ("malcolm", "vasiliki")])
    assert abs(oracle - 0.565) <= 0.05, oracle
