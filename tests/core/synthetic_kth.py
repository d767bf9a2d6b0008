"""The synthetic dataset in the KTH layout that ``synthetic_dataset`` (tests/core/conftest.py) writes:
two sketches of three rooms in a row, a model map, and two annotators' cliques.

A module rather than part of the conftest so that tests can read what the dataset is made of
(``from synthetic_kth import ...``: pytest puts tests/core on the path with its conftest)."""

from __future__ import annotations

import numpy as np

# Three rooms of different sizes in a row joined by doors; (row, col) centres of the rooms.
ROOM_CENTRES = ((35, 30), (35, 85), (25, 150))
MODEL_SCALE = 1.5
#: Sketch name -> the scale it is drawn at (the model map's scale: a copy).
SKETCH_SCALES = {"copy": MODEL_SCALE, "small": 1.0}


def plan_image(scale: float) -> np.ndarray:
    """The three rooms at ``scale``, white free space on black (uint8)."""

    def s(value):
        return int(round(value * scale))

    free = np.zeros((s(70), s(190)), bool)
    free[s(5) : s(65), s(5) : s(55)] = True
    free[s(15) : s(55), s(65) : s(105)] = True
    free[s(5) : s(45), s(115) : s(185)] = True
    free[s(30) : s(38), s(55) : s(65)] = True
    free[s(20) : s(28), s(105) : s(115)] = True
    return np.where(free, 255, 0).astype(np.uint8)


def dat_text(sketch_scale: float, model_scale: float, rooms: int) -> str:
    """The legacy ``.dat`` of cliques of the first ``rooms`` rooms, one point per map."""
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
