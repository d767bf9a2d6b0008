"""The bundled example pair written by save_example (ursim_core.synth.example)."""

from __future__ import annotations

import json

import numpy as np
from PIL import Image

from ursim_core.correspondences import load_correspondences
from ursim_core.synth import ground_truth_pairs, make_pair, save_example


def test_save_example_writes_loadable_files(tmp_path):
    plan, sketch = make_pair(seed=1)
    save_example(plan, sketch, tmp_path, now="2024-01-01T00:00:00Z")
    for name, free in (("metric.png", plan.free), ("sketch.png", sketch.free)):
        image = Image.open(tmp_path / name)
        assert image.mode == "L"
        assert np.array_equal(np.asarray(image), np.where(free, 255, 0))
    corr = load_correspondences(tmp_path / "ground_truth.json")  # validates against the schema
    assert corr.sketch.path == (tmp_path / "sketch.png").resolve()
    assert corr.sketch.size == sketch.free.shape and corr.metric.size == plan.free.shape
    pairs = ground_truth_pairs(plan, sketch)
    assert [(list(c.sketch_points), list(c.metric_points)) for c in corr.cliques] == pairs
    document = json.loads((tmp_path / "ground_truth.json").read_text())
    assert document["format"] == "ursim-correspondences" and document["version"] == 1
    assert document["cliques"][0]["note"] == "place 1 corridor"
    # Same input, same timestamp: the same bytes (tools/make_example.py relies on it).
    first = (tmp_path / "ground_truth.json").read_bytes()
    save_example(plan, sketch, tmp_path, now="2024-01-01T00:00:00Z")
    assert (tmp_path / "ground_truth.json").read_bytes() == first
