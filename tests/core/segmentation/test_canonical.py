"""Segmentation in a canonical pose (ursim_core.segmentation.canonical): wall angles, the pose, turned maps."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.segmentation import (
    load_label_image,
    resolve_params,
    save_label_image,
    segment,
    segment_canonical,
    with_resamplings,
)
from ursim_core.segmentation.canonical import (
    RESAMPLING_OFFSETS,
    _renumber,
    _turned,
    _voted_angle,
    canonical_labels,
    canonical_pose,
    dihedral,
    smoothed_turn,
    turned_back,
    wall_angle,
)
from ursim_core.synth import make_pair


def _rectangle_turned(degrees: float) -> np.ndarray:
    free = np.zeros((200, 200), bool)
    free[60:140, 40:160] = True
    turned, _ = _turned(free, degrees)
    return turned


@pytest.mark.parametrize("degrees", [0, 10, 30, -20, 44])
def test_wall_angle_finds_the_turn_of_a_rectangle(degrees):
    assert wall_angle(_rectangle_turned(degrees)) == pytest.approx(degrees, abs=1.5)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_wall_angle_is_exactly_the_same_for_every_quarter_turn_and_negated_for_a_mirror_image(seed):
    # Exactly: a map 3.04 degrees off its axes and its mirror image (traced alone, 3.04 and -3.02)
    # were resampled by different turns and could come out with different regions.
    free = make_pair(seed=seed)[1].free
    angle = wall_angle(free)
    for quarter_turns in range(4):
        for mirrored in (False, True):
            assert wall_angle(dihedral(free, quarter_turns, mirrored)) == (-angle if mirrored else angle)


def _angle_of_the_whole_image(free) -> float:
    image = np.ascontiguousarray(np.asarray(free) != 0, dtype=np.uint8)
    _voted_angle.cache_clear()
    return _voted_angle(image.tobytes(), image.shape)


def test_wall_angle_traced_in_the_free_space_box_is_the_whole_image_s():
    # wall_angle traces the box around the free space (a pixel of margin where there is one):
    # the same angle, bit for bit, as tracing the whole image, also for free space on the
    # image's edges (which OpenCV reads as walls) and for the padded image of a turned map.
    plan, sketch = make_pair(seed=3)
    turned, _ = _turned(sketch.free, 33.0)
    maps = [plan.free, sketch.free, turned, sketch.free[:250, 30:], np.pad(plan.free, ((7, 0), (0, 40)))]
    rng = np.random.default_rng(41)
    maps += [rng.random(tuple(rng.integers(1, 40, 2))) < rng.random() for _ in range(200)]
    for free in maps:
        expected = _angle_of_the_whole_image(free)
        _voted_angle.cache_clear()
        assert wall_angle(free) == expected


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


def _plan_turned(degrees: float) -> np.ndarray:
    plan, _ = make_pair(seed=2)
    turned, _ = _turned(plan.free, degrees)
    return turned


def test_a_map_on_its_axes_has_no_other_resampling():
    plan, _ = make_pair(seed=2)
    assert not turned_back(plan.free)
    assert segment_canonical(plan.free, preset="default", resampled=True).resampled == ()


def test_a_turned_map_is_also_segmented_in_its_other_resamplings():
    free = _plan_turned(25.0)
    assert turned_back(free)
    seg = segment_canonical(free, preset="default", resampled=True)
    assert np.array_equal(seg.labels, segment_canonical(free, preset="default").labels)
    offsets = [other.params["canonical_turn_offset"] for other in seg.resampled]
    assert offsets == [None, *RESAMPLING_OFFSETS]
    for other in seg.resampled:
        assert other.labels.shape == free.shape and other.n_regions > 0
        assert other.resampled == ()
        # Each records what made it: segment() with its parameters gives it again.
        again = segment(free, method=other.method, params=other.params)
        assert np.array_equal(again.labels, other.labels)
    # Turned by other angles, the resampled map's regions differ somewhere.
    assert any(not np.array_equal(other.labels, seg.labels) for other in seg.resampled)


def test_a_reloaded_label_image_gets_its_resamplings_again(tmp_path):
    free = _plan_turned(25.0)
    seg = segment_canonical(free, preset="default", resampled=True)
    save_label_image(seg, tmp_path / "labels.png")
    reloaded = load_label_image(tmp_path / "labels.png", shape=free.shape)
    assert reloaded.resampled == ()
    again = with_resamplings(reloaded, free, method=seg.method, params=seg.params)
    # The reloaded labels stay the answer's frame; the others are the ones segment_canonical made.
    assert np.array_equal(again.labels, reloaded.labels) and again.source == reloaded.source
    assert [o.params for o in again.resampled] == [o.params for o in seg.resampled]
    assert all(np.array_equal(a.labels, b.labels) for a, b in zip(again.resampled, seg.resampled, strict=True))


def test_resamplings_are_made_only_for_a_canonical_segmentation_of_a_turned_map():
    free = _plan_turned(25.0)
    plain = segment(free, preset="default")
    assert with_resamplings(plain, free, method="maoris", params=plain.params) is plain  # not canonical
    canonical = segment_canonical(free, preset="default", resampled=True)
    assert with_resamplings(canonical, free, method="maoris", params=canonical.params) is canonical  # has them
    one = canonical.resampled[0]  # itself one of the resamplings
    assert with_resamplings(one, free, method="maoris", params=one.params) is one


@pytest.mark.parametrize("cpus", [1, 2, 8])
def test_the_resamplings_made_on_threads_are_those_made_one_after_the_other(monkeypatch, cpus):
    import threading

    from ursim_core.segmentation import interface

    free = _plan_turned(25.0)
    base = segment_canonical(free, preset="default")
    threads = set()
    original = interface.segment

    def recorded(*args, **kwargs):
        threads.add(threading.current_thread().name)
        return original(*args, **kwargs)

    monkeypatch.setattr(interface, "segment", recorded)
    monkeypatch.setattr(interface, "usable_cpus", lambda: cpus)
    made = with_resamplings(base, free, method="maoris", params=base.params)
    assert [o.params["canonical_turn_offset"] for o in made.resampled] == [None, *RESAMPLING_OFFSETS]
    for other in made.resampled:
        assert np.array_equal(other.labels, original(free, method="maoris", params=other.params).labels)
    on_pool = {name for name in threads if name.startswith("ursim-resampling")}
    assert bool(on_pool) == (cpus > 1) and len(on_pool) <= min(cpus, len(RESAMPLING_OFFSETS))


def test_the_resampled_segmentations_survive_pickling():
    seg = segment_canonical(_plan_turned(25.0), preset="default", resampled=True)
    copy = pickle.loads(pickle.dumps(seg))
    assert [o.params for o in copy.resampled] == [o.params for o in seg.resampled]
    assert all(np.array_equal(a.labels, b.labels) for a, b in zip(copy.resampled, seg.resampled, strict=True))


@pytest.mark.parametrize(
    "params, field",
    [
        ({"canonical_turn_offset": 1.0}, "canonical_turn_offset"),
        ({"canonical": True, "canonical_turn_offset": "x"}, "canonical_turn_offset"),
    ],
)
def test_a_turn_offset_needs_a_number_and_the_canonical_pose(params, field):
    with pytest.raises(ParameterError) as error:
        resolve_params("maoris", "default", params)
    assert error.value.field == field


def _rooms(scale: int) -> np.ndarray:
    """Two rooms and a corridor, every length times ``scale``, and a one-pixel spur on a wall."""
    free = np.zeros((60 * scale, 100 * scale), bool)
    free[5 * scale : 55 * scale, 5 * scale : 45 * scale] = True
    free[10 * scale : 50 * scale, 60 * scale : 95 * scale] = True
    free[25 * scale : 35 * scale, 45 * scale : 60 * scale] = True
    free[30 * scale, 95 * scale : 98 * scale] = True
    return free


def test_the_smoothing_of_a_turned_map_follows_the_size_of_its_rooms():
    from scipy import ndimage

    changed = {}
    for scale in (2, 4, 8, 16):
        free = _rooms(scale)
        smoothed = smoothed_turn(free)
        assert not smoothed[30 * scale, 95 * scale + 1 : 98 * scale].any(), scale  # the spur goes
        assert ndimage.label(smoothed)[1] == 1  # the rooms and the corridor stay one piece
        changed[scale] = (free ^ smoothed).sum() / free.sum()
        assert changed[scale] < 0.01
    # The side is a share of the rooms' size: the corners are rounded alike at every scale (a
    # fixed side would change a quarter of the share at four times the scale).
    assert changed[16] > 0.5 * changed[4]
    # A map whose rooms are a few pixels across is left as it is (no filter below 3 px).
    assert np.array_equal(smoothed_turn(_rooms(1)), _rooms(1))
    assert not smoothed_turn(np.zeros((20, 20), bool)).any()


def test_a_turned_map_is_smoothed_once_on_its_axes_before_it_is_segmented():
    free = _plan_turned(25.0)
    seen = []

    def record(image):
        seen.append(image.copy())
        return image.astype(np.int32)

    canonical_labels(free, record)
    turned, _ = _turned(free, -wall_angle(free))
    expected = smoothed_turn(turned)
    assert not np.array_equal(expected, turned)  # the filter does something on this map
    assert np.array_equal(seen[0], dihedral(expected, *canonical_pose(expected)))
    # A map on its axes is not resampled, and so not smoothed either.
    plan, _ = make_pair(seed=2)
    seen.clear()
    canonical_labels(plan.free, record)
    assert np.array_equal(seen[0], dihedral(plan.free, *canonical_pose(plan.free)))


@pytest.mark.parametrize("seed", range(4))
def test_renumbering_keeps_the_order_of_the_ids_and_zero(seed):
    # The table by id gives what the sort of every pixel gave (numpy.unique), zero present or not.
    rng = np.random.default_rng(seed)
    for low in (0, 1):
        labels = rng.choice(rng.integers(low, 5000, 40), size=(37, 53)).astype(np.int32)
        ids, inverse = np.unique(labels, return_inverse=True)
        expected = (np.arange(ids.size) + (0 if ids[0] == 0 else 1))[inverse].reshape(labels.shape)
        renumbered = _renumber(labels)
        assert renumbered.dtype == np.int32
        assert np.array_equal(renumbered, expected)


def test_renumbering_in_a_window_is_renumbering_the_whole_image():
    rng = np.random.default_rng(7)
    for zero_inside in (False, True):
        labels = np.zeros((60, 70), np.int32)
        labels[12:40, 9:51] = rng.choice(rng.integers(1 - zero_inside, 900, 12), size=(28, 42))
        window = (slice(12, 40), slice(9, 51))
        assert np.array_equal(_renumber(labels.copy(), window), _renumber(labels))
    whole = (slice(0, 60), slice(0, 70))  # the window is the image: 0 is there only if a label is 0
    labels = rng.integers(3, 9, (60, 70)).astype(np.int32)
    assert np.array_equal(_renumber(labels.copy(), whole), _renumber(labels))
    assert _renumber(labels.copy(), whole).min() == 1


def _maoris_default(free):
    from ursim_core.segmentation.maoris import PRESETS, maoris_labels

    return maoris_labels(free, PRESETS["default"])


@pytest.mark.parametrize("degrees", [0.0, 17.0, 30.0, 134.0])
def test_maoris_given_only_the_free_box_labels_as_on_the_whole_canvas(degrees):
    # The canonical image's canvas is mostly empty; MAORIS works on the box of its free pixels
    # and a pixel around it, so it is given only that: the same labels, bit for bit, for every
    # resampling, for free space on the image's edges, mirrored, and for a map with none.
    _, sketch = make_pair(seed=5)
    free = sketch.free if degrees == 0 else _turned(sketch.free, degrees)[0]
    maps = [free, free[:, ::-1], free[40:, : free.shape[1] - 35], np.zeros((30, 40), bool)]
    for image in maps:
        for offset in (0.0, None, *RESAMPLING_OFFSETS[:2]):
            _voted_angle.cache_clear()
            expected = canonical_labels(image, _maoris_default, turn_offset=offset)
            got = canonical_labels(image, _maoris_default, turn_offset=offset, free_box_only=True)
            assert got.dtype == expected.dtype == np.int32
            assert np.array_equal(got, expected), (degrees, offset, image.shape)


def test_the_pose_from_the_free_box_is_the_pose_from_the_whole_image():
    from ursim_core.segmentation.canonical import _moments, free_window

    rng = np.random.default_rng(3)
    for _ in range(50):
        free = np.zeros(tuple(rng.integers(20, 90, 2)), bool)
        rows, cols = free.shape
        free[rng.integers(0, rows // 2) : rng.integers(rows // 2, rows + 1), rng.integers(0, cols // 2) : cols] = True
        free &= rng.random(free.shape) < 0.8
        window = free_window(free, int(rng.integers(0, 3)))
        assert _moments(free, window) == _moments(free)  # bit for bit
        assert canonical_pose(free, window=window) == canonical_pose(free)
