"""The resamplings kept packed in the evaluation (ursim_core.evaluation.packing) come back identical."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.evaluation import cache as evaluation_cache
from ursim_core.evaluation import packing
from ursim_core.evaluation.cache import SegmentationJob, read_cached, segment_all
from ursim_core.evaluation.packing import Packed, pack_labels, packed_apart, unpack_labels, with_unpacked
from ursim_core.evaluation.pool import Progress
from ursim_core.evaluation.runner import run_evaluation
from ursim_core.segmentation import segment_canonical
from ursim_core.segmentation.canonical import _turned
from ursim_core.synth import make_pair


@pytest.mark.parametrize(
    "labels",
    [
        np.zeros((0, 5), np.int32),
        np.array([[7]], np.int32),
        np.array([[1, 1, 2], [2, 2, 2]], np.uint16),
        np.random.default_rng(0).integers(0, 4, (37, 53)).astype(np.int32),
        np.repeat(np.arange(-3, 2**31 - 1, 2**27, dtype=np.int64), 4).reshape(4, -1),
    ],
)
def test_labels_come_back_identical(labels):
    packed = pack_labels(labels)
    again = unpack_labels(packed)
    assert again.dtype == labels.dtype and again.shape == labels.shape and np.array_equal(again, labels)


def test_a_label_image_packs_to_its_runs():
    labels = np.zeros((400, 600), np.int32)
    labels[50:350, 20:300] = 1
    labels[50:350, 320:580] = 2
    packed = pack_labels(labels)
    assert len(packed.starts) == 1 + 4 * 300 and packed.nbytes < labels.nbytes / 50


@pytest.fixture(scope="module")
def turned_sketch():
    turned, _ = _turned(make_pair(seed=5)[1].free, 25.0)
    return segment_canonical(turned, preset="default", resampled=True)


def test_the_resamplings_come_back_as_they_were(turned_sketch):
    alone, packed = packed_apart(turned_sketch)
    # The first segmentation is packed too, and reads as it was.
    assert alone.resampled == () and alone.packed_labels.nbytes < turned_sketch.labels.nbytes / 10
    assert np.array_equal(alone.labels, turned_sketch.labels) and alone.labels.dtype == turned_sketch.labels.dtype
    assert alone.n_regions == turned_sketch.n_regions and alone.regions is turned_sketch.regions
    assert packed.nbytes < sum(o.labels.nbytes for o in turned_sketch.resampled) / 10
    again = with_unpacked(alone, packed)
    assert np.array_equal(again.labels, turned_sketch.labels) and again.n_regions == turned_sketch.n_regions
    assert (again.method, again.params, again.source) == (turned_sketch.method, turned_sketch.params, None)
    assert len(again.resampled) == len(turned_sketch.resampled) == 5
    for got, want in zip(again.resampled, turned_sketch.resampled, strict=True):
        assert np.array_equal(got.labels, want.labels) and got.labels.dtype == want.labels.dtype
        assert (got.method, got.params, got.source) == (want.method, want.params, want.source)
        assert sorted(got.graph.edges) == sorted(want.graph.edges) and got.n_regions == want.n_regions
    # Nothing to pack: the same object, and back again.
    plain = segment_canonical(make_pair(seed=5)[1].free, preset="default", resampled=True)
    assert packed_apart(plain) == (plain, None) and with_unpacked(plain, None) is plain
    # A packed segmentation comes back whole without resamplings to add, as the Dask tasks ask.
    assert np.array_equal(with_unpacked(alone, None).labels, turned_sketch.labels)


def test_segment_all_keeps_the_resamplings_packed_and_the_caches_whole(tmp_path, turned_sketch, monkeypatch):
    import cv2

    path = tmp_path / "turned.png"

    cv2.imwrite(str(path), (turned_sketch.labels > 0).astype(np.uint8) * 255)
    job = SegmentationJob.of(path, "default", {}, {}, canonical=True, resampled=True)
    memory: dict = {}
    packed: dict = {}
    found, _ = segment_all([job], 1, Progress(None, 1), memory, tmp_path / "cache", packed=packed)
    assert found[job.key].resampled == () and len(packed[job.key].items) == 5
    assert isinstance(memory[job.key], Packed)  # the memory cache holds the packed form
    # Read back, from the packed memory cache or from disk, it is whole and the same.
    for source in (memory, None):
        whole = read_cached(job, source, tmp_path / "cache")
        assert len(whole.resampled) == 5
        unpacked = with_unpacked(found[job.key], packed[job.key])
        for a, b in zip(whole.resampled, unpacked.resampled, strict=True):
            assert np.array_equal(a.labels, b.labels)
    # Asked again with packing, the packed cache entry serves as it is: nothing unpacked.
    monkeypatch.setattr(packing, "with_unpacked", lambda *args: pytest.fail("unpacked"))
    again: dict = {}
    second, cached = segment_all([job], 1, Progress(None, 1), memory, None, packed=again)
    assert cached == 1 and again[job.key] is packed[job.key] and second[job.key] is found[job.key]


def test_an_evaluation_of_turned_sketches_is_the_same_packed_or_not(synthetic_dataset, monkeypatch):
    options = dict(
        matchers=["planar"],
        variants=["T4"],
        m_grid=(0.1,),
        preset="robot",
        metric_preset="robot",
        workers=1,
        augment="angles=25,200",
        human=False,
    )
    packs = []
    pack = evaluation_cache.packed_apart
    monkeypatch.setattr(evaluation_cache, "packed_apart", lambda segmentation: packs.append(1) or pack(segmentation))
    packed = run_evaluation(synthetic_dataset, **options)
    assert sum(1 for key in packs) >= 2  # the turned sketches had resamplings to pack
    monkeypatch.setattr(evaluation_cache, "packed_apart", lambda segmentation: (segmentation, None))
    whole = run_evaluation(synthetic_dataset, **options)

    def scores(result):
        return [(r.map, r.augment, r.annotator, r.m_label, r.f1, r.place_accuracy, r.n_pairs) for r in result.rows]

    # Two maps, upright and at the two angles, two annotators, m 0.1 and automatic.
    assert scores(packed) == scores(whole) and len(packed.rows) == 2 * 3 * 2 * 2
