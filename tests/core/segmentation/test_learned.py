"""Learned merging of candidate pieces: features, the model file, the segmenter, its figures."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.segmentation import segment
from ursim_core.segmentation.learned import model as model_module
from ursim_core.segmentation.learned.features import FEATURE_NAMES, PieceGraph
from ursim_core.segmentation.learned.merging import agglomerate, apply_merges, learned_labels
from ursim_core.segmentation.learned.model import (
    default_merge_model,
    fit_merge_model,
    load_merge_model,
)
from ursim_core.segmentation.learned.training import oracle_pairs
from ursim_core.segmentation.presets_cv import BenchmarkMap


def _column(name: str) -> int:
    return FEATURE_NAMES.index(name)


def _row_of_pieces() -> tuple[np.ndarray, np.ndarray]:
    """Three pieces side by side in a 10 x 30 free block: 10, 10 and 10 columns wide."""
    labels = np.zeros((12, 32), np.int32)
    labels[1:11, 1:11], labels[1:11, 11:21], labels[1:11, 21:31] = 1, 2, 3
    clearance = np.ones(labels.shape, np.float32)
    clearance[5, 10:12] = 4.0  # the widest point of the seam between 1 and 2 (one pixel pair)
    return labels, clearance


def test_features_of_a_hand_made_pair():
    labels, clearance = _row_of_pieces()
    maoris = np.where(labels > 0, 1 + (labels == 3), 0)  # MAORIS separates 2 | 3 only
    graph = PieceGraph.from_arrays(labels, maoris, labels, clearance)
    assert graph.pairs() == [(1, 2), (2, 3)]
    f12, f23 = graph.features([(1, 2), (2, 3)])
    # 10 px of seam; each piece has 40 pixel sides of perimeter and 100 px of area.
    assert f12[_column("size_ratio")] == 1.0
    assert f12[_column("boundary_of_small")] == pytest.approx(10 / 40)
    assert f12[_column("boundary_per_side")] == pytest.approx(10 / math.sqrt(100))
    assert f12[_column("log_area_small")] == pytest.approx(math.log(100 / 300), abs=1e-6)
    # Widest clearance on the seam 4, peaks 4 and 4 -> 1; seam 2|3 has 1 of peaks 4 and 1.
    assert f12[_column("saddle_ratio")] == 1.0
    assert f23[_column("saddle_ratio")] == 1.0 and f23[_column("saddle_of_large_peak")] == 0.25
    assert f12[_column("mean_to_saddle")] == pytest.approx((9 * 1 + 4) / 10 / 4)
    assert (f12[_column("maoris_cut")], f23[_column("maoris_cut")]) == (0.0, 1.0)
    assert f12[_column("watershed_cut")] == 1.0
    assert f12[_column("compact_small")] == pytest.approx(4 * math.pi * 100 / 40**2)
    assert f12[_column("elongation_small")] == pytest.approx(0.0, abs=1e-6)  # a square
    assert f12[_column("elongation_union")] > 0.4  # a 10 x 20 rectangle


def test_features_after_a_merge_equal_those_of_the_merged_image():
    labels, clearance = _row_of_pieces()
    graph = PieceGraph.from_arrays(labels, labels, labels, clearance)
    graph.merge(2, 1)
    merged = np.where(labels == 1, 2, labels)
    fresh = PieceGraph.from_arrays(merged, labels, labels, clearance)
    assert graph.pairs() == fresh.pairs() == [(2, 3)]
    np.testing.assert_allclose(graph.features([(2, 3)]), fresh.features([(2, 3)]))
    np.testing.assert_allclose(graph.pieces[2], fresh.pieces[2])


def test_oracle_pairs_follow_the_ground_truth_through_merges():
    labels, clearance = _row_of_pieces()
    truth = np.where(labels > 0, 1 + (labels == 3), 0)
    x, y = oracle_pairs(PieceGraph.from_arrays(labels, labels, labels, clearance), labels, truth)
    assert x.shape == (3, len(FEATURE_NAMES))
    assert y.tolist() == [1.0, 0.0, 0.0]  # (1, 2), (2, 3), then (1+2, 3)


def test_the_shipped_model_loads_and_predicts_deterministically():
    model = default_merge_model()
    assert model.features == FEATURE_NAMES
    assert "GPL-3.0" in model.metadata["licence"] and "maoris" in model.metadata["source"]
    x = np.random.default_rng(3).uniform(0, 1, (50, len(FEATURE_NAMES)))
    p = model.predict(x)
    assert ((p > 0) & (p < 1)).all()
    assert np.array_equal(p, model.predict(x))
    shipped = Path(model_module.__file__).with_name("merge_model.json")
    assert np.array_equal(p, load_merge_model(shipped).predict(x))
    assert len(set(np.round(p, 3).tolist())) > 5  # the features matter


def test_training_is_deterministic_and_a_saved_model_predicts_the_same(tmp_path):
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, (400, 3))
    y = ((x[:, 0] > 0.6) & (x[:, 2] < 0.5)).astype(float)
    first = fit_merge_model(x, y, features=("a", "b", "c"), trees=40)
    second = fit_merge_model(x, y, features=("a", "b", "c"), trees=40)
    assert first.to_dict() == second.to_dict()
    assert ((first.predict(x) > 0.5) == (y == 1)).mean() > 0.95
    first.save(tmp_path / "m.json")
    again = load_merge_model(tmp_path / "m.json")
    assert np.array_equal(again.predict(x), first.predict(x))
    with pytest.raises(SegmentationError, match="takes 3 features"):
        first.predict(x[:, :2])


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        ("{not json", "not JSON"),
        ('{"format": "other"}', "not a merge model"),
        ('{"format": "ursim-merge-model", "version": 7}', "version"),
        ('{"format": "ursim-merge-model", "version": 1, "features": ["a"], "base": 0, "trees": [{}]}', "trees"),
    ],
)
def test_a_bad_model_file_is_a_segmentation_error_naming_the_file(tmp_path, content, problem):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(SegmentationError, match=problem) as caught:
        load_merge_model(path)
    assert str(path) in str(caught.value)


def test_a_bad_tree_field_is_named(tmp_path):
    data = default_merge_model().to_dict()
    data["trees"][3]["feature"] = [0, 99, 1]
    path = tmp_path / "model.json"
    path.write_text(json.dumps(data))
    with pytest.raises(SegmentationError, match=r"trees\[3\]\.feature"):
        load_merge_model(path)
    with pytest.raises(SegmentationError, match="not found"):
        load_merge_model(tmp_path / "missing.json")


def _two_rooms() -> np.ndarray:
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    return free


def test_the_segmenter_behind_the_interface():
    free = _two_rooms()
    seg = segment(free, method="learned")
    assert seg.method == "learned" and seg.params["model"] == "default"
    assert seg.labels[30, 30] != seg.labels[30, 100]
    assert not seg.labels[~free].any()
    # Free pixels MAORIS leaves out (specks at the walls) stay out; all others are labelled.
    assert np.array_equal(seg.labels > 0, segment(free, preset="sketch").labels > 0)
    assert np.array_equal(seg.labels, segment(free, method="learned", params=seg.params).labels)
    # Threshold 0 merges every touching pair; 1 none (MAORIS and the watershed pieces stay).
    assert int(learned_labels(free, threshold=0.0).max()) == 1
    assert int(learned_labels(free, threshold=1.0).max()) >= 2


def test_bad_parameters_and_a_bad_model_through_segment(tmp_path):
    with pytest.raises(ParameterError, match="unknown parameter of the learned segmenter"):
        segment(_two_rooms(), method="learned", params={"doors": 40})
    with pytest.raises(ParameterError, match="threshold"):
        segment(_two_rooms(), method="learned", params={"threshold": 2})
    with pytest.raises(ParameterError, match="preset"):
        segment(_two_rooms(), method="learned", preset="robot")
    (tmp_path / "broken.json").write_text("[]")
    with pytest.raises(SegmentationError, match="broken.json"):
        segment(_two_rooms(), method="learned", params={"model": str(tmp_path / "broken.json")})


def test_agglomeration_merges_most_probable_first_and_stops_below_threshold():
    labels, clearance = _row_of_pieces()

    class ByMaorisCut:  # merges where MAORIS saw no boundary
        def predict(self, x):
            return 1.0 - x[:, _column("maoris_cut")]

    maoris = np.where(labels > 0, 1 + (labels == 3), 0)
    graph = PieceGraph.from_arrays(labels, maoris, labels, clearance)
    into = agglomerate(graph, ByMaorisCut(), threshold=0.5)
    assert len(into) == 1
    out = apply_merges(labels, into)
    assert out[5, 5] == out[5, 15] != out[5, 25]


def test_cross_validation_trains_without_the_left_out_map():
    from ursim_core.segmentation.learned_cv import cross_validate_learned

    free = _two_rooms()
    truth = np.where(free, 1 + (np.arange(130) >= 65), 0).astype(np.int32)
    maps = [BenchmarkMap(f"m{i}", free, {"a": truth, "b": truth}) for i in range(3)]
    cv = cross_validate_learned(maps)
    assert [(r["map"], r["annotator"]) for r in cv.rows][:2] == [("m0", "a"), ("m0", "b")]
    assert cv.rows[0]["cv_choice"] == "model trained without m0"
    assert all(r["cv_f1"] > 0.9 for r in cv.rows)
    assert cv.summary()[0]["preset"] == "learned" and cv.agreement[0]["f1"] == 1.0


@pytest.mark.skipif(dataset_root() is None, reason=MISSING_REASON)
def test_on_sketches_the_learned_segmenter_is_close_to_the_annotators():
    from ursim_core.segmentation.presets_cv import load_benchmark
    from ursim_core.segmentation.scoring import score_segmentation

    sketch = next(m for m in load_benchmark(dataset_root(), "sketches") if m.name == "01")
    labels = segment(sketch.free, method="learned").labels
    assert score_segmentation(labels, sketch.ground_truths["gt_lex"]).f1 > 0.75
