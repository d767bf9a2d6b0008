"""`ursim bench quality` and `ursim segment --evaluate`: in-sample and leave-one-map-out columns."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_core.bench import quality
from ursim_core.segmentation.presets_cv import BenchmarkMap, Candidate, CrossValidation


def _two_rooms(door: int, seed: int):
    free = np.zeros((60, 130), bool)
    free[5:55, 5:60] = free[5:55, 70:125] = True
    free[30 - door // 2 : 30 + door // 2, 60:70] = True
    truth = np.where(free, 1 + (np.arange(130) >= 65), 0).astype(np.int32)
    return BenchmarkMap(f"m{seed}", free, {"gt": truth})


def test_data_chosen_rules():
    assert quality.data_chosen_rule("maoris", "sketch") == "sketch"
    assert quality.data_chosen_rule("watershed", "robot") == "watershed"
    assert quality.data_chosen_rule("learned", "default") == "learned"
    assert quality.data_chosen_rule("maoris", "default") is None
    assert quality.cross_validate_rule([_two_rooms(6, 0)], "maoris", "default") is None


def test_cross_validated_column_differs_from_in_sample_when_the_left_out_map_disagrees(capsys, monkeypatch):
    from ursim_core.segmentation import presets_cv

    # F1 of two candidates on three maps: candidate 1 wins on all maps (2.0 against 1.9), but
    # without m2 candidate 0 wins, so m2's cross-validated F1 is candidate 0's.
    f1 = np.array([[0.9, 0.9, 0.1], [0.5, 0.5, 1.0]])[:, :, None]
    monkeypatch.setattr(presets_cv, "score_candidates", lambda benchmark, candidates: f1)
    maps = [_two_rooms(6, seed) for seed in range(3)]
    grid = {"doors": [Candidate("maoris", {"doors": 40}), Candidate("maoris", {"doors": 100})]}
    cv = presets_cv.cross_validate(benchmark=maps, selections=grid, fixed={})
    by_map = {row["map"]: row for row in cv.rows}
    assert [by_map[m]["in_sample_f1"] for m in ("m0", "m1", "m2")] == [0.5, 0.5, 1.0]
    assert [by_map[m]["cv_f1"] for m in ("m0", "m1", "m2")] == [0.5, 0.5, 0.1]
    quality.print_cross_validation(cv, title="tiny")
    text = capsys.readouterr().out
    assert "doors gt in" in text and "doors gt cv" in text
    summary = [line for line in text.splitlines() if line.startswith("doors ")]
    assert summary and "0.667" in summary[0] and "0.367" in summary[0]


def test_print_shows_agreement_and_every_preset(capsys):
    rows = [
        {"preset": p, "map": m, "annotator": a, "in_sample_f1": 0.9, "cv_f1": 0.8, "cv_choice": "x", "chosen": "y"}
        for p in ("sketch", "learned")
        for m in ("00", "01")
        for a in ("gt_lex", "gt_ezvin")
    ]
    cv = CrossValidation(rows=rows, agreement=[{"map": "00", "f1": 0.87}, {"map": "01", "f1": 0.77}])
    quality.print_cross_validation(cv, title="t")
    text = capsys.readouterr().out
    assert "agreement" in text and "0.870" in text and "learned gt_ezvin cv" in text
    assert "annotators' agreement" in text


def test_segment_evaluate_prints_the_cross_validated_column(tmp_path, capsys):
    from ursim_core.cli import main

    maps_dir, gt_dir = tmp_path / "maps", tmp_path / "gt"
    maps_dir.mkdir()
    gt_dir.mkdir()
    for item in (_two_rooms(6, 0), _two_rooms(8, 1)):
        cv2.imwrite(str(maps_dir / f"{item.name}.png"), np.where(item.free, 255, 0).astype(np.uint8))
        separators = np.where(item.free, 255, 0).astype(np.uint8)
        separators[:, 65] = np.where(item.free[:, 65], 0, separators[:, 65])  # the door line
        cv2.imwrite(str(gt_dir / f"{item.name}.png"), separators)
    assert main(["segment", "--evaluate", str(gt_dir), str(maps_dir), "--preset", "sketch"]) == 0
    text = capsys.readouterr().out
    assert "CV F1" in text and "rule (sketch)" in text
    assert main(["segment", "--evaluate", str(gt_dir), str(maps_dir), "--preset", "default"]) == 0
    assert "was not chosen on data" in capsys.readouterr().out


def test_bench_quality_without_the_dataset_says_so(tmp_path, capsys):
    import ursim_core.bench.runner as runner

    assert runner.run_bench("quality", datasets=tmp_path) == 1
    assert "maoris_segmentation" in capsys.readouterr().err


@pytest.mark.dataset
def test_bench_quality_on_the_dataset_robot_maps(tmp_path, capsys):
    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

    root = dataset_root(None)
    if root is None or not (root / "maoris_segmentation").is_dir():
        pytest.skip(MISSING_REASON)
    rows = quality.bench_quality(root, kinds=("robot_maps",), learned=False, csv_path=tmp_path / "q.csv")
    text = capsys.readouterr().out
    assert "watershed gt cv" in text
    assert (tmp_path / "q.csv").read_text().splitlines()[0].startswith("kind,preset,map")
    watershed = [row["cv_f1"] for row in rows if row["preset"] == "watershed"]
    assert len(watershed) == 15 and np.mean(watershed) > 0.9
