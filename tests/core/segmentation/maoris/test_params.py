"""MAORIS parameters and presets (ursim_core.segmentation.maoris.params)."""

from __future__ import annotations

import pytest

from ursim_core.errors import ParameterError
from ursim_core.segmentation.maoris import PRESETS, MaorisParams

# --------------------------------------------------------------------------
# Parameters


def test_presets():
    assert PRESETS["default"] == MaorisParams()
    assert PRESETS["robot"].threshold == 0.5 and PRESETS["robot"].doors == 40
    assert PRESETS["ursim-released"] == PRESETS["robot"]
    assert PRESETS["icra"].threshold == 0.3 and PRESETS["icra"].doors == 40
    assert set(PRESETS) >= {"default", "sketch", "robot", "ursim-released", "icra"}


def test_params_round_trip_and_overrides():
    params = PRESETS["sketch"].with_overrides(margin=0.2, small_after=50)
    assert MaorisParams.from_dict(params.to_dict()) == params
    assert params.margin == 0.2 and params.small_after == 50
    assert MaorisParams.from_dict({}) == MaorisParams()


@pytest.mark.parametrize(
    "name, value",
    [
        ("threshold", 1.0),
        ("threshold", -0.1),
        ("margin", 1.5),
        ("ripples", 101),
        ("doors", -1),
        ("max_radius", 0),
        ("quantum", 0),
        ("quantum", 300),
        ("small_before", 2.5),
        ("small_after", -3),
        ("threshold", "0.3"),
        ("doors", True),
        ("threshold", float("nan")),
    ],
)
def test_invalid_parameter_values_name_the_parameter(name, value):
    with pytest.raises(ParameterError) as caught:
        MaorisParams().with_overrides(**{name: value})
    assert caught.value.field == name


def test_unknown_parameter_name_is_reported():
    with pytest.raises(ParameterError) as caught:
        MaorisParams.from_dict({"treshold": 0.3})
    assert caught.value.field == "treshold"
