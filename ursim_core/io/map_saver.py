"""A map_server YAML file and its image, as nav2's ``map_saver`` writes them.

:func:`save_map_yaml` writes what nav2's ``map_saver`` writes for each mode, so
:func:`~ursim_core.io.maps.load_map` (or nav2's map_server) reads the same grid back:

- ``trinary``: free 254, occupied 0, unknown 205, 8-bit PGM. The default ``free_thresh`` is
  0.196 (ROS 1 map_saver's value), not nav2's 0.25: with 0.25 nav2 reads its own unknown grey
  205 (occ = 0.196) back as *free*, so a saved map would lose its unknown space.
- ``scale``: grey ``(100 - cell) / 100``, unknown transparent, RGBA PNG (nav2 writes
  TrueColorMatte; PGM has no alpha).
- ``raw``: grey = cell value, unknown 255, 8-bit PGM; exact for every value.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.io.atomic import atomic_write_bytes, atomic_write_text
from ursim_core.io.maps import Map
from ursim_core.io.occupancy_grid import (
    TRINARY_FREE,
    TRINARY_OCCUPIED,
    TRINARY_UNKNOWN,
    OccupancyGrid,
    _is_real,
    occupancy_grid_from_map,
)

__all__ = ["save_map_yaml", "SAVE_MODES", "SAVE_DEFAULTS"]

#: Modes of :func:`save_map_yaml`, as nav2's map_saver.
SAVE_MODES = ("trinary", "scale", "raw")
#: Thresholds written by :func:`save_map_yaml` (see the module docstring for 0.196).
SAVE_DEFAULTS = {"free_thresh": 0.196, "occupied_thresh": 0.65}


def save_map_yaml(
    source: Map | OccupancyGrid,
    yaml_path: str | Path,
    *,
    mode: str = "trinary",
    free_thresh: float = SAVE_DEFAULTS["free_thresh"],
    occupied_thresh: float = SAVE_DEFAULTS["occupied_thresh"],
    resolution: float | None = None,
    origin: Sequence[float] | None = None,
    image_name: str | None = None,
) -> Path:
    """Write a map_server YAML file and its image beside it, as nav2's map_saver does.

    Parameters
    ----------
    source : Map or OccupancyGrid
        A map (a drawn sketch, a label map's free mask, a loaded ROS map) or a grid.
    yaml_path : str or Path
        The YAML file to write; the image goes into the same folder.
    mode : {"trinary", "scale", "raw"}, keyword-only
        How cells become grey values (see the module docstring). ``trinary`` and ``raw`` write
        an 8-bit PGM, ``scale`` an RGBA PNG (unknown cells transparent).
    free_thresh, occupied_thresh : float, keyword-only
        Written to the YAML; in trinary mode cells ``<= rint(100 * free_thresh)`` are drawn free
        and cells ``>= rint(100 * occupied_thresh)`` occupied, as nav2 does.
    resolution, origin : keyword-only
        For a map without them (see :func:`occupancy_grid_from_map`).
    image_name : str, keyword-only
        File name of the image (default: the YAML's stem + ``.pgm`` / ``.png``).

    Returns
    -------
    Path
        The image written. Both files are written atomically, the image first.

    Raises
    ------
    ParameterError
        An unknown mode, thresholds outside ``0 <= free < occupied <= 1``, or no resolution.

    Examples
    --------
    >>> import tempfile
    >>> from ursim_core.io.maps import load_map
    >>> grid = OccupancyGrid(data=[0, 0, 100, -1], width=2, height=2, resolution=0.05)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     image = save_map_yaml(grid, Path(folder) / "room.yaml")
    ...     again = occupancy_grid_from_map(load_map(Path(folder) / "room.yaml"))
    >>> image.name, again == grid
    ('room.pgm', True)
    """
    if mode not in SAVE_MODES:
        raise ParameterError(f"mode must be one of {', '.join(SAVE_MODES)}, got {mode!r}", field="mode")
    for name, value in (("free_thresh", free_thresh), ("occupied_thresh", occupied_thresh)):
        if not _is_real(value) or not 0.0 <= value <= 1.0:
            raise ParameterError(f"{name} must be a number in [0, 1], got {value!r}", field=name)
    if free_thresh >= occupied_thresh:
        raise ParameterError(
            f"free_thresh ({free_thresh}) must be below occupied_thresh ({occupied_thresh})", field="free_thresh"
        )
    grid = source if isinstance(source, OccupancyGrid) else occupancy_grid_from_map(source, resolution=resolution)
    if origin is not None:
        grid = OccupancyGrid(grid.data, grid.width, grid.height, grid.resolution, tuple(origin), grid.frame_id)
    yaml_path = Path(yaml_path)
    suffix = ".png" if mode == "scale" else ".pgm"
    image_path = yaml_path.with_name(image_name or (yaml_path.stem + suffix))
    cells = grid.cells()
    image_bytes = _encode_cells(cells, mode=mode, free_thresh=free_thresh, occupied_thresh=occupied_thresh)
    atomic_write_bytes(image_path, image_bytes)
    atomic_write_text(yaml_path, _yaml_text(grid, image_path.name, mode, free_thresh, occupied_thresh))
    return image_path


def _encode_cells(cells: np.ndarray, *, mode: str, free_thresh: float, occupied_thresh: float) -> bytes:
    from PIL import Image

    cells = cells.astype(np.int16)
    unknown = (cells < 0) | (cells > 100)
    if mode == "trinary":
        free_int, occupied_int = round(free_thresh * 100.0), round(occupied_thresh * 100.0)
        grey = np.full(cells.shape, TRINARY_UNKNOWN, np.uint8)
        grey[~unknown & (cells <= free_int)] = TRINARY_FREE
        grey[~unknown & (cells >= occupied_int)] = TRINARY_OCCUPIED
        image = Image.fromarray(grey, mode="L")
        file_format = "PPM"  # Pillow writes 8-bit grey as binary PGM (P5)
    elif mode == "raw":
        grey = np.where(unknown, 255, np.clip(cells, 0, 100)).astype(np.uint8)
        image = Image.fromarray(grey, mode="L")
        file_format = "PPM"
    else:
        # GraphicsMagick rounds the double (100 - cell) / 100 to the nearest 8-bit value.
        grey = np.floor((100.0 - np.clip(cells, 0, 100)) / 100.0 * 255.0 + 0.5).astype(np.uint8)
        grey[unknown] = 128
        rgba = np.dstack([grey, grey, grey, np.where(unknown, 0, 255).astype(np.uint8)])
        image = Image.fromarray(rgba, mode="RGBA")
        file_format = "PNG"
    buffer = io.BytesIO()
    image.save(buffer, format=file_format)
    return buffer.getvalue()


def _yaml_text(grid: OccupancyGrid, image_name: str, mode: str, free_thresh: float, occupied_thresh: float) -> str:
    import yaml

    x, y, yaw = grid.origin
    # Keys in map_saver's order; repr() of a float round-trips exactly (nav2 writes 3 digits,
    # which would move the origin by up to half a millimetre).
    lines = [
        f"image: {yaml.safe_dump(image_name, default_style=None).splitlines()[0]}",
        f"mode: {mode}",
        f"resolution: {grid.resolution!r}",
        f"origin: [{x!r}, {y!r}, {yaw!r}]",
        "negate: 0",
        f"occupied_thresh: {float(occupied_thresh)!r}",
        f"free_thresh: {float(free_thresh)!r}",
    ]
    return "\n".join(lines) + "\n"
