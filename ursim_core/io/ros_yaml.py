"""ROS map_server YAML maps, read as the navigation2 map loader does.

:func:`read_ros_yaml` follows nav2's ``loadMapYaml`` / ``loadMapFromFile``
(``nav2_map_server/src/map_io.cpp``): the YAML keys, the image relative to the YAML's folder,
and the per-pixel occupancy of the ``trinary``, ``scale`` and ``raw`` modes on a 16-bit scale
as GraphicsMagick Q16 computes it. :func:`ursim_core.io.load_map` turns the result into a
:class:`~ursim_core.io.maps.Map`; its docstring describes the keys and the modes.
"""

from __future__ import annotations

import hashlib
import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ursim_core.errors import MapError
from ursim_core.io.images import Pixels, decode_image, display_grey, read_file_bytes, row_blocks, transparent_mask

__all__ = [
    "RosMap",
    "read_ros_yaml",
    "ROS_SUFFIXES",
    "OCCUPANCY_FREE",
    "OCCUPANCY_OCCUPIED",
    "OCCUPANCY_UNKNOWN",
]

# Values of Map.occupancy (ROS nav_msgs/OccupancyGrid); scale-mode maps also hold 1..99.
OCCUPANCY_FREE = 0
OCCUPANCY_OCCUPIED = 100
OCCUPANCY_UNKNOWN = -1

