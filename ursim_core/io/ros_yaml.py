"""ROS map_server YAML maps, read as the navigation2 map loader does.

:func:`read_ros_yaml` follows nav2's ``loadMapYaml`` / ``loadMapFromFile``
(``nav2_map_server/src/map_io.cpp``): the YAML keys, the image relative to the YAML's folder,
and the per-pixel occupancy of the ``trinary``, ``scale`` and ``raw`` modes on a 16-bit scale
as GraphicsMagick Q16 computes it. :func:`ursim_core.io.load_map` turns the result into a
:class:`~ursim_core.io.maps.Map`; its docstring describes the keys and the modes.
"""

from __future__ import annotations

import functools
import hashlib
import math
import numbers
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ursim_core.errors import MapError, MapFileNotFoundError
from ursim_core.io.images import Pixels, decode_image, display_grey, read_file_bytes, row_blocks, transparent_mask
from ursim_core.io.reading import read_regular_file

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


def ros_image_path(yaml_path: str | os.PathLike) -> Path:
    """The image file a map_server YAML file names, resolved as :func:`read_ros_yaml` resolves
    it: relative to the YAML's folder unless absolute (nav2's rule).

    Raises
    ------
    MapError
        The YAML cannot be read or is not a valid map_server file (as the loader would say).

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / "map.yaml").write_text("image: map.pgm\\nresolution: 0.05\\norigin: [0, 0, 0]\\n")
    >>> ros_image_path(folder / "map.yaml") == folder / "map.pgm"
    True
    """
    yaml_path = Path(yaml_path)
    document = _parse_yaml(yaml_path)
    if not isinstance(document, dict):
        raise MapError("not a ROS map_server YAML file: expected a mapping", path=yaml_path)
    return _image_path(yaml_path, _ros_settings(document, yaml_path)["image"])


def _image_path(yaml_path: Path, image: str) -> Path:
    image_path = Path(image)
    return image_path if image_path.is_absolute() else yaml_path.parent / image_path


def read_ros_yaml(yaml_path: Path, *, max_pixels: int) -> RosMap:
    """Read a ROS map_server YAML file and its image (see :func:`ursim_core.io.load_map`).

    Raises
    ------
    MapError
        The YAML or its image is unreadable or invalid, or the map has no free cell.
    """
    document = _parse_yaml(yaml_path)
    if not isinstance(document, dict):
        raise MapError(
            "not a ROS map_server YAML file: expected a mapping with keys image, resolution, "
            f"origin, got {type(document).__name__}",
            path=yaml_path,
        )
    settings = _ros_settings(document, yaml_path)
    image_path = _image_path(yaml_path, settings["image"])
    shown = _cut(str(image_path), 200)
    if not os.path.lexists(image_path):
        raise MapFileNotFoundError(f"image file not found: {shown}", path=yaml_path, field="image", filename=image_path)
    try:
        data = read_file_bytes(image_path, empty_problem="empty file (0 bytes): zero-size image", max_pixels=max_pixels)
        # nav2 loads through GraphicsMagick without auto-orientation, so EXIF is ignored here.
        pixels = decode_image(data, image_path, max_pixels=max_pixels, apply_exif_orientation=False)
    except MapError as error:
        problem = f"cannot load the image {shown}: {error.problem}"
        if isinstance(error, FileNotFoundError):  # a dangling link: the image it names is missing
            raise MapFileNotFoundError(problem, path=yaml_path, field="image", filename=error.filename) from error
        raise MapError(problem, path=yaml_path, field="image") from error
    extent_problem = world_extent_problem(settings["resolution"], settings["origin"], pixels.colour.shape[:2])
    if extent_problem is not None:
        raise MapError(extent_problem[1], path=yaml_path, field=extent_problem[0])

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


#: Farthest, in metres, a map's corner may lie from the world's origin: a hundred million
#: kilometres, far beyond any map a robot makes (UTM northings are under 1e7 m), and far below
#: where the pixel <-> world conversions and their exports would overflow to infinity or NaN.
MAX_WORLD_EXTENT = 1e11


