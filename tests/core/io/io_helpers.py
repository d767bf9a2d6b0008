"""Small map files and the one-line-error check shared by the tests of ursim_core.io."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ursim_core.errors import MapError
from ursim_core.io.maps import load_map
from ursim_core.io.occupancy_grid import OccupancyGrid

# Grey values around the default threshold (250) and 0, the cases binarisation must get right.
GREY = np.array(
    [
        [0, 1, 100, 249, 250, 251],
        [255, 254, 252, 0, 128, 255],
        [250, 251, 0, 255, 10, 200],
    ],
    dtype=np.uint8,
)
GREY_FREE = GREY > 250


def save(image: Image.Image, path: Path, **options) -> Path:
    image.save(path, **options)
    return path


def _png(folder: Path, name: str = "room.png") -> Path:
    grey = np.zeros((8, 8), np.uint8)
    grey[2:6, 2:6] = 255
    path = folder / name
    Image.fromarray(grey).save(path)
    return path


def _yaml(folder: Path, text: str, name: str = "map.yaml") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


VALID_YAML = "image: room.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"


def _refused(path: Path, match: str | None = None) -> str:
    with pytest.raises(MapError) as caught:
        load_map(path)
    message = str(caught.value)
    assert "\n" not in message, message
    assert len(message) < 400, message
    assert str(path) in message, message
    if match is not None:
        assert match in message, message
    return message


# OccupancyGrid cases (test_occupancy_grid, test_map_saver).
SHAPES = [(1, 3), (7, 5), (32, 48)]
YAWS = [0.0, 0.7, -2.5, math.pi]


def random_grid(shape, seed, *, values=(-1, 0, 100), yaw=0.3) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    height, width = shape
    data = rng.choice(np.asarray(values), size=height * width)
    data[0] = 0  # at least one free cell
    return OccupancyGrid(data=data, width=width, height=height, resolution=0.05, origin=(1.5, -2.25, yaw))


def nav2_cell(grey: int, alpha: int | None, *, mode: str, negate: int, free: float, occupied: float) -> int:
    """nav2 loadMapFromFile for one 8-bit grey pixel, written out independently of ursim_core."""
    channels = [grey * 257] * 3
    if mode == "trinary" and alpha is not None:
        channels.append(alpha * 257)
    shade = (sum(channels) / len(channels)) / 65535.0
    occ = shade if negate else 1.0 - shade
    if mode == "raw":
        value = math.floor(shade * 255 + 0.5)
        return value if 0 <= value <= 100 else -1
    if mode == "scale" and alpha is not None and alpha != 255:
        return -1
    if occupied < occ:
        return 100
    if occ < free:
        return 0
    if mode == "trinary":
        return -1
    return min(max(round((occ - free) / (occupied - free) * 100.0), 1), 99)
