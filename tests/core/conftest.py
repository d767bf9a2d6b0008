"""Fixtures shared by the core tests: a small generated dataset in the KTH layout."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

# The synthetic dataset: used by evaluation/test_evaluation_runner.py (which also reads _plan and
# SKETCH_SCALES: keep its copies alike), evaluation/test_distributed.py and cli/test_cli_evaluate.py.

# Three rooms of different sizes in a row joined by doors; (row, col) centres of the rooms.
ROOM_CENTRES = ((35, 30), (35, 85), (25, 150))


def _plan(scale: float) -> np.ndarray:
    def s(value):
        return int(round(value * scale))

    free = np.zeros((s(70), s(190)), bool)
    free[s(5) : s(65), s(5) : s(55)] = True
    free[s(15) : s(55), s(65) : s(105)] = True
    free[s(5) : s(45), s(115) : s(185)] = True
    free[s(30) : s(38), s(55) : s(65)] = True
    free[s(20) : s(28), s(105) : s(115)] = True
    return np.where(free, 255, 0).astype(np.uint8)


def _dat_text(sketch_scale: float, model_scale: float, rooms: int) -> str:
    lines = ["# sketch.png model_simple.png"]
    for index, (row, col) in enumerate(ROOM_CENTRES[:rooms]):
        lines += [
            f"# {index}match set",
            "# map1",
            f"{round(row * sketch_scale)} {round(col * sketch_scale)}",
            "# map2",
            f"{round(row * model_scale)} {round(col * model_scale)}",
            "",
        ]
    # The published files end with an empty match set; the legacy fnfix scorer counts it.
    lines += [f"# {rooms}match set", "# map1", "# map2", ""]
    return "\n".join(lines)


MODEL_SCALE = 1.5
SKETCH_SCALES = {"copy": MODEL_SCALE, "small": 1.0}


@pytest.fixture(scope="module")
def synthetic_dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("synthetic_kth")
    (root / "sketches").mkdir()
    (root / "model").mkdir()
    Image.fromarray(_plan(MODEL_SCALE)).save(root / "model" / "model_simple.png")
    for name, scale in SKETCH_SCALES.items():
        Image.fromarray(_plan(scale)).save(root / "sketches" / f"{name}.png")
        # malcolm annotated the three rooms, vasiliki only the first two.
        for annotator, rooms in (("malcolm", 3), ("vasiliki", 2)):
            folder = root / "gt_correspondences" / annotator
            folder.mkdir(parents=True, exist_ok=True)
            (folder / f"gt_{name}_model_simple.dat").write_text(_dat_text(scale, MODEL_SCALE, rooms))
    return root
