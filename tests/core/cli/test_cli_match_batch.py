"""``ursim match-batch``: every pair's outputs as ``ursim match`` writes them, one summary CSV,
a failed pair reported without stopping the others."""

from __future__ import annotations

import csv
import json

import cv2
import pytest
from cli_helpers import building

from ursim_core.cli import main
from ursim_core.cli.match_batch import read_manifest
from ursim_core.errors import FormatError


@pytest.fixture()
def maps(tmp_path):
    cv2.imwrite(str(tmp_path / "metric.png"), building())
    cv2.imwrite(str(tmp_path / "sketch.png"), building(1.3))
    cv2.imwrite(str(tmp_path / "same.png"), building())
    return tmp_path


@pytest.mark.parametrize("workers", [1, 2])
def test_batch_writes_each_pair_and_a_summary(maps, workers):
    (maps / "pairs.csv").write_text(
        "sketch,metric,name\nsketch.png,metric.png,a\nsame.png,metric.png,b\nmissing.png,metric.png,c\n"
    )
    out = maps / "out"
    code = main(["match-batch", str(maps / "pairs.csv"), "-o", str(out), "--workers", str(workers), "--m", "0.3"])
    assert code == 1  # one pair failed
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert [r["name"] for r in rows] == ["a", "b", "c"]
    assert [r["status"] for r in rows] == ["ok", "ok", "failed"]
    assert "missing.png" in rows[2]["error"] and int(rows[0]["n_matches"]) > 0
    # How each sketch was read, and how far behind the reading ranked next came.
    batch_record = json.loads((out / "a" / "correspondences.json").read_text())["matcher"]
    assert float(rows[0]["orientation_degrees"]) == pytest.approx(batch_record["orientation"]["degrees"], abs=1e-5)
    assert rows[0]["orientation_mirrored"] == str(batch_record["orientation"]["mirrored"])
    assert float(rows[0]["next_reading_gap"]) == pytest.approx(batch_record["next_reading"]["ranked_worse_by"])
    assert rows[0]["resampling_votes"] == "0" and rows[2]["next_reading_gap"] == ""
    # Where the pairs came from: the sketch laid and bent onto the map (MatchConfig.elastic).
    assert batch_record["pairs_from"] == rows[0]["pairs_from"] == "laid sketch" and rows[2]["pairs_from"] == ""
    # Laid box onto box: a sketch of the whole map (the default window laying keeps the boxes).
    assert batch_record["laid_by"] == rows[0]["laid_by"] == "boxes" and rows[2]["laid_by"] == ""
    for name in ("a", "b"):
        assert {p.name for p in (out / name).iterdir()} == {
            "correspondences.json",
            "matches.png",
            "sketch.labels.png",
            "metric.labels.png",
        }
    # The same pair through `ursim match` gives the same correspondences.
    single = maps / "single"
    assert main(["match", str(maps / "sketch.png"), str(maps / "metric.png"), "-o", str(single), "--m", "0.3"]) == 0
    one = json.loads((single / "correspondences.json").read_text())
    batch = json.loads((out / "a" / "correspondences.json").read_text())
    assert one["cliques"] == batch["cliques"]


def test_json_manifest_and_names(maps):
    (maps / "pairs.json").write_text(json.dumps([{"sketch": "sketch.png", "metric": "metric.png"}] * 2))
    pairs = read_manifest(maps / "pairs.json")
    assert [p["name"] for p in pairs] == ["001-sketch", "002-sketch"]
    assert pairs[0]["sketch"] == maps / "sketch.png" and pairs[0]["reference"] is None
    assert pairs[0]["review"] is None


def test_a_review_column_reaches_each_pair(maps):
    (maps / "pairs.csv").write_text("sketch,metric,review\nsketch.png,metric.png,done/a.json\nsame.png,metric.png,\n")
    assert [p["review"] for p in read_manifest(maps / "pairs.csv")] == [maps / "done" / "a.json", None]
    out = maps / "out"
    assert main(["match-batch", str(maps / "pairs.csv"), "-o", str(out), "--workers", "1"]) == 1
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert [r["status"] for r in rows] == ["failed", "ok"] and "a.json" in rows[0]["error"]


@pytest.mark.parametrize(
    "name, text",
    [
        ("a.csv", "map,other\nx,y\n"),
        ("b.csv", "sketch,metric\n"),
        ("c.json", "{}"),
        ("d.json", "[{'sketch': 1}]"),
        ("e.csv", "sketch,metric,name\na.png,b.png,x\nc.png,d.png,x\n"),
        ("f.json", '[{"sketch": "a.png", "metric": "b.png", "review": 3}]'),
    ],
)
def test_bad_manifests_are_format_errors(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    with pytest.raises(FormatError) as error:
        read_manifest(tmp_path / name)
    assert name in str(error.value)
