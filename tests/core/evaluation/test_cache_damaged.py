"""A damaged or foreign disk-cache file (ursim_core.evaluation.cache) is only a cache miss, and a
``--cache`` that names a file is an error."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.evaluation.cache import (
    SegmentationJob,
    _disk_cache_path,
    check_cache_dir,
    read_cached,
    segment_all,
    segment_job,
    store_segmentation,
)
from ursim_core.evaluation.pool import Progress

LOAD = {"threshold": 250, "nonzero_free": False}


@pytest.fixture
def stored(tmp_path):
    image = np.zeros((60, 90), np.uint8)
    image[5:55, 5:40] = 255
    image[5:55, 45:85] = 255
    image[28:32, 40:45] = 255
    path = tmp_path / "map.png"
    cv2.imwrite(str(path), image)
    job = SegmentationJob.of(path, "default", LOAD, {})
    segmentation = segment_job(job)
    cache = tmp_path / "cache"
    store_segmentation(job, segmentation, None, cache)
    return job, segmentation, cache, _disk_cache_path(cache, job)


def _rewrite(file, **changes):
    with np.load(file) as stored:
        arrays = dict(stored)
    arrays.update(changes)
    np.savez_compressed(file, **arrays)


def test_a_good_cache_file_is_read(stored):
    job, segmentation, cache, _ = stored
    assert np.array_equal(read_cached(job, None, cache).labels, segmentation.labels)


def test_a_cut_cache_file_is_a_miss(stored):
    job, _, cache, file = stored
    file.write_bytes(file.read_bytes()[: file.stat().st_size // 2])
    assert read_cached(job, None, cache) is None


def test_a_cache_file_of_garbage_is_a_miss(stored):
    job, _, cache, file = stored
    file.write_bytes(b"PK\x03\x04" + bytes(200))
    assert read_cached(job, None, cache) is None


@pytest.mark.parametrize(
    "labels",
    [
        lambda labels: labels.ravel(),
        lambda labels: labels[:-5, :-3],
        lambda labels: labels.T,
        lambda labels: labels.astype(float),
        lambda labels: labels - 10,
    ],
    ids=["1-D", "smaller", "transposed", "float", "negative"],
)
def test_labels_that_are_not_the_maps_are_a_miss(stored, labels):
    job, segmentation, cache, file = stored
    _rewrite(file, labels=labels(segmentation.labels))
    assert read_cached(job, None, cache) is None


def test_another_maps_file_under_this_name_is_a_miss(stored):
    job, _, cache, file = stored
    _rewrite(file, map_sha256=np.array("0" * 64))
    assert read_cached(job, None, cache) is None
    _rewrite(file, map_sha256=np.array(job.digest), map_shape=np.array(5))
    assert read_cached(job, None, cache) is None


def test_a_miss_is_segmented_again_and_written_over(stored):
    job, segmentation, cache, file = stored
    _rewrite(file, labels=segmentation.labels.ravel())
    found, cached = segment_all([job], 1, Progress(None, 1), None, cache)
    assert cached == 0 and np.array_equal(found[job.key].labels, segmentation.labels)
    assert np.array_equal(read_cached(job, None, cache).labels, segmentation.labels)


def test_a_cache_that_names_a_file_is_an_error(tmp_path, stored):
    job = stored[0]
    a_file = tmp_path / "cache.txt"
    a_file.write_text("not a folder")
    for where in (a_file, a_file / "below"):
        with pytest.raises(ParameterError, match="must be a folder"):
            check_cache_dir(where)
        with pytest.raises(ParameterError, match="must be a folder"):
            segment_all([job], 1, Progress(None, 1), None, where)
    check_cache_dir(tmp_path / "new" / "folder")
