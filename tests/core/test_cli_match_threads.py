"""`ursim match` loads and segments its two maps on two threads: errors as one step after the other."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from test_cli import two_rooms

from ursim_core.cli import main


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

    sketch, metric = two_rooms(tmp_path / "a.png"), two_rooms(tmp_path / "b.png")
    args = SimpleNamespace(
        threshold=250, nonzero_free=False, max_pixels=64_000_000, sketch_preset="sketch", metric_preset="default"
    )
    *_, sketch_seg, metric_seg = load_and_segment(sketch, metric, args, params={}, canonical=True)
    alone = segment_checked(load(sketch, args), preset="sketch", params={}, canonical=True)
    assert np.array_equal(sketch_seg.labels, alone.labels)
    assert np.array_equal(metric_seg.labels, segment_checked(load(metric, args), preset="default", params={}).labels)
