"""The template search for where a partial sketch sits on the metric map (ursim_core.matching.template)."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.matching.template import WINDOW_GAIN, best_window
from ursim_core.synth import make_pair


@pytest.fixture(scope="module")
def plan_free():
    return make_pair(seed=9)[0].free


def _box(free):
    rows, cols = np.nonzero(free)
    return rows.min(), rows.max() + 1, cols.min(), cols.max() + 1


@pytest.mark.parametrize("part", ["left", "top", "middle"])
def test_a_part_of_a_plan_is_found_where_it_was_cut_from(plan_free, part):
    r0, r1, c0, c1 = _box(plan_free)
    height, width = r1 - r0, c1 - c0
    window = {
        "left": (slice(r0, r1), slice(c0, c0 + int(width * 0.65))),
        "top": (slice(r0, r0 + int(height * 0.65)), slice(c0, c1)),
        "middle": (slice(r0 + height // 7, r1 - height // 7), slice(c0 + width // 7, c1 - width // 7)),
    }[part]
    found = best_window(plan_free[window], plan_free)
    top, left = _box(plan_free[window])[0] + window[0].start, _box(plan_free[window])[2] + window[1].start
    # Within a few coarse pixels (the map's longer side at 128 px) of where the part was cut.
    tolerance = 5 * max(plan_free.shape) / 128
    assert abs(found.top - top) <= tolerance and abs(found.left - left) <= tolerance
    part_box = _box(plan_free[window])
    assert abs(found.height - (part_box[1] - part_box[0])) < 0.15 * (part_box[1] - part_box[0])
    assert found.gain >= WINDOW_GAIN


def test_a_whole_plan_is_not_taken_for_a_part_of_itself(plan_free):
    found = best_window(plan_free, plan_free)
    assert found.gain < WINDOW_GAIN
    r0, r1, c0, c1 = _box(plan_free)
    assert found.correlation > 0.9 and abs(found.height - (r1 - r0)) < 0.1 * (r1 - r0)


def test_rescaled_part_is_found_at_the_map_scale(plan_free):
    import cv2

    r0, r1, c0, c1 = _box(plan_free)
    part = plan_free[r0:r1, c0 : c0 + (c1 - c0) * 2 // 3]
    doubled = cv2.resize(part.astype(np.uint8), (part.shape[1] * 2, part.shape[0] * 2), interpolation=cv2.INTER_NEAREST)
    found = best_window(doubled > 0, plan_free)
    assert abs(found.width - part.shape[1]) < 0.15 * part.shape[1]


def test_windows_under_a_third_of_the_map_are_not_tried(plan_free):
    from ursim_core.matching.template import WINDOW_MIN_AREA

    r0, r1, c0, c1 = _box(plan_free)
    corner = plan_free[r0 : r0 + (r1 - r0) // 2, c0 : c0 + (c1 - c0) // 2]  # a quarter of the map
    found = best_window(corner, plan_free)
    assert found.height * found.width >= WINDOW_MIN_AREA * (r1 - r0) * (c1 - c0) * 0.95
    assert best_window(corner, plan_free, min_area=0.2).height < found.height


def test_nothing_to_search_gives_none():
    free = np.zeros((50, 80), bool)
    some = free.copy()
    some[10:40, 10:70] = True
    assert best_window(free, some) is None and best_window(some, free) is None
