"""The sketch orientation model: the readings a match ranked, from a result or a file's record."""

from __future__ import annotations

import pytest

from ursim_gui.model.orientation import SketchOrientation


def _record(**extra) -> dict:
    return {"config": {"orientation": "any"}, "orientation": {"degrees": 90.0, "mirrored": False}, **extra}


def _reading(degrees: float, mirrored: bool, gap: float) -> dict:
    return {"degrees": degrees, "mirrored": mirrored, "ranked_worse_by": gap}


def test_the_readings_of_a_file_are_its_ranked_list():
    record = _record(readings=[_reading(90.0, False, 0.0), _reading(270.0, True, 0.01), _reading(0.0, False, 0.4)])
    readings = SketchOrientation.readings_in(record=record)
    assert readings == [
        (SketchOrientation(90.0, False), 0.0),
        (SketchOrientation(270.0, True), 0.01),
        (SketchOrientation(0.0, False), 0.4),
    ]


def test_a_file_written_before_the_ranked_list_offers_its_reading_and_runner_up():
    record = _record(next_reading=_reading(270.0, True, 0.01))
    assert SketchOrientation.readings_in(record=record) == [
        (SketchOrientation(90.0, False), 0.0),
        (SketchOrientation(270.0, True), 0.01),
    ]


@pytest.mark.parametrize(
    "readings",
    [
        "upright",  # not a list
        [_reading(90.0, False, 0.0)],  # one reading: nothing to compare
        [_reading(90.0, False, 0.0), {"degrees": 270.0}],  # an entry without its gap
        [_reading(90.0, False, 0.0), _reading(270.0, "yes", 0.01)],  # mirrored not a bool
        [_reading(90.0, False, 0.0), _reading(float("nan"), False, 0.01)],
        [_reading(180.0, False, 0.0), _reading(270.0, True, 0.01)],  # not led by the reading read
    ],
)
def test_a_ranked_list_a_person_or_another_tool_spoilt_falls_back_to_the_runner_up(readings):
    record = _record(readings=readings, next_reading=_reading(0.0, True, 0.2))
    assert SketchOrientation.readings_in(record=record) == [
        (SketchOrientation(90.0, False), 0.0),
        (SketchOrientation(0.0, True), 0.2),
    ]


def test_no_readings_when_the_matcher_was_told_the_orientation_or_ranked_one():
    told = {**_record(readings=[_reading(90.0, False, 0.0), _reading(270.0, True, 0.01)])}
    told["config"] = {"orientation": 90.0}
    assert SketchOrientation.readings_in(record=told) == []
    assert SketchOrientation.readings_in(record=_record()) == []
    assert SketchOrientation.readings_in(record={"matcher": "hand"}) == []
    assert SketchOrientation.readings_in() == []


def test_the_reading_an_answer_was_laid_in_is_told_or_chosen():
    from types import SimpleNamespace as Result

    told = Result(config=Result(orientation=180.0), orientation=(180.0, True), orientation_scan={})
    assert SketchOrientation.laid_in(told) == SketchOrientation(180.0, True)
    assert SketchOrientation.found_in(told) is None  # told: not a reading the matcher chose
    assert SketchOrientation.laid_in(record=_record()) == SketchOrientation(90.0, False)
    assert SketchOrientation.laid_in(record={"orientation": {"degrees": 90.0, "mirrored": 1}}) is None
