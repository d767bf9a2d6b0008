"""discover(): the KTH and Halmstad layouts, built in tmp_path, and the errors on bad layouts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ursim_core.errors import FormatError, ParameterError, UrsimError
from ursim_core.evaluation.layouts import Experiment, discover

DAT = "# {map1} {map2}\n# 0match set\n# map1\n5 5\n# map2\n6 6\n\n# 1match set\n# map1\n# map2\n"


def _png(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    image = np.zeros((12, 12), np.uint8)
    image[2:10, 2:10] = 255
    Image.fromarray(image).save(path)
    return path


def _dat(path: Path, map1: str = "a.png", map2: str = "model_simple.png") -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(DAT.format(map1=map1, map2=map2))
    return path


def _kth(root: Path, sketches=("00", "01", "02"), gt=None) -> Path:
    gt = gt if gt is not None else {"malcolm": ("00", "01"), "vasiliki": ("01",)}
    for name in sketches:
        _png(root / "sketches" / f"{name}.png")
    _png(root / "model" / "model_simple.png")
    for annotator, names in gt.items():
        for name in names:
            _dat(root / "gt_correspondences" / annotator / f"gt_{name}_model_simple.dat")
    return root


def _halmstad(root: Path) -> Path:
    for name in ("E5_01", "E5_02", "E5_08", "E5_10"):
        _png(root / f"{name}.png")
    for annotator, _model, maps in (
        ("Malcolm", "E5_08", ("E5_01", "E5_10")),
        ("Vasiliki", "E5_10", ("E5_01", "E5_02", "E5_08")),
    ):
        _png(root / "GT" / annotator / "model_simple.png")
        for name in maps:
            _dat(root / "GT" / annotator / f"gt_{name}_model_simple.dat")
        # The model matched onto itself is not an experiment.
        _dat(root / "GT" / annotator / "gt_model_simple_model_simple.dat")
    return root


def test_kth_layout_one_experiment_per_sketch_with_every_annotator(tmp_path):
    root = _kth(tmp_path / "kth")
    _dat(root / "gt_correspondences" / "vasiliki" / "gt_model_simple_model_simple.dat")

    experiments = discover(root)

    assert [e.name for e in experiments] == ["00", "01"]  # 02 has no ground truth
    first, second = experiments
    assert first.annotators == ("malcolm",)
    assert second.annotators == ("malcolm", "vasiliki")
    assert second.sketch == (root / "sketches" / "01.png").resolve()
    assert second.metric == (root / "model" / "model_simple.png").resolve()
    assert second.ground_truth["vasiliki"].name == "gt_01_model_simple.dat"
    assert {e.layout for e in experiments} == {"kth"}
    assert all(isinstance(e, Experiment) for e in experiments)


def test_kth_names_sort_numerically(tmp_path):
    root = _kth(tmp_path / "kth", sketches=("2", "10", "1"), gt={"ann": ("2", "10", "1")})
    assert [e.name for e in discover(root)] == ["1", "2", "10"]


def test_halmstad_layout_one_experiment_per_map_model_and_annotator(tmp_path):
    root = _halmstad(tmp_path / "E5")

    experiments = discover(root)

    described = [(e.name, e.annotators, e.metric.parent.name) for e in experiments]
    assert described == [
        ("E5_01", ("malcolm",), "Malcolm"),
        ("E5_01", ("vasiliki",), "Vasiliki"),
        ("E5_02", ("vasiliki",), "Vasiliki"),
        ("E5_08", ("vasiliki",), "Vasiliki"),
        ("E5_10", ("malcolm",), "Malcolm"),
    ]
    malcolm_01 = experiments[0]
    assert malcolm_01.sketch == (root / "E5_01.png").resolve()
    assert malcolm_01.metric == (root / "GT" / "Malcolm" / "model_simple.png").resolve()
    assert malcolm_01.layout == "halmstad"


def test_halmstad_parent_folder_is_accepted(tmp_path):
    _halmstad(tmp_path / "robot_maps" / "E5")
    (tmp_path / "robot_maps" / "KT").mkdir()  # a sibling without ground truth is ignored
    _png(tmp_path / "robot_maps" / "KT" / "KPT4A_01.png")

    experiments = discover(tmp_path / "robot_maps")

    assert len(experiments) == 5
    assert {e.dataset for e in experiments} == {(tmp_path / "robot_maps" / "E5").resolve()}


def test_missing_folder_is_a_parameter_error(tmp_path):
    with pytest.raises(ParameterError, match="not found"):
        discover(tmp_path / "nowhere")


def test_unknown_layout_lists_the_layouts_and_the_datasets_below(tmp_path):
    _kth(tmp_path / "datasets" / "sketch_set")
    (tmp_path / "datasets" / "other").mkdir()

    with pytest.raises(ParameterError) as raised:
        discover(tmp_path / "datasets")

    message = str(raised.value)
    assert str(tmp_path / "datasets") in message
    assert "sketches/<map>.png" in message and "GT/<Annotator>" in message
    assert "sketch_set" in message


def test_empty_folder_is_not_a_dataset(tmp_path):
    with pytest.raises(ParameterError, match="known layout"):
        discover(tmp_path)


def test_ground_truth_for_a_missing_sketch_names_the_file(tmp_path):
    root = _kth(tmp_path / "kth", sketches=("00",), gt={"malcolm": ("00", "07")})
    with pytest.raises(FormatError) as raised:
        discover(root)
    assert "gt_07_model_simple.dat" in str(raised.value)
    assert "sketches/07.png" in str(raised.value)


def test_kth_without_model_is_a_format_error(tmp_path):
    root = _kth(tmp_path / "kth")
    (root / "model" / "model_simple.png").unlink()
    with pytest.raises(FormatError, match="model"):
        discover(root)


def test_annotator_folder_without_matching_files_is_a_format_error(tmp_path):
    root = _kth(tmp_path / "kth")
    (root / "gt_correspondences" / "empty_annotator").mkdir()
    with pytest.raises(FormatError) as raised:
        discover(root)
    assert "empty_annotator" in str(raised.value)
    assert "gt_<map>_model_simple.dat" in str(raised.value)


def test_halmstad_annotator_without_model_is_a_format_error(tmp_path):
    root = _halmstad(tmp_path / "E5")
    (root / "GT" / "Malcolm" / "model_simple.png").unlink()
    with pytest.raises(FormatError) as raised:
        discover(root)
    assert "Malcolm" in str(raised.value) and "model_simple.png" in str(raised.value)


def test_halmstad_ground_truth_for_a_missing_map(tmp_path):
    root = _halmstad(tmp_path / "E5")
    (root / "E5_02.png").unlink()
    with pytest.raises(FormatError, match="E5_02"):
        discover(root)


def test_annotators_differing_only_by_case_are_refused(tmp_path):
    root = _kth(tmp_path / "kth", gt={"Ann": ("00",), "ann": ("01",)})
    with pytest.raises(UrsimError, match="'ann'"):
        discover(root)


@pytest.mark.dataset
def test_real_datasets_are_discovered():
    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    kth = discover(root / "ursim_kth_sketches")
    assert len(kth) == 18 and all(e.annotators == ("malcolm", "vasiliki") for e in kth)
    e5 = discover(root / "ursim_halmstad_robot_maps" / "E5")
    assert sum(e.annotators == ("malcolm",) for e in e5) == 10
    assert sum(e.annotators == ("vasiliki",) for e in e5) == 10
    assert {e.metric.parent.name for e in e5} == {"Malcolm", "Vasiliki"}
