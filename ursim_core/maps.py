"""Maps: loading images and ROS map_server YAML files into a binary free-space mask.

Conventions: pixel coordinates are (row, col) with row 0 at the top of the image;
``Map.free`` is True where a robot (or the sketch's reader) can be, False for walls,
outside and unknown space.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Map", "load_map", "map_from_array", "pixel_to_world", "world_to_pixel", "DEFAULT_FREE_THRESHOLD", "DEFAULT_MAX_PIXELS"]

DEFAULT_FREE_THRESHOLD = 250
DEFAULT_MAX_PIXELS = 64_000_000


@dataclass(frozen=True, eq=False)
class Map:
    """A binary map.

    Attributes
    ----------
    free : ndarray of bool, shape (rows, cols)
        True for free space.
    path : Path or None
        The file the map came from (the YAML for ROS maps).
    sha256 : str or None
        Hex digest of the file bytes (of the YAML's image for ROS maps).
    resolution : float or None
        Metres per pixel, when known (ROS maps).
    origin : tuple of float or None
        (x, y, yaw) world pose of the lower-left pixel, when known.
    occupancy : ndarray of int8 or None
        For ROS maps: 0 free, 100 occupied, -1 unknown (trinary view); else None.
    image : ndarray of uint8 or None
        The grey image as loaded (for display), shape (rows, cols).
    """

    free: np.ndarray
    path: Path | None = None
    sha256: str | None = None
    resolution: float | None = None
    origin: tuple[float, float, float] | None = None
    occupancy: np.ndarray | None = field(default=None, repr=False)
    image: np.ndarray | None = field(default=None, repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.free.shape)  # type: ignore[return-value]

    @property
    def name(self) -> str:
        """File name without extension ('map' when there is no file)."""
        return self.path.stem if self.path is not None else "map"
