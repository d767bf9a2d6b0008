"""Regression on the 18 KTH sketches in all 8 orientations (needs ../shared/datasets).

Protocol: each sketch image is turned by 0/90/180/270 degrees, mirrored or not, and its
ground-truth points are moved with it by ``ursim_core.evaluation.augment`` (exactly: quarter turns and
mirrors permute pixels). The
sketch is segmented with :func:`ursim_core.segmentation.canonical.segment_canonical`, the metric
model with ``segment`` (its own frame; canonicalising it too gave 0.616 upright), both with the
MAORIS ``default`` preset (the one the annotators clicked on), and matched with the default
``MatchConfig()`` (orientation unknown, automatic m); F1 is the correct scoring of
``score_matches`` against both annotators.

Measured with this code (mean F1 of the two annotators per orientation): 0.762 in every one of the
8 orientations (round 7: 0.717 in seven and 0.754 in the eighth; the orientations are ranked by
hypothesis score over free-space overlap; before, by the score alone: 0.644-0.658). The one thing chosen on these
sketches is that ranking's power (``orientation_overlap``), so the headline figure is its
leave-one-sketch-out cross-validation over 0 (score alone) and 1: held-out F1 0.72, place
accuracy 0.74, in every orientation (without the position refit). With the position refit
(``position_refits``, designed on generated pairs) and exact quarter-turn candidates, every
orientation gives the same answers: in sample 0.76 / 0.78 with one refit, 0.72 / 0.73 without;
cross-validated over 0 and 1 with the power at 1, 0.72 / 0.73 held out (the fold that holds out
sketch 01, the only sketch the refit changes much, chooses none). Round 30: the refit may rank the
orientations without its answer being kept (``keep_refit=False``); cross-validated over that option,
0.74 / 0.76 held out in every orientation (sketch 01 read the right way round in its own fold). The matching issue's bar (0.80 in every orientation) is not
reached; the annotators agree with each other at 0.74-0.77 on these sketches. These assertions keep
what was reached. The released options on the released pipeline (oracle m, fnfix scoring)
reproduce the authors' binary (0.565) within 0.05, upright as they were.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from ursim_core.correspondences import load_dat, regions_at_points
from ursim_core.evaluation import datasets
from ursim_core.evaluation.augment import Orientation, transform_image, transform_points
from ursim_core.evaluation.crossval import cross_validate
from ursim_core.evaluation.kth_protocol import f1_table, kth_pairs, summarise
from ursim_core.evaluation.runner import run_evaluation
from ursim_core.evaluation.scoring import score_matches
from ursim_core.io import load_map
from ursim_core.matching import M_GRID, MatchConfig, match
from ursim_core.segmentation import segment, segment_canonical

pytestmark = [pytest.mark.dataset, pytest.mark.slow]
ORIENTATIONS = [(k, m) for m in (False, True) for k in range(4)]


@pytest.fixture(scope="module")
def root():
    found = datasets.dataset_root()
    if found is None:
        pytest.skip(datasets.MISSING_REASON)
    return found


@functools.lru_cache(maxsize=1)
def _f1_by_orientation(folder) -> dict:
    model = segment(load_map(folder / "model" / "model_simple.png"), preset="default")
    scores = {orientation: [] for orientation in ORIENTATIONS}
    for path in sorted((folder / "sketches").glob("*.png")):
        sketch = load_map(path)
        truths = [
            load_dat(folder / "gt_correspondences" / annotator / f"gt_{path.stem}_model_simple.dat").cliques
            for annotator in ("malcolm", "vasiliki")
        ]
        for orientation in ORIENTATIONS:
            turn = Orientation(90.0 * orientation[0], mirrored=orientation[1])
            seg = segment_canonical(transform_image(sketch.free, turn), preset="default")
            pairs = match(seg, model).pairs

            def move(points, turn=turn, shape=sketch.free.shape):
                return transform_points(points, shape, turn)

            for cliques in truths:
                reference = [
                    (
                        {r for r in regions_at_points(seg.labels, move(c.sketch_points)) if r},
                        {r for r in regions_at_points(model.labels, c.metric_points) if r},
                    )
                    for c in cliques
                ]
                scores[orientation].append(score_matches(pairs, reference).f1)
    return {orientation: float(np.mean(values)) for orientation, values in scores.items()}


def test_default_matches_every_orientation_alike(root):
    means = _f1_by_orientation(root / "ursim_kth_sketches")
    upright = means[(0, False)]
    assert upright >= 0.75, means
    # The same regions (canonical segmentation) and exact quarter-turn candidates: the same answers.
    assert max(means.values()) - min(means.values()) < 1e-9, means


def test_sketch_12_is_read_the_way_it_is_drawn(root):
    # Round 36: with three finalist orientations the right reading of sketch 12 (drawn upright;
    # the highest free-space overlap of the eight) was screened out and the sketch read transposed.
    folder = root / "ursim_kth_sketches"
    model = segment(load_map(folder / "model" / "model_simple.png"), preset="default")
    sketch = segment_canonical(load_map(folder / "sketches" / "12.png"), preset="default")
    assert match(sketch, model).orientation == (0.0, False)
    assert match(sketch, model, config=MatchConfig(orientation_finalists=3)).orientation == (270.0, True)


def test_a_turned_sketch_is_read_the_right_way_round_or_the_close_call_is_said(root):
    # Round 37: sketch 01 turned by 75 degrees. Of its ten segmentations four chose the right
    # reading (turned back by about 286 degrees) and four the mirror image, and the count gave the
    # tie to the mirror image; ranked over all the segmentations the right reading is best, and
    # the mirror image came next, under 2 % behind. Round 38 (the resampled sketch smoothed): still
    # read right, the mirror image next but 12 % behind. Sketch 07 turned by 150 degrees is read
    # wrongly (0.4 % ahead of the next reading): the user must then be told that it was a close call.
    from ursim_core.matching.orientation import CLOSE_READING, next_reading

    folder = root / "ursim_kth_sketches"
    model = segment(load_map(folder / "model" / "model_simple.png"), preset="default")

    def read(name: str, degrees: float):
        turned = transform_image(load_map(folder / "sketches" / f"{name}.png").free, Orientation(degrees))
        result = match(segment_canonical(turned, preset="default", resampled=True), model)
        return result.orientation, next_reading(result.orientation, result.orientation_scan)

    (degrees, mirrored), ((_, runner_up_mirrored), _) = read("01", 75.0)
    assert not mirrored and abs(degrees - 285.0) < 3.0, (degrees, mirrored)
    assert runner_up_mirrored
    (degrees, mirrored), (_, gap) = read("07", 150.0)
    right = not mirrored and abs(degrees - 210.0) < 3.0
    assert right or 0.0 <= gap < CLOSE_READING, (degrees, mirrored, gap)


def _cross_validated(root, option: str, values, *, augment: str = "dihedral"):
    """Leave-one-sketch-out cross-validation of ``option`` over ``values`` (planar T4, the sketches
    turned as ``augment`` says). The graph matcher's own options are measured on its own answer
    (``elastic='off'``): with the elastic answer they only choose the orientation."""
    fixed = {} if option == "elastic" else {"elastic": "off"}
    results = {
        value: run_evaluation(
            root / "ursim_kth_sketches",
            matchers=["planar"],
            variants=["T4"],
            augment=augment,
            human=False,
            config_overrides={**fixed, option: value},
            segmentation_cache=_SEGMENTATIONS,
        )
        for value in values
    }
    return cross_validate(results, option=option)


def test_cross_validated_orientation_ranking_in_every_orientation(root):
    cv = _cross_validated(root, "orientation_overlap", (0.0, 1.0))
    assert cv.f1 >= 0.70 and cv.place_accuracy >= 0.72, cv.table()
    assert min(f1 for f1, _ in cv.by_orientation.values()) >= 0.70, cv.table()
    # Ranking by the score alone is worse held out too.
    assert cv.in_sample[1.0][0] > cv.in_sample[0.0][0] + 0.04, cv.table()


def test_cross_validated_position_refit_in_every_orientation(root):
    cv = _cross_validated(root, "position_refits", (0, 1))
    assert cv.f1 >= 0.71 and cv.place_accuracy >= 0.72, cv.table()
    # Exact quarter-turn candidates: the same answers in every orientation.
    by_orientation = [f1 for f1, _ in cv.by_orientation.values()]
    assert len(by_orientation) == 8 and max(by_orientation) - min(by_orientation) < 1e-9, cv.table()
    # The refit's gain in sample is sketch 01 alone (0.17 -> 1.00): held out, its fold chooses none.
    assert cv.in_sample[1][0] > cv.in_sample[0][0] + 0.03, cv.table()


def test_cross_validated_keep_refit_in_every_orientation(root):
    cv = _cross_validated(root, "keep_refit", (True, False))
    # Round 30: 0.74 / 0.76 held out in every orientation (0.72 / 0.73 over position_refits).
    assert cv.f1 >= 0.73 and cv.place_accuracy >= 0.75, cv.table()
    by_orientation = [f1 for f1, _ in cv.by_orientation.values()]
    assert len(by_orientation) == 8 and max(by_orientation) - min(by_orientation) < 1e-9, cv.table()
    # Sketch 01's fold keeps the answer from before the refit, in the orientation the refit ranked
    # first: the right way round (0.83), where no refit reads it mirrored (0.17).
    rows = {row[0]: row for row in cv.rows}
    assert rows["01"][1] is False and rows["01"][2] >= 0.8, cv.table()


_SEGMENTATIONS: dict = {}


def test_cross_validated_elastic_answer_meets_the_bar_in_every_orientation(root):
    # Round 43: the sketch laid on the model by its box and bent by an optical flow
    # (MatchConfig.elastic). Chosen in all 18 folds, held out 0.82 / 0.81 in every orientation,
    # against 0.77 / 0.78 in sample without it; the bar is 0.80 / 0.80.
    cv = _cross_validated(root, "elastic", ("off", "alone", "completed"))
    assert cv.f1 >= 0.80 and cv.place_accuracy >= 0.80, cv.table()
    by_orientation = list(cv.by_orientation.values())
    assert len(by_orientation) == 8, cv.table()
    assert min(f1 for f1, _ in by_orientation) >= 0.80 and min(p for _, p in by_orientation) >= 0.80, cv.table()
    # 'alone' pairs more but places worse: regions the bent sketch misses lose their partner.
    assert cv.in_sample["alone"][1] < cv.in_sample["completed"][1], cv.table()


def test_the_resampled_segmentations_vote_at_free_angles(root):
    # Round 30: the sketches turned by 30 and 60 degrees are resampled onto their wall axes, and
    # their regions change with the resampling; the vote over six resamplings gave 0.71 mean F1
    # against 0.64 for one (a study script; in sample, the design was chosen on these sketches).
    # Round 38, the resampled sketch smoothed before MAORIS: one segmentation does much better
    # (0.7635), the vote still better (0.7738), held out over the two 0.76. At all 24 angles of
    # 15-degree steps (`ursim evaluate`, README): 0.7670 against 0.7426 for one, held out over
    # `vote_segmentations` 0.7702 / 0.7717, above the 0.75; those 433 sketches with their
    # resamplings take 5 to 6 minutes and 14 GB here, too much for this suite.
    cv = _cross_validated(root, "resampling_vote", (True, False), augment="angles=30,60")
    turned = {name: f1 for name, (f1, _) in cv.by_orientation.items() if name != "rot0"}
    assert len(turned) == 2, cv.table()
    voted, single = cv.in_sample[True][0], cv.in_sample[False][0]
    assert voted >= single + 0.005, cv.table()
    assert cv.f1 >= 0.75 and cv.place_accuracy >= 0.75, cv.table()


def test_paper_method_with_oracle_m(root):
    cases = kth_pairs(root, pipeline="recommended")
    summary = summarise(f1_table(cases, MatchConfig.paper(), M_GRID))
    assert min(summary[a]["oracle"][0] for a in ("malcolm", "vasiliki")) >= 0.60


def test_released_options_reproduce_the_released_accuracy(root):
    cases = kth_pairs(root, pipeline="released")
    summary = summarise(f1_table(cases, MatchConfig.released(), M_GRID, legacy="fnfix"))
    oracle = np.mean([summary[a]["oracle"][0] for a in ("malcolm", "vasiliki")])
    assert abs(oracle - 0.565) <= 0.05, oracle
