"""Sketches drawn from a plan (ursim_core.synth.drawing): labels kept, no distortion, options."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from ursim_core.errors import ParameterError
from ursim_core.synth import generate_floor_plan, sketchify


@pytest.mark.parametrize("seed", range(6))
def test_sketchify_keeps_place_labels_consistent(seed):
    plan = generate_floor_plan(seed=seed)
    sketch = sketchify(plan, seed=seed)
    present = set(np.unique(sketch.rooms)) - {0}
    assert len(sketch.dropped) == 1 and len(sketch.extra) == 1
    assert plan.kinds[sketch.dropped[0]] == "corridor"
    assert sketch.extra[0] not in plan.kinds
    assert present == (set(plan.kinds) - set(sketch.dropped)) | set(sketch.extra)
    assert sketch.free.dtype == bool and sketch.rooms.dtype == np.int32
    assert np.array_equal(sketch.free, sketch.rooms > 0)
    # Doors stay open and the stub is attached: the sketch is still one building.
    assert ndimage.label(sketch.free)[1] == 1
    assert len(sketch.notes) == 3


def test_sketchify_without_distortion_is_the_plan_cropped():
    plan = generate_floor_plan(seed=1)
    sketch = sketchify(
        plan,
        scale=1.0,
        scale_jitter=0.0,
        wobble=0.0,
        rotation_deg=0.0,
        pen_width=0.0,
        pen_noise=0.0,
        drop_corridor=False,
        extra_corridor=False,
    )
    rows, cols = np.nonzero(plan.free)
    window = plan.rooms[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    rows, cols = np.nonzero(sketch.free)
    assert np.array_equal(sketch.rooms[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1], window)
    assert sketch.dropped == sketch.extra == ()


def test_sketchify_can_drop_a_room_and_rejects_bad_options():
    plan = generate_floor_plan(seed=0)
    sketch = sketchify(plan, seed=0, drop_corridor=False, drop_room=True, extra_corridor=False)
    assert [plan.kinds[p] for p in sketch.dropped] == ["room"]
    assert not np.isin(sketch.dropped, sketch.rooms).any()
    with pytest.raises(ParameterError, match="pen_noise"):
        sketchify(plan, pen_width=1.0, pen_noise=2.0)
    with pytest.raises(ParameterError, match="scale_jitter"):
        sketchify(plan, scale_jitter=1.0)
