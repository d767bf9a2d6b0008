"""Small map files and the one-line-error check shared by the tests of ursim_core.io."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ursim_core.errors import MapError
from ursim_core.io.maps import load_map

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
