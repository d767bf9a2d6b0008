"""Segmentation scoring: ground truth from separator images, precision/recall."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from ursim_core.errors import SegmentationError
from ursim_core.segmentation.scoring import (
    gt_labels_from_separator_image,
    load_label_array,
    relabel_in_raster_order,
    score_segmentation,
)


def separator_image() -> np.ndarray:
    """Two 5x8 rooms side by side, split by a 1-px grey separator line."""
    image = np.zeros((9, 21), np.uint8)
    image[2:7, 2:19] = 255
    image[2:7, 10] = 120
    return image


def test_separator_image_gives_one_label_per_room():
    labels = gt_labels_from_separator_image(separator_image())
    assert labels.max() == 2
    assert labels[4, 5] == 1 and labels[4, 15] == 2
    # Erode then dilate by 1 px (an opening): each room gets its free pixels back,
    # nothing beyond them, and the separator stays unlabelled.
    free = separator_image() > 250
    np.testing.assert_array_equal(labels > 0, free)
    assert labels[4, 10] == 0


def test_separator_image_transparent_pixels_are_obstacle():
    grey = separator_image()
    rgba = np.dstack([np.full_like(grey, 255)] * 3 + [np.where(grey > 0, 255, 0).astype(np.uint8)])
    rgba[2:7, 10, :3] = 120
    np.testing.assert_array_equal(gt_labels_from_separator_image(rgba), gt_labels_from_separator_image(grey))


def test_separator_image_from_file(tmp_path: Path):
    path = tmp_path / "gt.png"
    cv2.imwrite(str(path), separator_image())
    np.testing.assert_array_equal(
        gt_labels_from_separator_image(path), gt_labels_from_separator_image(separator_image())
    )


def test_filled_top_level_contour_covers_its_holes():
    image = np.zeros((12, 12), np.uint8)
    image[1:11, 1:11] = 255
    image[5:7, 5:7] = 0  # a pillar inside the room
    labels = gt_labels_from_separator_image(image)
    assert labels.max() == 1 and labels[5, 5] == 1


def test_perfect_segmentation_scores_one():
    gt = np.array([[1, 1, 0, 2, 2], [1, 1, 0, 2, 2]])
    score = score_segmentation(gt * 7, gt)
    assert (score.precision, score.recall, score.f1) == (1.0, 1.0, 1.0)
    assert score.evaluator_precision == 1.0 and score.evaluator_f1 == 1.0
    assert score.best_match == (7, 14) and score.n_predicted == 2


def test_merged_prediction_halves_precision():
    gt = np.array([[1, 1, 2, 2]])
    score = score_segmentation(np.array([[5, 5, 5, 5]]), gt)
    assert score.region_precision == (0.5, 0.5) and score.region_recall == (1.0, 1.0)
    assert score.precision == 0.5 and score.recall == 1.0
    assert score.f1 == pytest.approx(2 / 3)
    # Per predicted region, the only region overlaps its best GT region on half its pixels.
    assert score.evaluator_precision == 0.5


def test_split_prediction_halves_recall():
    gt = np.array([[1, 1, 1, 1]])
    score = score_segmentation(np.array([[1, 1, 2, 2]]), gt)
    assert score.precision == 1.0 and score.recall == 0.5
    assert score.best_match == (1,)  # tie on overlap: the smaller label


def test_unmatched_gt_region_scores_zero():
    gt = np.array([[1, 1, 2, 2]])
    score = score_segmentation(np.array([[3, 3, 0, 0]]), gt)
    assert score.region_precision == (1.0, 0.0) and score.region_recall == (1.0, 0.0)
    assert score.best_match == (3, 0)
    assert score.precision == 0.5 and score.recall == 0.5


def test_prediction_outside_gt_counts_against_precision():
    gt = np.array([[1, 1, 0, 0]])
    score = score_segmentation(np.array([[1, 1, 1, 1]]), gt)
    assert score.precision == 0.5 and score.recall == 1.0


def test_empty_prediction_scores_zero():
    gt = np.array([[1, 2]])
    score = score_segmentation(np.zeros((1, 2), int), gt)
    assert (score.precision, score.recall, score.f1, score.evaluator_f1) == (0.0, 0.0, 0.0, 0.0)


def test_score_rejects_bad_input():
    with pytest.raises(SegmentationError, match="shape"):
        score_segmentation(np.zeros((2, 2), int), np.zeros((2, 3), int))
    with pytest.raises(SegmentationError, match="no region"):
        score_segmentation(np.ones((2, 2), int), np.zeros((2, 2), int))


def test_relabel_in_raster_order():
    labels = np.array([[0, 9, 9], [4, 0, 9], [4, 2, 0]])
    assert relabel_in_raster_order(labels).tolist() == [[0, 1, 1], [2, 0, 1], [2, 3, 0]]


def test_load_label_array(tmp_path: Path):
    path = tmp_path / "labels.png"
    cv2.imwrite(str(path), np.array([[0, 5, 5], [3, 3, 0]], np.uint8))
    assert load_label_array(path).tolist() == [[0, 1, 1], [2, 2, 0]]
    sixteen = tmp_path / "labels16.png"
    cv2.imwrite(str(sixteen), np.array([[0, 700, 300]], np.uint16))
    assert load_label_array(sixteen).tolist() == [[0, 1, 2]]


def test_load_label_array_errors(tmp_path: Path):
    with pytest.raises(SegmentationError, match="label image not found"):
        load_label_array(tmp_path / "missing.png")
    colour = tmp_path / "colour.png"
    cv2.imwrite(
        str(colour), np.dstack([np.full((2, 2), 1, np.uint8), np.full((2, 2), 2, np.uint8), np.zeros((2, 2), np.uint8)])
    )
    with pytest.raises(SegmentationError, match="got colour"):
        load_label_array(colour)


# --------------------------------------------------------------------------
# Research data


@pytest.fixture(scope="module")
def sketches() -> Path:
    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

    root = dataset_root()
    if root is None or not (root / "maoris_segmentation" / "sketches").is_dir():
        pytest.skip(MISSING_REASON)
    return root / "maoris_segmentation" / "sketches"


@pytest.mark.dataset
def test_evaluator_scores_reproduce_the_published_figures(sketches):
    """The authors' label images, scored per predicted region, give their published P/R."""
    published = {"gt_lex": (0.9056, 0.9048), "gt_ezvin": (0.8658, 0.9112)}
    for folder, (precision, recall) in published.items():
        scores = [
            score_segmentation(
                load_label_array(sketches / "maoris_output" / path.name),
                gt_labels_from_separator_image(sketches / folder / path.name),
            )
            for path in sorted((sketches / "maps").glob("*.png"))
        ]
        assert len(scores) == 18
        assert np.mean([s.evaluator_precision for s in scores]) == pytest.approx(precision, abs=0.025)
        assert np.mean([s.recall for s in scores]) == pytest.approx(recall, abs=0.01)


@pytest.mark.dataset
@pytest.mark.slow
def test_sketch_preset_beats_the_authors_segmentations(sketches):
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation.maoris import PRESETS, maoris_labels

    ours: dict[str, list[float]] = {"gt_lex": [], "gt_ezvin": []}
    authors: dict[str, list[float]] = {"gt_lex": [], "gt_ezvin": []}
    for path in sorted((sketches / "maps").glob("*.png")):
        labels = maoris_labels(load_map(path).free, PRESETS["sketch"])
        reference = load_label_array(sketches / "maoris_output" / path.name)
        for folder in ours:
            gt = gt_labels_from_separator_image(sketches / folder / path.name)
            ours[folder].append(score_segmentation(labels, gt).f1)
            authors[folder].append(score_segmentation(reference, gt).f1)
    for folder in ours:
        assert np.mean(ours[folder]) >= np.mean(authors[folder]), folder
