"""Two maps matched as ``ursim match`` matches them (ursim_core.matching.from_maps)."""

from __future__ import annotations

import numpy as np
import pytest

from ursim_core.correspondences import assign_regions, load_dat
from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.evaluation import datasets
from ursim_core.evaluation.scoring import score_matches
from ursim_core.io import load_map, map_from_array
from ursim_core.matching import MatchConfig, match, match_maps, segment_for_matching, sketch_segmentation_rule
from ursim_core.segmentation import segment


def _rooms() -> np.ndarray:
    image = np.zeros((120, 200), np.uint8)
    image[10:110, 10:80] = image[30:90, 120:180] = image[55:65, 80:120] = 255
    image[10:40, 80:110] = 255  # a nook, so the two rooms are not alike
    return image


def test_the_sketch_is_segmented_in_its_canonical_pose_unless_told_upright():
    the_map = map_from_array(_rooms())
    assert segment_for_matching(the_map, side="sketch").params.get("canonical") is True
    told = segment_for_matching(the_map, side="sketch", config=MatchConfig(orientation="upright"))
    assert "canonical" not in told.params
    assert "canonical" not in segment_for_matching(the_map, side="metric").params


def test_the_matchers_preset_is_the_default_not_segments_own():
    # segment() alone uses the 'sketch' preset; the matcher's evidence is on 'default'.
    the_map = map_from_array(_rooms())
    metric = segment_for_matching(the_map, side="metric")
    assert np.array_equal(metric.labels, segment(the_map, preset="default").labels)
    assert metric.params == segment(the_map, preset="default").params


def test_the_resamplings_are_made_only_for_the_planar_matchers_vote():
    assert sketch_segmentation_rule(MatchConfig()) == (True, True)
    assert sketch_segmentation_rule(MatchConfig(resampling_vote=False)) == (True, False)
    assert sketch_segmentation_rule(MatchConfig(matcher="hungarian")) == (True, False)
    assert sketch_segmentation_rule(MatchConfig(), constrained=True) == (True, False)


def test_two_georeferenced_maps_give_the_matcher_their_scale(tmp_path):
    import cv2

    for name, resolution in (("sketch", 0.1), ("metric", 0.05)):
        cv2.imwrite(str(tmp_path / f"{name}.png"), _rooms())
        (tmp_path / f"{name}.yaml").write_text(f"image: {name}.png\nresolution: {resolution}\norigin: [0, 0, 0]\n")
    found = match_maps(load_map(tmp_path / "sketch.yaml"), load_map(tmp_path / "metric.yaml"))
    assert found.config.scale == 2.0 and found.config.resolved().matcher == "overlay"
    assert sketch_segmentation_rule(found.config) == (True, False)  # no resamplings for the overlay


def test_a_map_without_a_region_is_refused_naming_its_file(tmp_path):
    import cv2

    image = np.zeros((60, 60), np.uint8)
    image[10:13, 10:13] = 255  # free, but too small to be a region
    cv2.imwrite(str(tmp_path / "dots.png"), image)
    with pytest.raises(SegmentationError, match="0 regions") as raised:
        match_maps(load_map(tmp_path / "dots.png"), map_from_array(_rooms()))
    assert raised.value.path == tmp_path / "dots.png"
    with pytest.raises(ParameterError, match="side"):
        segment_for_matching(map_from_array(_rooms()), side="robot")


@pytest.mark.dataset
def test_on_kth_the_pipeline_scores_what_ursim_match_scores_and_segment_then_match_does_not():
    root = datasets.dataset_root()
    if root is None:
        pytest.skip(datasets.MISSING_REASON)
    folder = root / "ursim_kth_sketches"
    sketch, model = load_map(folder / "sketches" / "00.png"), load_map(folder / "model" / "model_simple.png")
    reference = load_dat(folder / "gt_correspondences" / "malcolm" / "gt_00_model_simple.dat")

    def f1(sketch_seg, metric_seg, pairs):
        return score_matches(pairs, assign_regions(reference, sketch_seg.labels, metric_seg.labels)).f1

    found = match_maps(sketch, model)
    assert f1(found.sketch_seg, found.metric_seg, found.result.pairs) >= 0.95
    # What the docstrings led a caller to before (the audit measured 0.64).
    plain_sketch, plain_model = segment(sketch), segment(model)
    assert f1(plain_sketch, plain_model, match(plain_sketch, plain_model).pairs) < 0.8


def test_a_match_saves_as_a_correspondence_file_and_loads_back(tmp_path):
    from ursim_core.correspondences import load_correspondences, save_correspondences
    from ursim_core.segmentation import load_label_image, save_label_image

    image = _rooms()
    sketch_path, metric_path = tmp_path / "sketch.png", tmp_path / "metric.png"
    import cv2

    cv2.imwrite(str(sketch_path), np.rot90(image))
    cv2.imwrite(str(metric_path), image)
    found = match_maps(load_map(sketch_path), load_map(metric_path))
    save_label_image(found.sketch_seg, tmp_path / "sketch.labels.png")
    corr = found.correspondences(sketch_labels_path=tmp_path / "sketch.labels.png")
    save_correspondences(corr, tmp_path / "pair.json")
    loaded = load_correspondences(tmp_path / "pair.json")
    assert loaded.sketch.path == sketch_path and loaded.metric.path == metric_path
    assert loaded.sketch.sha256 == load_map(sketch_path).sha256
    assert loaded.sketch.labels_path == tmp_path / "sketch.labels.png" and loaded.metric.labels_path is None
    assert loaded.sketch.segmentation_params.get("canonical") is True
    pairs = sorted((c.sketch_regions[0], c.metric_regions[0]) for c in loaded.cliques)
    assert pairs == sorted(found.result.pairs) and len(pairs) == found.metric_seg.n_regions
    record = loaded.extra["matcher"]
    assert record["config"]["orientation"] == "any" and record["orientation"]["degrees"] in (90.0, 270.0)
    relabelled = load_label_image(loaded.sketch.labels_path, shape=found.sketch_seg.labels.shape)
    assert np.array_equal(relabelled.labels, found.sketch_seg.labels)


def test_a_configuration_is_built_without_importing_the_matcher():
    # ``from ursim_core.matching import MatchConfig`` imported the pipeline, networkx and the
    # matcher (379 ms, 582 modules) for a dataclass; a caller building options pays for them
    # only when it matches.
    import subprocess
    import sys

    code = (
        "import sys; from ursim_core.matching import MatchConfig, MATCH_PRESETS; MatchConfig(orientation=90);"
        "print('networkx' in sys.modules, 'ursim_core.matching.pipeline' in sys.modules)"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.split() == ["False", "False"]


def test_match_refuses_maps_naming_the_argument_and_what_to_call():
    # match(Map, Map) gave "AttributeError: 'Map' object has no attribute 'graph'".
    the_map = map_from_array(_rooms())
    with pytest.raises(ParameterError, match="match_maps") as raised:
        match(the_map, the_map)
    assert raised.value.field == "sketch_seg"
    with pytest.raises(ParameterError) as raised:
        match(segment(the_map), "metric.png")
    assert raised.value.field == "metric_seg" and "got str" in str(raised.value)


def test_a_path_given_for_a_map_is_refused_naming_the_argument():
    with pytest.raises(ParameterError, match="load_map") as raised:
        match_maps("sketch.png", map_from_array(_rooms()))
    assert raised.value.field == "sketch_map"
    with pytest.raises(ParameterError) as raised:
        match_maps(map_from_array(_rooms()), _rooms())
    assert raised.value.field == "metric_map" and "ndarray" in str(raised.value)