def world_extent_problem(
    resolution: float, origin: tuple[float, float, float], shape: tuple[int, int]
) -> tuple[str, str] | None:
    """``(field, problem)`` when a map of ``shape`` pixels at ``resolution`` metres a pixel and
    ``origin`` (x, y, yaw) would have a corner farther than :data:`MAX_WORLD_EXTENT` from the
    world's origin, else None.

    Each number of a YAML file can be finite while their product is not (``resolution: 1e306``
    on a 1000-pixel image): refused when the map is loaded, rather than as NaN in a goal or an
    export later.

    Examples
    --------
    >>> world_extent_problem(0.05, (-10.0, -5.0, 0.0), (400, 600)) is None
    True
    >>> world_extent_problem(1e306, (0.0, 0.0, 0.0), (400, 600))[0]
    'resolution'
    """
    x0, y0, yaw = origin
    rows, cols = shape
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    farthest = 0.0
    for frame_x in (0.0, resolution * cols):
        for frame_y in (0.0, resolution * rows):
            x = x0 + cos_yaw * frame_x - sin_yaw * frame_y
            y = y0 + sin_yaw * frame_x + cos_yaw * frame_y
            farthest = max(farthest, abs(x), abs(y)) if math.isfinite(x) and math.isfinite(y) else math.inf
    if farthest <= MAX_WORLD_EXTENT:
        return None
    field = "origin" if max(abs(x0), abs(y0)) > MAX_WORLD_EXTENT / 2 else "resolution"
    shown = "beyond any floating-point number" if math.isinf(farthest) else f"{farthest:.3g} m"
    return field, (
        f"resolution {resolution:g} m/pixel on {cols}x{rows} pixels from origin ({x0:g}, {y0:g}) puts the "
        f"map's far corner {shown} from the world origin (at most {MAX_WORLD_EXTENT:.0e} m)"
    )


# A map_server YAML file is a handful of keys: these bounds are far above any real one and far
# below what an alias bomb or a deeply nested file needs to hurt (seconds, gigabytes).
MAX_YAML_BYTES = 1024**2
MAX_YAML_DEPTH = 32
MAX_YAML_NODES = 100_000


class _YamlRefused(Exception):
    def __init__(self, problem: str, mark=None):
        super().__init__(problem)
        self.problem = problem
        self.mark = mark


@functools.cache
def _bounded_loader():
    """A ``yaml.SafeLoader`` that refuses aliases and bounds depth and size while composing."""
    import yaml

    class BoundedLoader(yaml.SafeLoader):
        depth = 0
        nodes = 0

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                event = self.peek_event()
                raise _YamlRefused(
                    f"YAML aliases (*{_cut(event.anchor, 40)}) are not accepted in a map file", event.start_mark
                )
            self.nodes += 1
            if self.nodes > MAX_YAML_NODES:
                raise _YamlRefused(f"more than {MAX_YAML_NODES} YAML values", self.peek_event().start_mark)
            self.depth += 1
            try:
                if self.depth > MAX_YAML_DEPTH:
                    raise _YamlRefused(f"nested deeper than {MAX_YAML_DEPTH} levels", self.peek_event().start_mark)
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    return BoundedLoader


def _parse_yaml(yaml_path: Path):
    """The YAML document of ``yaml_path``, or a one-line MapError naming the file."""
    import yaml

    raw = read_regular_file(
        yaml_path,
        max_bytes=MAX_YAML_BYTES,
        error=MapError,
        what="ROS map YAML file",
        empty_problem="empty file (0 bytes): not a ROS map YAML",
    )
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = raw[: error.start].count(b"\n") + 1
        raise MapError(
            f"not UTF-8 text (byte {error.start}, line {line}): not a ROS map YAML", path=yaml_path
        ) from None
    loader = None
    try:
        # The reader checks the first characters already when the loader is made.
        loader = _bounded_loader()(text)
        return loader.get_single_data()
    except _YamlRefused as error:
        raise MapError(f"not accepted as YAML: {error.problem}{_at(error.mark)}", path=yaml_path) from None
    except yaml.YAMLError as error:
        raise MapError(f"not valid YAML: {_yaml_problem(error)}", path=yaml_path) from None
    except (ValueError, OverflowError, RecursionError, MemoryError) as error:
        # e.g. an integer of more than 4300 digits: Python's int() refuses to convert it.
        raise MapError(f"not valid YAML for a map: {_cut(str(error), 120)}", path=yaml_path) from None
    finally:
        if loader is not None:
            loader.dispose()


