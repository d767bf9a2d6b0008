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
