"""Segmentation in a canonical pose (ursim_core.segmentation.canonical): wall angles, the pose, turned maps."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.segmentation import segment_canonical
from ursim_core.segmentation.canonical import _turned, canonical_pose, dihedral, wall_angle
from ursim_core.synth import make_pair


def _rectangle_turned(degrees: float) -> np.ndarray:
    free = np.zeros((200, 200), bool)
    free[60:140, 40:160] = True
    turned, _ = _turned(free, degrees)
    return turned


@pytest.mark.parametrize("degrees", [0, 10, 30, -20, 44])
def test_wall_angle_finds_the_turn_of_a_rectangle(degrees):
    assert wall_angle(_rectangle_turned(degrees)) == pytest.approx(degrees, abs=1.5)


def test_wall_angle_of_nothing_is_zero():
    assert wall_angle(np.zeros((10, 10), bool)) == 0.0


def test_canonical_pose_is_the_same_image_for_all_eight_transforms():
    plan, _ = make_pair(seed=3)
    reference = dihedral(plan.free, *canonical_pose(plan.free))
    for quarter_turns in range(4):
        for mirrored in (False, True):
            moved = dihedral(plan.free, quarter_turns, mirrored)
            assert np.array_equal(dihedral(moved, *canonical_pose(moved)), reference)


def test_canonical_segmentation_turns_with_the_map():
    plan, _ = make_pair(seed=2)
    upright = segment_canonical(plan.free, preset="default")
    for quarter_turns, mirrored in ((1, False), (2, True), (3, True)):
        moved = segment_canonical(dihedral(plan.free, quarter_turns, mirrored), preset="default")
        assert np.array_equal(moved.labels, dihedral(upright.labels, quarter_turns, mirrored))
