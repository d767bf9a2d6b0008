"""Leave-one-map-out cross-validation of a matching option (ursim_core.evaluation.crossval)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation.crossval import cross_validate, parse_choices, parse_option


def _run(name, f1, place=math.nan, augment="", m_label="auto", matcher="planar"):
    return SimpleNamespace(
        map=name, matcher=matcher, variant="T4", m_label=m_label, augment=augment, f1=f1, place_accuracy=place
    )


def test_each_map_is_scored_with_the_value_best_on_the_others():
    # Value 1 is best in-sample (mean .6 against .5) but loses on held-out maps.
    results = {
        0: SimpleNamespace(rows=[_run("a", 0.5, 0.5), _run("b", 0.5, 0.5), _run("c", 0.5, 0.5)]),
        1: SimpleNamespace(
            rows=[_run("a", 1.0, 1.0), _run("b", 0.4, 0.4), _run("c", 0.4, 0.4), _run("a", 0.0, m_label="0.1")]
        ),
    }
    cv = cross_validate(results, option="k")
    assert [(row[0], row[1]) for row in cv.rows] == [("a", 0), ("b", 1), ("c", 1)]
    assert cv.f1 == pytest.approx((0.5 + 0.4 + 0.4) / 3)
    assert cv.in_sample[1][0] == pytest.approx(0.6) and cv.in_sample[0][0] == pytest.approx(0.5)
    assert cv.worst[0] in ("b", "c")
    table = cv.table()
    assert "held-out F1" in table and "in-sample k=1" in table and "worst" in table


def test_orientations_are_pooled_per_map_and_reported_apart():
    rows0 = [_run(n, 0.2, 0.2, augment=a) for n in "ab" for a in ("rot0", "rot90")]
    rows1 = [_run(n, 0.9 if a == "rot0" else 0.7, 0.8, augment=a) for n in "ab" for a in ("rot0", "rot90")]
    cv = cross_validate({0: SimpleNamespace(rows=rows0), 1: SimpleNamespace(rows=rows1)}, option="k")
    assert cv.by_orientation["rot0"][0] == pytest.approx(0.9)
    assert cv.by_orientation["rot90"][0] == pytest.approx(0.7)
    assert cv.place_accuracy == pytest.approx(0.8)


def test_bad_specifications_are_parameter_errors():
    assert parse_option("orientation=upright") == ("orientation", "upright")
    assert parse_choices("mirrored=true,false") == ("mirrored", [True, False])
    for text in ("k", "k=", "=3"):
        with pytest.raises(ParameterError):
            parse_option(text)
    for text in ("k=1", "k=1,1", "k"):
        with pytest.raises(ParameterError):
            parse_choices(text)
    with pytest.raises(ParameterError, match="two or more maps"):
        cross_validate({0: SimpleNamespace(rows=[_run("a", 1)]), 1: SimpleNamespace(rows=[_run("a", 1)])}, option="k")
