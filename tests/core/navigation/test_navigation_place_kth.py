"""Bar of issue 15: `ursim goal` at every GT sketch point of the 18 KTH sketches (upright and turned)
lands in the GT place exactly as often as place accuracy (issue 11) says: one rule, `locate`.

Place accuracy, as defined in issue 11: for every reference clique with points on both sides and
every sketch point p of it, the goal of p (`locate`: region of p in the matcher's sketch
segmentation, 10 px rule; interior point of the largest metric region matched to it) succeeds
when it lies in the clique's place, the union of the regions of the reference segmentation of
the model (MAORIS `default`) under the clique's metric points. Mean over the clique's points,
then over cliques, then over (sketch, annotator) pairs.
"""

from __future__ import annotations

import argparse
import json
import statistics

import numpy as np
import pytest
from PIL import Image

from ursim_core.cli import goal as goal_cli
from ursim_core.correspondences import load_dat, regions_at_points
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.io.maps import load_map
from ursim_core.matching import match_maps
from ursim_core.navigation.goal import locate, match_table
from ursim_core.segmentation import segment

ROOT = dataset_root()
pytestmark = [
    pytest.mark.dataset,
    pytest.mark.slow,
    pytest.mark.skipif(ROOT is None, reason=MISSING_REASON),
]
ANNOTATORS = ("malcolm", "vasiliki")


def kth_folder():
    return ROOT / "ursim_kth_sketches"


def turned_point(point, shape, quarter_turns):
    """Where pixel (row, col) of an image of ``shape`` goes under np.rot90(image, k)."""
    row, col = point
    rows, cols = shape
    for _ in range(quarter_turns % 4):
        row, col, rows, cols = cols - 1 - col, row, cols, rows
    return row, col


def cliques_with_both_sides(name):
    result = []
    for annotator in ANNOTATORS:
        path = kth_folder() / "gt_correspondences" / annotator / f"gt_{name}_model_simple.dat"
        result += [(annotator, c) for c in load_dat(path).cliques if c.sketch_points and c.metric_points]
    return result


def place_hits(goal_pixels, clique, reference_labels):
    place = {r for r in regions_at_points(reference_labels, clique.metric_points) if r != 0}
    return [pixel is not None and int(reference_labels[tuple(pixel)]) in place for pixel in goal_pixels]


def run_goal_cli(argv, capsys):
    parser = argparse.ArgumentParser(prog="ursim")
    goal_cli.add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    code = args.handler(args)
    documents = json.loads(capsys.readouterr().out)
    return code, documents if isinstance(documents, list) else [documents]


@pytest.fixture(scope="module")
def reference_labels():
    return segment(load_map(kth_folder() / "model" / "model_simple.png"), preset="default").labels


@pytest.mark.parametrize("quarter_turns", [0, 1, 2, 3])
def test_ursim_goal_lands_in_the_place_as_often_as_place_accuracy_says(
    tmp_path, capsys, reference_labels, quarter_turns
):
    model_path = kth_folder() / "model" / "model_simple.png"
    metric_map = load_map(model_path)
    accuracies = []
    for sketch_path in sorted((kth_folder() / "sketches").glob("*.png")):
        image = np.asarray(Image.open(sketch_path))
        turned_path = tmp_path / sketch_path.name
        Image.fromarray(np.ascontiguousarray(np.rot90(image, quarter_turns))).save(turned_path)
        cliques = cliques_with_both_sides(sketch_path.stem)
        points = [turned_point(p, image.shape[:2], quarter_turns) for _, c in cliques for p in c.sketch_points]

        # Place accuracy's side: locate() on the matcher's own segmentations, in process (the
        # pipeline of ursim match, which ursim goal runs too).
        found = match_maps(load_map(turned_path), metric_map)
        table = match_table(found.result)
        located = [
            locate(table, found.sketch_seg, found.metric_seg, None, r, c, suggest_nearest=False).pixel
            for r, c in points
        ]

        # The robot's side: the `ursim goal` command at every point.
        argv = ["goal", str(turned_path), str(model_path)] + [f"--at={r},{c}" for r, c in points]
        code, documents = run_goal_cli(argv, capsys)
        commanded = [d["ursim"]["pixel"] for d in documents]
        assert [None if p is None else tuple(p) for p in commanded] == located
        assert code == (1 if any(p is None for p in located) else 0)

        per_clique = {annotator: [] for annotator in ANNOTATORS}
        start = 0
        for annotator, clique in cliques:
            pixels = commanded[start : start + len(clique.sketch_points)]
            start += len(clique.sketch_points)
            per_clique[annotator].append(statistics.mean(place_hits(pixels, clique, reference_labels)))
        assert start == len(points)
        accuracies += [statistics.mean(values) for values in per_clique.values()]
    print(f"\nKTH place accuracy via `ursim goal`, {quarter_turns * 90} degrees: {statistics.mean(accuracies):.3f}")
    assert len(accuracies) == 36