ROS_SUFFIXES = (".yaml", ".yml")
_ROS_MODES = ("trinary", "scale", "raw")
_ROS_DEFAULTS = {"negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.25, "mode": "trinary"}


@dataclass(frozen=True, eq=False)
class RosMap:
    """A ROS map as read from its YAML file and image, before it becomes a ``Map``.

    ``occupancy`` is int8 (0 free, 100 occupied, -1 unknown, 1..99 in scale mode), row 0 at the
    top; ``image`` the uint8 display grey (transparent pixels 0); ``sha256`` that of the image
    file, the bytes that define the map.
    """

    occupancy: np.ndarray = field(repr=False)
    image: np.ndarray = field(repr=False)
    sha256: str
    resolution: float
    origin: tuple[float, float, float]


def read_ros_yaml(yaml_path: Path, *, max_pixels: int) -> RosMap:
    """Read a ROS map_server YAML file and its image (see :func:`ursim_core.io.load_map`).

    Raises
    ------
    MapError
        The YAML or its image is unreadable or invalid, or the map has no free cell.
    """
    import yaml

    text = read_file_bytes(yaml_path, empty_problem="empty file (0 bytes): not a ROS map YAML")
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise MapError(f"not valid YAML: {error}", path=yaml_path) from None
    if not isinstance(document, dict):
        raise MapError(
            "not a ROS map_server YAML file: expected a mapping with keys image, resolution, "
            f"origin, got {type(document).__name__}",
            path=yaml_path,
        )
    settings = _ros_settings(document, yaml_path)

    image_path = Path(settings["image"])
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path
    if not image_path.exists():
        raise MapError(f"image file not found: {image_path}", path=yaml_path, field="image")
    try:
        data = read_file_bytes(image_path, empty_problem="empty file (0 bytes): zero-size image")
        # nav2 loads through GraphicsMagick without auto-orientation, so EXIF is ignored here.
        pixels = decode_image(data, image_path, max_pixels=max_pixels, apply_exif_orientation=False)
    except MapError as error:
        raise MapError(f"cannot load the image {image_path}: {error.problem}", path=yaml_path, field="image") from error

    occupancy = _nav2_occupancy(
        pixels,
        mode=settings["mode"],
        negate=settings["negate"],
        free_thresh=settings["free_thresh"],
        occupied_thresh=settings["occupied_thresh"],
    )
    free = occupancy == OCCUPANCY_FREE
    if not free.any():
        n_occupied = int(np.count_nonzero(occupancy == OCCUPANCY_OCCUPIED))
        n_unknown = int(np.count_nonzero(occupancy == OCCUPANCY_UNKNOWN))
        raise MapError(
            f"no free cell in {image_path.name} (mode {settings['mode']}, negate {settings['negate']}, "
            f"free_thresh {settings['free_thresh']}): {n_occupied} occupied, {n_unknown} unknown, "
            f"{occupancy.size - n_occupied - n_unknown} intermediate",
            path=yaml_path,
        )
    image = display_grey(pixels)
    transparent = transparent_mask(pixels.alpha)
    if transparent is not None:
        image[transparent] = 0
    return RosMap(
        occupancy=occupancy,
        image=image,
        sha256=hashlib.sha256(data).hexdigest(),
        resolution=settings["resolution"],
        origin=settings["origin"],
    )


def _ros_settings(document: dict, yaml_path: Path) -> dict:
    """Validated map_server keys, with nav2's meaning and the defaults in _ROS_DEFAULTS."""

    def fail(key: str, problem: str) -> MapError:
        return MapError(problem, path=yaml_path, field=key)

    for key in ("image", "resolution", "origin"):
        if key not in document or document[key] is None:
            raise fail(key, f"missing required key '{key}'")

    image = document["image"]
    if not isinstance(image, str) or not image.strip():
        raise fail("image", f"must be a non-empty file path, got {image!r}")

    resolution = document["resolution"]
    if not _is_real_number(resolution) or not math.isfinite(resolution) or resolution <= 0:
        raise fail("resolution", f"must be a positive number (metres per pixel), got {resolution!r}")

    origin = document["origin"]
    if (
        not isinstance(origin, (list, tuple))
        or len(origin) != 3
        or not all(_is_real_number(value) and math.isfinite(value) for value in origin)
    ):
        raise fail("origin", f"must be a list of 3 finite numbers [x, y, yaw], got {origin!r}")

    negate = document.get("negate", _ROS_DEFAULTS["negate"])
    if isinstance(negate, bool):
        negate = int(negate)
    if not isinstance(negate, int) or negate not in (0, 1):
        raise fail("negate", f"must be 0 or 1, got {negate!r}")

    thresholds = {}
    for key in ("occupied_thresh", "free_thresh"):
        value = document.get(key, _ROS_DEFAULTS[key])
        if not _is_real_number(value) or not 0 <= value <= 1:
            raise fail(key, f"must be a number in [0, 1], got {value!r}")
        thresholds[key] = float(value)
    if thresholds["free_thresh"] >= thresholds["occupied_thresh"]:
        raise fail(
            "free_thresh",
            f"must be below occupied_thresh ({thresholds['free_thresh']} >= {thresholds['occupied_thresh']})",
        )

    mode = document.get("mode", _ROS_DEFAULTS["mode"])
    if mode not in _ROS_MODES:
        raise fail("mode", f"must be one of {', '.join(_ROS_MODES)}, got {mode!r}")

    return {
        "image": image,
        "resolution": float(resolution),
        "origin": tuple(float(value) for value in origin),
        "negate": negate,
        "mode": mode,
        **thresholds,
    }


def _nav2_lookup_table(
    n_channels: int, *, mode: str, negate: int, free_thresh: float, occupied_thresh: float
) -> np.ndarray:
    """Occupancy for every possible sum of ``n_channels`` 16-bit channel values.

    The per-pixel arithmetic copies nav2's ``loadMapFromFile`` on a Q16 GraphicsMagick:
    ``shade = (sum / n_channels) / 65535``. A table over the integer sums gives the same
    doubles as nav2 without a float array the size of the map.
    """
    sums = np.arange(n_channels * 65535 + 1, dtype=np.float64)
    shade = (sums / n_channels) / 65535.0
    if mode == "raw":
        # std::round rounds halves away from zero; shade is never negative.
        value = np.floor(shade * 255.0 + 0.5)
        in_range = (value >= OCCUPANCY_FREE) & (value <= OCCUPANCY_OCCUPIED)
        return np.where(in_range, value, OCCUPANCY_UNKNOWN).astype(np.int8)
    occ = shade if negate else 1.0 - shade
    table = np.full(sums.shape, OCCUPANCY_UNKNOWN, dtype=np.int8)
    occupied = occupied_thresh < occ
    free = ~occupied & (occ < free_thresh)
    table[occupied] = OCCUPANCY_OCCUPIED
    table[free] = OCCUPANCY_FREE
    if mode == "scale":
        between = ~occupied & ~free
        scaled = np.rint((occ[between] - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        table[between] = np.clip(scaled, 1, 99).astype(np.int8)
    return table


def _nav2_occupancy(
    pixels: Pixels, *, mode: str, negate: int, free_thresh: float, occupied_thresh: float
) -> np.ndarray:
    colour, alpha = pixels.colour, pixels.alpha
    colour_to_q16 = 257 if colour.dtype == np.uint8 else 1
    alpha_to_q16 = 0 if alpha is None else (257 if alpha.dtype == np.uint8 else 1)
    alpha_in_shade = mode == "trinary" and alpha is not None
    table = _nav2_lookup_table(
        4 if alpha_in_shade else 3,
        mode=mode,
        negate=negate,
        free_thresh=free_thresh,
        occupied_thresh=occupied_thresh,
    )
    occupancy = np.empty(colour.shape[:2], dtype=np.int8)
    for block in row_blocks(*colour.shape[:2]):
        part = colour[block].astype(np.uint32) * colour_to_q16
        # A grey pixel is R = G = B for GraphicsMagick, so it counts three times.
        sums = part.sum(axis=-1, dtype=np.uint32) if part.ndim == 3 else part * 3
        if alpha_in_shade:
            sums += alpha[block].astype(np.uint32) * alpha_to_q16
        cells = table[sums]
        if mode == "scale" and alpha is not None:
            cells[alpha[block] != np.iinfo(alpha.dtype).max] = OCCUPANCY_UNKNOWN
        occupancy[block] = cells
    return occupancy


def _is_real_number(value) -> bool:
    # bool is an int subclass; a flag passed by mistake must not read as 0 or 1.
    return isinstance(value, numbers.Real) and not isinstance(value, bool)
