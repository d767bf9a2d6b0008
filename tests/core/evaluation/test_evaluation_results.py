"""Summaries of an evaluation's rows (ursim_core.evaluation.results): oracle, fixed and automatic m, hand-made rows."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ursim_core.evaluation.results import (
    DEFAULT_M_GRID,
    POOLED,
    EvaluationResult,
    RunRow,
    m_label,
    mean_f1_by_m,
    summarise,
    summarise_human,
)


def _row(name, m, f1, *, annotator="malcolm", matcher="planar", variant="T4", precision=None, recall=None, auto_m=0.05):
    label = "auto" if m == "auto" else m_label(m)
    value = auto_m if m == "auto" else float(m)
    return RunRow(
        map=name,
        annotator=annotator,
        matcher=matcher,
        variant=variant,
        m_label=label,
        m_value=value,
        tp=0,
        fp=0,
        fn=0,
        precision=f1 if precision is None else precision,
        recall=f1 if recall is None else recall,
        f1=f1,
        seeds=0,
        n_sketch_regions=3,
        n_metric_regions=3,
        time_s=0.0,
    )


# --------------------------------------------------------------------------- summaries


# F1 per map (rows) and m (columns 0, 0.1, 0.2), with the automatic m's F1.
TABLE = {
    "00": ((0.0, 0.5, 0.5), 0.5),
    "01": ((0.2, 0.2, 0.9), 0.2),
    "02": ((0.0, 0.8, 0.4), 0.8),
}


def _table_rows(annotator="malcolm", table=TABLE, **kwargs):
    rows = []
    for name, (per_m, auto_f1) in table.items():
        rows += [_row(name, m, f1, annotator=annotator, **kwargs) for m, f1 in zip((0.0, 0.1, 0.2), per_m)]
        rows.append(_row(name, "auto", auto_f1, annotator=annotator, **kwargs))
    return rows


def _by_choice(summaries, annotator="malcolm"):
    return {s.choice: s for s in summaries if s.annotator == annotator}


def test_oracle_takes_the_best_m_of_each_map_and_the_smallest_m_on_ties():
    oracle = _by_choice(summarise(_table_rows()))["oracle"]
    assert oracle.maps == ("00", "01", "02")
    assert oracle.f1 == (0.5, 0.9, 0.8)
    assert oracle.m_values == (0.1, 0.2, 0.1)  # map 00 ties at 0.1 and 0.2: the smaller wins
    assert oracle.median == pytest.approx(0.8)
    assert oracle.mean == pytest.approx(2.2 / 3)
    assert oracle.sd == pytest.approx(np.std([0.5, 0.9, 0.8], ddof=1))


def test_fixed_m_is_the_single_m_with_the_best_mean():
    # Means over maps: m=0: 0.067, m=0.1: 0.5, m=0.2: 0.6.
    fixed = _by_choice(summarise(_table_rows()))["fixed"]
    assert fixed.fixed_m == "0.2"
    assert fixed.f1 == (0.5, 0.9, 0.4)
    assert fixed.mean == pytest.approx(0.6)
    assert fixed.median == pytest.approx(0.5)


def test_fixed_m_ties_pick_the_smallest_m():
    table = {"00": ((0.3, 0.6, 0.6), 0.0), "01": ((0.3, 0.6, 0.6), 0.0)}
    assert _by_choice(summarise(_table_rows(table=table)))["fixed"].fixed_m == "0.1"


def test_auto_uses_the_auto_rows_and_their_m():
    auto = _by_choice(summarise(_table_rows()))["auto"]
    assert auto.f1 == (0.5, 0.2, 0.8)
    assert auto.m_values == (0.05, 0.05, 0.05)
    assert auto.mean == pytest.approx(0.5)


def test_precision_and_recall_follow_the_chosen_rows():
    rows = [_row("00", 0.0, 0.0, precision=0.0, recall=0.0), _row("00", 0.1, 0.8, precision=1.0, recall=2 / 3)]
    oracle = _by_choice(summarise(rows))["oracle"]
    assert oracle.mean_precision == 1.0 and oracle.mean_recall == pytest.approx(2 / 3)


def test_annotators_are_summarised_apart_and_pooled():
    vasiliki_table = {name: (tuple(1.0 - f for f in per_m), 1.0 - auto) for name, (per_m, auto) in TABLE.items()}
    rows = _table_rows("malcolm") + _table_rows("vasiliki", table=vasiliki_table)
    summaries = summarise(rows)
    assert list(dict.fromkeys(s.annotator for s in summaries)) == ["malcolm", "vasiliki", POOLED]
    vasiliki_oracle = _by_choice(summaries, "vasiliki")["oracle"]
    assert vasiliki_oracle.f1 == (1.0, 0.8, 1.0)
    pooled = _by_choice(summaries, POOLED)
    assert pooled["oracle"].n == 6
    assert pooled["oracle"].maps[:2] == ("00/malcolm", "01/malcolm")
    # Pooled means per m: 0: 0.5, 0.1: 0.5, 0.2: 0.5 -> tie, smallest m.
    assert pooled["fixed"].fixed_m == "0"
    assert summarise(rows, pool=False)[-1].annotator == "vasiliki"


def test_methods_are_ordered_like_the_paper_table_and_human_rows_ignored():
    rows = (
        _table_rows(matcher="vf2", variant="T1")
        + _table_rows(matcher="planar", variant="T4")
        + _table_rows(matcher="planar", variant="baseline")
        + [RunRow("00", "malcolm", "human", "vasiliki", "-", math.nan, 1, 0, 0, 1.0, 1.0, 1.0, 0, 3, 3, 0.0)]
    )
    order = list(dict.fromkeys((s.matcher, s.variant) for s in summarise(rows)))
    assert order == [("planar", "baseline"), ("planar", "T4"), ("vf2", "T1")]


def test_m_grid_restricts_the_oracle_and_the_fixed_choice():
    summaries = summarise(_table_rows(), m_grid=(0.0, 0.1))
    assert _by_choice(summaries)["oracle"].f1 == (0.5, 0.2, 0.8)
    assert _by_choice(summaries)["fixed"].fixed_m == "0.1"


def test_single_map_has_no_sd():
    oracle = _by_choice(summarise([_row("00", 0.1, 0.4)]))["oracle"]
    assert oracle.mean == 0.4 and oracle.median == 0.4 and math.isnan(oracle.sd)


def test_human_summaries_per_direction():
    rows = [
        RunRow(name, reference, "human", scored, "-", math.nan, 1, 0, 0, 1.0, 1.0, f1, 0, 3, 3, 0.0)
        for name, reference, scored, f1 in (("00", "a", "b", 1.0), ("01", "a", "b", 0.6), ("00", "b", "a", 0.5))
    ]
    summaries = {(s.annotator, s.variant): s for s in summarise_human(rows)}
    assert summaries[("a", "b")].mean == pytest.approx(0.8)
    assert summaries[("b", "a")].f1 == (0.5,)


def test_mean_f1_by_m_leaves_auto_out():
    result = mean_f1_by_m(_table_rows())
    assert list(result) == [("malcolm", "planar", "T4")]
    assert [(label, round(mean, 4), n) for _, label, mean, n in result[("malcolm", "planar", "T4")]] == [
        ("0", round(0.2 / 3, 4), 3),
        ("0.1", 0.5, 3),
        ("0.2", 0.6, 3),
    ]


def test_m_labels_and_default_grid():
    assert [m_label(m) for m in DEFAULT_M_GRID[:4]] == ["0", "0.025", "0.05", "0.075"]
    assert len(DEFAULT_M_GRID) == 20 and m_label(DEFAULT_M_GRID[-1]) == "0.475"


def test_result_summary_lookup():
    result = EvaluationResult(rows=tuple(_table_rows()))
    assert result.summary("malcolm", "planar", "T4", "fixed").fixed_m == "0.2"
    assert result.summary("malcolm", "hungarian", "T4", "fixed") is None
    assert result.annotators == ("malcolm",)
