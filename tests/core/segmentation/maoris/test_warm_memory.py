"""Warming the zone graph's memory on a second thread (ursim_core.segmentation.maoris.warm_memory)."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.segmentation.maoris import PRESETS, maoris_labels
from ursim_core.segmentation.maoris import warm_memory as warm_module
from ursim_core.synth import make_large_building


@pytest.mark.parametrize("shape", [(1, 1), (1, 5), (6, 1), (513, 7), (1025, 300), (3, 1030)])
def test_border_length_counts_every_side_between_free_and_obstacle_once(shape):
    free = np.random.default_rng(sum(shape)).random(shape) < 0.5
    want = np.count_nonzero(free[:, 1:] != free[:, :-1]) + np.count_nonzero(free[1:] != free[:-1])
    for rows in (1, 2, 512):
        assert warm_module.border_length(free, rows=rows) == want


def test_the_block_follows_the_border_and_is_capped_per_pixel():
    room = np.zeros((3000, 3000), bool)
    room[10:-10, 10:-10] = True  # smooth walls: few flat zones, a small block
    border = warm_module.border_length(room)
    assert warm_module.warm_bytes(room) == warm_module.BYTES_PER_ZONE * warm_module.ZONES_PER_BORDER * border
    speckled = np.random.default_rng(1).random((3000, 3000)) < 0.9
    assert warm_module.warm_bytes(speckled) == warm_module.BYTES_PER_PIXEL * speckled.size


def test_small_maps_warm_nothing_and_large_ones_touch_every_page_of_their_block():
    side = int(np.ceil(np.sqrt(warm_module.WARM_MIN_PIXELS)))
    assert warm_module.warm_memory(np.ones((side - 1, side - 1), bool)) is None
    free = make_large_building(side, seed=3).free
    warming = warm_module.warm_memory(free)
    warming._thread.join()
    assert warming.block.size == warm_module.warm_bytes(free) > 0
    assert (warming.block[:: warm_module.mmap.PAGESIZE] == 1).all()
    assert warming.touched == warming.block.size
    warming.release()
    assert warming.block is None and not warming._thread.is_alive()


def test_a_release_stops_the_touching_at_the_next_chunk(monkeypatch):
    import time

    made = []

    def slow_to_size(free):  # the touching starts only once the release has asked it to stop
        while not made:
            time.sleep(0.001)
        made[0]._stop.wait()
        return 64 * warm_module.CHUNK_BYTES

    monkeypatch.setattr(warm_module, "warm_bytes", slow_to_size)
    made.append(warm_module.Warming(np.ones((50, 50), bool)))
    made[0].release()
    assert made[0].touched == 0 and made[0].block is None and not made[0]._thread.is_alive()


def test_a_block_that_cannot_be_had_leaves_nothing_warmed(monkeypatch):
    def no_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(warm_module.np, "empty", no_memory)
    warming = warm_module.Warming(np.ones((50, 50), bool))
    warming.release()
    assert warming.block is None


def test_segmentations_are_the_same_with_and_without_warming(monkeypatch):
    free = make_large_building(600, seed=2).free
    unwarmed = maoris_labels(free, PRESETS["robot"])
    warming_class, started = warm_module.Warming, []

    def recorded(mask):
        started.append(warming_class(mask))
        return started[-1]

    monkeypatch.setattr(warm_module, "WARM_MIN_PIXELS", 0)
    monkeypatch.setattr(warm_module, "Warming", recorded)
    np.testing.assert_array_equal(maoris_labels(free, PRESETS["robot"]), unwarmed)
    assert len(started) == 1, "the segmentation did not warm memory"
    assert started[0].block is None and not started[0]._thread.is_alive(), "the block was not released"
