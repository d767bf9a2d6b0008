"""Segmentation jobs and their caches (ursim_core.evaluation.cache): the resampled segmentations kept."""

from __future__ import annotations

import cv2
import numpy as np

from ursim_core.evaluation.cache import SegmentationJob, read_cached, segment_job, store_segmentation
from ursim_core.segmentation.canonical import RESAMPLING_OFFSETS, _turned
from ursim_core.synth import make_pair

LOAD = {"threshold": 250, "nonzero_free": False}


def _turned_sketch(folder):
    _, sketch = make_pair(seed=2)
    turned, _ = _turned(sketch.free, 20.0)
    path = folder / "turned.png"
    cv2.imwrite(str(path), turned.astype(np.uint8) * 255)
    return path


def test_a_resampled_job_keeps_its_other_segmentations_on_disk(tmp_path):
    path = _turned_sketch(tmp_path)
    job = SegmentationJob.of(path, "default", LOAD, {}, canonical=True, resampled=True)
    plain = SegmentationJob.of(path, "default", LOAD, {}, canonical=True)
    assert job.key != plain.key and not SegmentationJob.of(path, "default", LOAD, {}, resampled=True).resampled
    segmentation = segment_job(job)
    assert len(segmentation.resampled) == len(RESAMPLING_OFFSETS) + 1 and segment_job(plain).resampled == ()
    store_segmentation(job, segmentation, None, tmp_path / "cache")
    found = read_cached(job, {}, tmp_path / "cache")
    assert np.array_equal(found.labels, segmentation.labels) and found.params["canonical"] is True
    assert [o.params["canonical_turn_offset"] for o in found.resampled] == [
        o.params["canonical_turn_offset"] for o in segmentation.resampled
    ]
    for stored, computed in zip(found.resampled, segmentation.resampled, strict=True):
        assert np.array_equal(stored.labels, computed.labels)
    # The job without the other resamplings has a cache file of its own.
    assert read_cached(plain, {}, tmp_path / "cache") is None
