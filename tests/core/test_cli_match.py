"""``ursim match`` and ``ursim convert`` end to end on a small generated pair."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from ursim_core.cli import main
from ursim_core.correspondences import load_correspondences, load_dat


def building(scale: float = 1.0) -> np.ndarray:
    """A corridor with four rooms of different sizes above and below it."""
    s = lambda v: int(round(v * scale))
    image = np.zeros((s(260), s(420)), np.uint8)
    image[s(110) : s(150), s(10) : s(410)] = 255  # corridor
    rooms = [(10, 100, 10, 140), (10, 100, 150, 400), (160, 250, 10, 250), (160, 250, 260, 330)]
    for r0, r1, c0, c1 in rooms:
        image[s(r0) : s(r1), s(c0) : s(c1)] = 255
        door = (c0 + c1) // 2
        if r1 <= 110:
            image[s(r1) : s(110), s(door - 5) : s(door + 5)] = 255
        else:
            image[s(150) : s(r0), s(door - 5) : s(door + 5)] = 255
    return image


@pytest.fixture()
def pair(tmp_path):
    sketch, metric = tmp_path / "sketch.png", tmp_path / "metric.png"
    cv2.imwrite(str(metric), building())
    cv2.imwrite(str(sketch), building(1.3))
    return sketch, metric


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


def test_convert_round_trip(tmp_path, pair):
    dat = tmp_path / "gt.dat"
    dat.write_text(
        "# sketch.png metric.png\n# 0match set\n# map1\n30 60\n# map2\n25 50\n\n# 1match set\n# map1\n# map2\n"
    )
    json_path, back = tmp_path / "gt.json", tmp_path / "back.dat"
    assert main(["convert", str(dat), str(json_path), "--sketch", str(pair[0]), "--metric", str(pair[1])]) == 0
    corr = load_correspondences(json_path)
    assert corr.cliques[0].sketch_points == ((30, 60),) and corr.cliques[0].sketch_regions
    assert main(["convert", str(json_path), str(back)]) == 0
    assert [c.sketch_points for c in load_dat(back).cliques] == [c.sketch_points for c in load_dat(dat).cliques]


def test_convert_bad_input(tmp_path, capsys):
    (tmp_path / "bad.json").write_text("{not json")
    assert main(["convert", str(tmp_path / "bad.json"), str(tmp_path / "x.dat")]) == 1
    assert "bad.json" in capsys.readouterr().err
    assert main(["convert", str(tmp_path / "bad.json"), str(tmp_path / "x.txt")]) == 1


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
