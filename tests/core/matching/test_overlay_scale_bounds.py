"""The overlay matcher's scale bound (ursim_core.matching.overlay): a scale that lays the input far
longer than the metric map is refused by name, and no OpenCV call gets a size it cannot take."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.matching import MatchConfig
from ursim_core.matching.overlay import MAX_EXTENT, SCALE_SPREAD, _best_placement, _Side, ranked_overlays


def _rooms(rows: int = 60, cols: int = 90) -> np.ndarray:
    free = np.zeros((rows, cols), bool)
    free[5 : rows - 5, 5 : cols // 2] = True
    free[rows // 2 - 5 : rows // 2 + 5, cols // 2 : cols - 5] = True
    return free


def _extent(free: np.ndarray) -> int:
    rows, cols = np.flatnonzero(free.any(axis=1)), np.flatnonzero(free.any(axis=0))
    return max(rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1)


@pytest.mark.parametrize("scale", [100.0, 1e6, 1e308])
def test_a_scale_laying_the_input_far_longer_than_the_metric_map_is_refused(scale):
    free = _rooms()
    with pytest.raises(ParameterError, match="scale") as raised:
        ranked_overlays(free, free, orientations=[(0.0, False)], scale=scale)
    message = str(raised.value)
    assert "\n" not in message and "90 x 60 px" in message and f"at most {MAX_EXTENT:g} times" in message


def test_the_largest_scale_within_the_bound_is_still_searched():
    free = _rooms()
    # The longest input the bound allows, at the largest spread searched around the scale.
    scale = MAX_EXTENT * max(free.shape) / (_extent(free) * max(SCALE_SPREAD))
    assert ranked_overlays(free, free, orientations=[(0.0, False)], scale=scale * 0.999)
    with pytest.raises(ParameterError):
        ranked_overlays(free, free, orientations=[(0.0, False)], scale=scale * 1.01)


def test_a_placement_too_large_for_opencv_is_skipped_not_attempted():
    # What an estimated scale meets (no refusal there): the template would be 1e12 px long.
    sketch, metric = _Side(_rooms()), _Side(_rooms())
    assert _best_placement(sketch, metric, np.eye(2) * 1e10) is None
    assert _best_placement(sketch, metric, np.eye(2) * 1e300) is None
    assert _best_placement(sketch, metric, np.eye(2)) is not None


def test_an_input_far_larger_than_the_metric_map_of_unknown_scale_gives_no_placement_quickly():
    big = _rooms(600, 900)
    small = _rooms(12, 18)
    assert ranked_overlays(big, small, orientations=[(0.0, False)]) == []


def test_resolutions_whose_ratio_is_no_number_are_named():
    with pytest.raises(ParameterError, match=r"resolutions \(1e-300 and 1e\+300 m/px\)"):
        MatchConfig().with_resolutions(1e-300, 1e300)
    with pytest.raises(ParameterError, match="resolutions"):
        MatchConfig().with_resolutions(1e300, 1e-300)
    assert MatchConfig().with_resolutions(0.1, 0.05).scale == 2.0
