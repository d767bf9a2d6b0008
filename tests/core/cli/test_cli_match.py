"""``ursim match`` (ursim_core.cli.match) end to end: outputs, options, reviews, references, its two threads."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from cli_helpers import building, building_pair, two_rooms

from ursim_core.cli import main
from ursim_core.correspondences import load_correspondences


@pytest.fixture()
def pair(tmp_path):
    return building_pair(tmp_path)


def test_match_writes_all_outputs(tmp_path, pair):
    out = tmp_path / "out"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(out)]) == 0
    corr = load_correspondences(out / "correspondences.json")
    sketch_labels = cv2.imread(str(out / "sketch.labels.png"), cv2.IMREAD_UNCHANGED)
    metric_labels = cv2.imread(str(out / "metric.labels.png"), cv2.IMREAD_UNCHANGED)
    assert sketch_labels.dtype == np.uint16 and metric_labels.dtype == np.uint16
    assert corr.cliques, "a scaled copy of the map must give matches"
    for clique in corr.cliques:
        assert clique.source == "auto"
        (s_region,), (m_region,) = clique.sketch_regions, clique.metric_regions
        (s_row, s_col), (m_row, m_col) = clique.sketch_points[0], clique.metric_points[0]
        assert sketch_labels[s_row, s_col] == s_region and metric_labels[m_row, m_col] == m_region
    raw = json.loads((out / "correspondences.json").read_text())
    assert raw["maps"]["sketch"]["sha256"] and raw["matcher"]["m"] is not None
    figure = cv2.imread(str(out / "matches.png"))
    assert figure.shape[1] > sketch_labels.shape[1]


def test_match_scaled_copy_is_mostly_right(tmp_path, pair):
    from ursim_core.segmentation.graph import region_graph

    out = tmp_path / "out"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(out)]) == 0
    corr = load_correspondences(out / "correspondences.json")
    sketch_labels = cv2.imread(str(out / "sketch.labels.png"), cv2.IMREAD_UNCHANGED).astype(np.int32)
    metric_labels = cv2.imread(str(out / "metric.labels.png"), cv2.IMREAD_UNCHANGED).astype(np.int32)
    centroids = dict(region_graph(sketch_labels).nodes(data="centroid"))
    right = 0
    for clique in corr.cliques:
        (s_region,), (m_region,) = clique.sketch_regions, clique.metric_regions
        row, col = centroids[s_region]
        right += metric_labels[round(row / 1.3), round(col / 1.3)] == m_region
    assert len(corr.cliques) == 5 and right == 5


@pytest.mark.parametrize("option", [["--m", "0.1"], ["--variant", "T2"], ["--matcher", "hungarian"], ["--released"]])
def test_match_options(tmp_path, pair, option):
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(tmp_path / "o"), *option]) == 0


def test_match_bad_m_is_an_input_error(tmp_path, pair, capsys):
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(tmp_path / "o"), "--m", "lots"]) == 1
    assert "--m" in capsys.readouterr().err


def test_match_overlay_with_a_known_scale_lays_a_crop_back(tmp_path, capsys):
    full = building()
    part = full[:, 140:].copy()  # the right-hand part of the building only
    cv2.imwrite(str(tmp_path / "full.png"), full)
    cv2.imwrite(str(tmp_path / "part.png"), part)
    args = ["match", str(tmp_path / "part.png"), str(tmp_path / "full.png"), "-o", str(tmp_path / "out")]
    assert main(args + ["--matcher", "overlay", "--scale", "1", "--mirrored", "no"]) == 0
    document = json.loads((tmp_path / "out" / "correspondences.json").read_text())
    assert document["matcher"]["config"]["matcher"] == "overlay" and document["matcher"]["config"]["scale"] == 1.0
    assert len(document["cliques"]) >= 3
    assert main(args + ["--matcher", "overlay", "--scale", "0"]) != 0
    assert "scale" in capsys.readouterr().err


def test_match_overlay_reads_the_scale_of_two_ros_maps(tmp_path):
    full = building()
    half = cv2.resize(full[:, 140:], None, fx=0.5, fy=0.5, interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(tmp_path / "full.png"), full)
    cv2.imwrite(str(tmp_path / "half.png"), half)
    for name, resolution in (("full", 0.05), ("half", 0.1)):
        (tmp_path / f"{name}.yaml").write_text(
            f"image: {name}.png\nresolution: {resolution}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
        )
    out = tmp_path / "out"
    args = ["match", str(tmp_path / "half.yaml"), str(tmp_path / "full.yaml"), "-o", str(out), "--matcher", "overlay"]
    assert main(args + ["--mirrored", "no"]) == 0
    document = json.loads((out / "correspondences.json").read_text())
    assert document["matcher"]["config"]["scale"] == pytest.approx(2.0)
    assert len(document["cliques"]) >= 3
    # With no --matcher, the known scale makes the default (auto) the overlay matcher, not mirrored.
    assert main(args[:-2]) == 0
    default = json.loads((out / "correspondences.json").read_text())
    assert default["matcher"]["config"]["scale"] == pytest.approx(2.0)
    assert default["cliques"] == document["cliques"]


def test_match_a_metric_input_of_unknown_scale(tmp_path):
    full = building()
    part = cv2.resize(full[:, 140:], None, fx=0.7, fy=0.7, interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(tmp_path / "full.png"), full)
    cv2.imwrite(str(tmp_path / "part.png"), part)
    out = tmp_path / "out"
    assert (
        main(
            ["match", str(tmp_path / "part.png"), str(tmp_path / "full.png"), "-o", str(out), "--input-kind", "metric"]
        )
        == 0
    )
    document = json.loads((out / "correspondences.json").read_text())
    config = document["matcher"]["config"]
    assert config["input_kind"] == "metric" and config["scale"] is None
    assert len(document["cliques"]) >= 3


def test_match_again_on_a_review_keeps_it_and_builds_on_it(tmp_path, pair, capsys):
    import dataclasses

    from ursim_core.correspondences import save_correspondences

    first = tmp_path / "first"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(first)]) == 0
    corr = load_correspondences(first / "correspondences.json")
    accepted, rejected = corr.cliques[0], corr.cliques[1]
    reviewed = corr.with_cliques(
        [
            dataclasses.replace(accepted, status="accepted", note="checked"),
            dataclasses.replace(rejected, status="rejected"),
            *corr.cliques[2:],
        ]
    )
    save_correspondences(reviewed, tmp_path / "reviewed.json")

    again = tmp_path / "again"
    assert (
        main(["match", str(pair[0]), str(pair[1]), "-o", str(again), "--review", str(tmp_path / "reviewed.json")]) == 0
    )
    cliques = load_correspondences(again / "correspondences.json").cliques
    kept = [c for c in cliques if c.status in ("accepted", "rejected")]
    assert [(c.id, c.status, c.note) for c in kept] == [
        (accepted.id, "accepted", "checked"),
        (rejected.id, "rejected", ""),
    ]
    new = [(c.sketch_regions, c.metric_regions) for c in cliques if c.status is None]
    assert (rejected.sketch_regions, rejected.metric_regions) not in new
    assert all(accepted.sketch_regions[0] not in s and accepted.metric_regions[0] not in m for s, m in new)
    assert len({c.id for c in cliques}) == len(cliques)

    capsys.readouterr()
    assert (
        main(["match", str(pair[0]), str(pair[1]), "-o", str(again), "--review", str(tmp_path / "nothere.json")]) == 1
    )
    assert "nothere.json: " in capsys.readouterr().err


def test_a_review_with_a_matcher_that_takes_no_constraints_is_kept_as_it_is(tmp_path, pair, capsys):
    import dataclasses

    from ursim_core.correspondences import save_correspondences

    first = tmp_path / "first"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(first)]) == 0
    corr = load_correspondences(first / "correspondences.json")
    reviewed = corr.with_cliques([dataclasses.replace(corr.cliques[0], status="accepted")])
    save_correspondences(reviewed, tmp_path / "reviewed.json")
    capsys.readouterr()
    out = tmp_path / "vf2"
    args = ["match", str(pair[0]), str(pair[1]), "-o", str(out), "--matcher", "vf2", "--review"]
    assert main([*args, str(tmp_path / "reviewed.json")]) == 0
    assert "the vf2 matcher does not take the review's pairs" in capsys.readouterr().err
    cliques = load_correspondences(out / "correspondences.json").cliques
    assert [(c.id, c.status) for c in cliques if c.status] == [(corr.cliques[0].id, "accepted")]


def test_a_review_or_reference_of_another_pair_is_named_as_such(tmp_path, pair, capsys):
    first = tmp_path / "first"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(first)]) == 0
    other = tmp_path / "other.png"
    cv2.imwrite(str(other), building(1.1))
    for option in ("--review", "--reference"):
        capsys.readouterr()
        args = ["match", str(other), str(pair[1]), "-o", str(tmp_path / "x"), option]
        assert main([*args, str(first / "correspondences.json")]) == 1
        err = capsys.readouterr().err
        assert "correspondences.json: made on a sketch map of 338x546 px (sketch.png)" in err
        assert "a file of another pair?" in err


# --------------------------------------------------------------------------- the two maps loaded and segmented on two threads


def _white(path: Path) -> Path:
    # Every pixel free: it loads, but MAORIS finds no wall and so no region.
    cv2.imwrite(str(path), np.full((60, 60), 255, np.uint8))
    return path


def test_when_both_maps_fail_the_sketch_is_named(tmp_path, capsys):
    sketch, metric = _white(tmp_path / "sketch_white.png"), _white(tmp_path / "metric_white.png")
    assert main(["match", str(sketch), str(metric), "-o", str(tmp_path / "out")]) == 1
    error = capsys.readouterr().err
    assert "sketch_white.png" in error and "metric_white.png" not in error
    assert not (tmp_path / "out" / "correspondences.json").exists()


def test_a_missing_metric_map_fails_before_any_segmentation(tmp_path, capsys):
    sketch = two_rooms(tmp_path / "rooms.png")
    assert main(["match", str(sketch), str(tmp_path / "missing.png"), "-o", str(tmp_path / "out")]) == 1
    assert "missing.png" in capsys.readouterr().err
    assert not (tmp_path / "out" / "sketch.labels.png").exists()


def test_threads_give_the_outputs_of_one_step_after_the_other(tmp_path):
    from types import SimpleNamespace

    from ursim_core.cli.common import load
    from ursim_core.cli.match import load_and_segment
    from ursim_core.cli.segment import segment_checked
    from ursim_core.matching import MatchConfig

    sketch, metric = two_rooms(tmp_path / "a.png"), two_rooms(tmp_path / "b.png")
    args = SimpleNamespace(
        threshold=250, nonzero_free=False, max_pixels=64_000_000, sketch_preset="sketch", metric_preset="default"
    )
    _, _, sketch_seg, metric_seg, _ = load_and_segment(sketch, metric, args, MatchConfig(), params={})
    alone = segment_checked(load(sketch, args), preset="sketch", params={}, canonical=True, resampled=True)
    assert np.array_equal(sketch_seg.labels, alone.labels)
    assert np.array_equal(metric_seg.labels, segment_checked(load(metric, args), preset="default", params={}).labels)


def test_a_turned_sketch_is_matched_in_its_resamplings_and_voted(tmp_path, capsys):
    from ursim_core.segmentation.canonical import _turned
    from ursim_core.synth import make_pair

    plan, sketch = make_pair(seed=5)
    turned, _ = _turned(sketch.free, 25.0)
    cv2.imwrite(str(tmp_path / "sketch.png"), turned.astype(np.uint8) * 255)
    cv2.imwrite(str(tmp_path / "plan.png"), plan.free.astype(np.uint8) * 255)
    out = tmp_path / "out"
    assert main(["match", str(tmp_path / "sketch.png"), str(tmp_path / "plan.png"), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "voted over 6 resamplings" in printed
    corr = load_correspondences(out / "correspondences.json")
    assert corr.extra["matcher"]["config"]["resampling_vote"] is True
    # The reading ranked next, printed and kept in the file: another reading, ranked no better
    # over the ten segmentations (the score rule chose the best).
    runner_up = corr.extra["matcher"]["next_reading"]
    chosen = corr.extra["matcher"]["orientation"]
    assert runner_up["ranked_worse_by"] >= 0 and (runner_up["degrees"], runner_up["mirrored"]) != (
        chosen["degrees"],
        chosen["mirrored"],
    )
    assert f"next best reading: turned {runner_up['degrees']:.1f} deg" in printed
    # Every reading ranked, for the app to show side by side: the chosen one first, then the
    # runner-up, then the others ranked no better.
    readings = corr.extra["matcher"]["readings"]
    assert readings[0] == {**chosen, "ranked_worse_by": 0.0} and readings[1] == runner_up
    assert [r["ranked_worse_by"] for r in readings[1:]] == sorted(r["ranked_worse_by"] for r in readings[1:])
    # The voted pairs are in the regions of the label image written beside them.
    labels = cv2.imread(str(out / "sketch.labels.png"), cv2.IMREAD_UNCHANGED)
    assert {r for c in corr.cliques for r in c.sketch_regions} <= set(np.unique(labels).tolist()) - {0}


def test_a_told_orientation_has_no_runner_up(tmp_path, pair, capsys):
    out = tmp_path / "out"
    assert main(["match", str(pair[0]), str(pair[1]), "-o", str(out), "--orientation", "upright"]) == 0
    assert "next best reading" not in capsys.readouterr().out
    record = load_correspondences(out / "correspondences.json").extra["matcher"]
    assert "next_reading" not in record and "readings" not in record


def test_any_matching_option_is_set_with_set_and_a_wrong_one_is_refused_first(tmp_path, capsys):
    sketch, metric = two_rooms(tmp_path / "a.png"), two_rooms(tmp_path / "b.png")
    out = tmp_path / "out"
    argv = ["match", str(sketch), str(metric), "-o", str(out)]
    assert main([*argv, "--set", "vote_orientations=first", "--set", "orientation_finalists=2"]) == 0
    config = load_correspondences(out / "correspondences.json").extra["matcher"]["config"]
    assert config["vote_orientations"] == "first" and config["orientation_finalists"] == 2
    capsys.readouterr()
    for wrong, message in (
        ("nonsense=1", "unknown matching option 'nonsense'"),
        ("vote_orientations=sideways", "must be one of"),
        ("novalue", "expected NAME=VALUE"),
    ):
        elsewhere = tmp_path / wrong.replace("=", "_")
        assert main(["match", str(sketch), str(metric), "-o", str(elsewhere), "--set", wrong]) == 1
        assert message in capsys.readouterr().err
        assert not elsewhere.exists()  # refused before any work


def test_partial_tells_the_matcher_the_sketch_shows_part_of_the_map(tmp_path):
    from ursim_core.matching.config import PARTIAL_SKETCH

    sketch, metric = two_rooms(tmp_path / "a.png"), two_rooms(tmp_path / "b.png")
    argv = ["match", str(sketch), str(metric)]
    assert main([*argv, "-o", str(tmp_path / "partial"), "--partial"]) == 0
    config = load_correspondences(tmp_path / "partial" / "correspondences.json").extra["matcher"]["config"]
    assert {name: config[name] for name in PARTIAL_SKETCH} == PARTIAL_SKETCH
    # --set still wins over it, as over the other options.
    assert main([*argv, "-o", str(tmp_path / "set"), "--partial", "--set", "elastic_laying=window"]) == 0
    config = load_correspondences(tmp_path / "set" / "correspondences.json").extra["matcher"]["config"]
    assert config["elastic_laying"] == "window" and config["window_reading_margin"] == 0.1
    assert main([*argv, "-o", str(tmp_path / "whole")]) == 0
    config = load_correspondences(tmp_path / "whole" / "correspondences.json").extra["matcher"]["config"]
    assert config["window_reading_margin"] == 0 and config["elastic_laying"] == "window"
