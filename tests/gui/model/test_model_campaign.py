"""Campaigns (ursim_gui.model.campaign): the pairs of a plain folder or a manifest, and where their files go."""

from __future__ import annotations

import json

import pytest

from ursim_core.errors import FormatError
from ursim_gui.model.campaign import open_campaign


def test_plain_folder_and_manifest_campaigns(plain_campaign, tmp_path):
    campaign = open_campaign(plain_campaign, annotator="ann", data_dir=tmp_path / "data")
    assert [p.name for p in campaign.pairs] == ["s1", "s2", "s3"]
    assert campaign.output_dir == plain_campaign / "ursim_annotations" / "ann"  # the naming rule
    assert {p.metric.name for p in campaign.pairs} == {"metric.png"}
    manifest = tmp_path / "campaign.json"
    manifest.write_text(
        json.dumps({"metric": "plain/metric.png", "sketches": ["plain/s2.png"], "annotator": "bo", "output": "out"})
    )
    from_manifest = open_campaign(manifest)
    assert [p.name for p in from_manifest.pairs] == ["s2"] and from_manifest.annotator == "bo"
    assert from_manifest.pairs[0].output == tmp_path / "out" / "s2.json"
    (plain_campaign / "metric.png").rename(plain_campaign / "other.png")
    with pytest.raises(FormatError, match="exactly one metric map"):
        open_campaign(plain_campaign, data_dir=tmp_path / "data")


def _record(gap: float | None, orientation="any") -> dict:
    record = {"config": {"orientation": orientation}, "orientation": {"degrees": 90.0, "mirrored": True}}
    if gap is not None:
        record["next_reading"] = {"degrees": 270.0, "mirrored": True, "ranked_worse_by": gap}
    return record


def test_a_pair_says_how_its_sketch_was_read_and_whether_that_was_a_close_call():
    from ursim_core.correspondences import Correspondences
    from ursim_core.matching.orientation import CLOSE_READING
    from ursim_gui.model.campaign import PairSummary, summary_of

    def summary(record) -> PairSummary:
        return summary_of(Correspondences(extra={} if record is None else {"matcher": record}))

    assert summary(_record(0.25)) == PairSummary("automatic", 0, 0, "turned 90°, mirrored · next ranked 25.0% worse")
    close = summary(_record(CLOSE_READING / 2))
    assert close.close_call and close.reading.endswith(f"next ranked {CLOSE_READING / 2:.1%} worse")
    assert not summary(_record(CLOSE_READING)).close_call
    assert summary(_record(-0.01)).close_call  # a vote chose a reading another one outranked
    assert summary(_record(None)) == PairSummary("automatic", 0, 0, "turned 90°, mirrored")  # no runner-up
    # Told the orientation, or no match made the file: nothing to say.
    assert summary(_record(0.001, orientation=90.0)).reading == summary(None).reading == ""


def test_a_pairs_file_says_its_reading(tmp_path):
    from ursim_core.correspondences import Correspondences, save_correspondences
    from ursim_gui.model.campaign import pair_summary

    path = tmp_path / "pair.json"
    save_correspondences(Correspondences(extra={"matcher": _record(0.001)}), path)
    assert pair_summary(path).close_call and pair_summary(path).reading.startswith("turned 90°, mirrored")
    assert pair_summary(tmp_path / "none.json").reading == ""


def test_a_manifest_nested_deep_or_repeating_a_key_is_refused_naming_it(tmp_path):
    # It was read with read_text + json.loads: deep nesting raised RecursionError (a traceback),
    # and a repeated key silently kept the last value.
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 5000 + "]" * 5000)
    with pytest.raises(FormatError, match="nested deeper") as raised:
        open_campaign(deep)
    assert raised.value.path == deep
    twice = tmp_path / "twice.json"
    twice.write_text('{"metric": "a.png", "metric": "b.png", "sketches": []}')
    with pytest.raises(FormatError, match="'metric' appears twice"):
        open_campaign(twice)


def test_a_campaign_that_is_not_there_is_also_a_file_not_found_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="campaign not found") as raised:
        open_campaign(tmp_path / "gone")
    assert isinstance(raised.value, FormatError) and raised.value.path == tmp_path / "gone"