def _yaml_problem(error) -> str:
    import yaml

    if not isinstance(error, yaml.MarkedYAMLError):
        return _cut(" ".join(str(error).split()), 200)
    problem = error.problem or error.context or "syntax error"
    if "'\\t'" in problem:
        problem += " (a tab: YAML indents with spaces)"
    if error.context and error.problem:
        problem = f"{problem} ({error.context})"
    return _cut(" ".join(problem.split()), 200) + _at(error.problem_mark or error.context_mark)


def _at(mark) -> str:
    return "" if mark is None else f" at line {mark.line + 1}, column {mark.column + 1}"


def short(value, limit: int = 60) -> str:
    """``repr`` of ``value`` on one line, cut to ``limit`` characters, for messages.

    Examples
    --------
    >>> short("x" * 100, 10)
    "'xxxxxx..."
    """
    return _cut(_repr(value), limit)


def _cut(text: str, limit: int) -> str:
    text = " ".join(text.splitlines())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _repr(value) -> str:
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**50:
        # repr of a 5000-digit int raises; say what it is instead.
        return f"an integer of {len(str(abs(value))) if abs(value) < 10**4000 else 'over 4000'} digits"
    try:
        return repr(value)
    except (ValueError, RecursionError):
        return f"a {type(value).__name__}"


def _ros_settings(document: dict, yaml_path: Path) -> dict:
    """Validated map_server keys, with nav2's meaning and the defaults in _ROS_DEFAULTS."""

    def fail(key: str, problem: str) -> MapError:
        return MapError(problem, path=yaml_path, field=key)

    for key in ("image", "resolution", "origin"):
        if key not in document or document[key] is None:
            raise fail(key, f"missing required key '{key}'")

    image = document["image"]
    if not isinstance(image, str) or not image.strip():
        raise fail("image", f"must be a non-empty file path, got {short(image)}")
    if "\x00" in image:
        raise fail("image", f"the file path contains a NUL character: {short(image)}")

    resolution = document["resolution"]
    if not _is_finite_number(resolution) or resolution <= 0:
        raise fail("resolution", f"must be a positive number (metres per pixel), got {short(resolution)}")

    origin = document["origin"]
    if (
        not isinstance(origin, (list, tuple))
        or len(origin) != 3
        or not all(_is_finite_number(value) for value in origin)
    ):
        raise fail("origin", f"must be a list of 3 finite numbers [x, y, yaw], got {short(origin)}")

    negate = document.get("negate", _ROS_DEFAULTS["negate"])
    if isinstance(negate, bool):
        negate = int(negate)
    if not isinstance(negate, int) or negate not in (0, 1):
        raise fail("negate", f"must be 0 or 1, got {short(negate)}")

    thresholds = {}
    for key in ("occupied_thresh", "free_thresh"):
        value = document.get(key, _ROS_DEFAULTS[key])
        if not _is_real_number(value) or not 0 <= value <= 1:
            raise fail(key, f"must be a number in [0, 1], got {short(value)}")
        thresholds[key] = float(value)
    if thresholds["free_thresh"] >= thresholds["occupied_thresh"]:
        raise fail(
            "free_thresh",
            f"must be below occupied_thresh ({thresholds['free_thresh']} >= {thresholds['occupied_thresh']})",
        )

    mode = document.get("mode", _ROS_DEFAULTS["mode"])
    if mode not in _ROS_MODES:
        raise fail("mode", f"must be one of {', '.join(_ROS_MODES)}, got {short(mode)}")

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


def _is_finite_number(value) -> bool:
    if not _is_real_number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        # An integer of hundreds of digits: no float holds it.
        return False
