"""Maps: loading images and ROS map_server YAML files into a binary free-space mask.

Conventions: pixel coordinates are (row, col) with row 0 at the top of the image;
``Map.free`` is True where a robot (or the sketch's reader) can be, False for walls,
outside and unknown space.

How a plain image becomes a free-space mask (:func:`load_map`, :func:`map_from_array`):

1. Decode with Pillow (PNG, JPEG, BMP, TIFF, PGM/PPM and anything else Pillow reads) and
   apply the EXIF orientation, as ``cv::imread`` does.
2. Depth: 16-bit grey is scaled to 8 bits with ``round(v / 257)`` (``(v + 128) // 257``), which
   maps 257 * k to k exactly and is what GraphicsMagick (the nav2 map loader) does. 16-bit colour
   images are reduced to 8 bits per channel by Pillow (high byte).
3. Colour to grey: ITU-R 601 luma computed exactly as ``cv2.cvtColor(..., COLOR_RGB2GRAY)``
   on 8-bit data, ``(9798 R + 19235 G + 3735 B + 2**14) >> 15``. Palette images are expanded
   through their palette first.
4. Alpha: a pixel with alpha < 50 % (< 128 of 255) is transparent. Transparent pixels are
   outside, i.e. obstacle, and are 0 in ``Map.image``.
5. ``free = grey > threshold`` (default 250, as the MAORIS evaluation tools).

``nonzero_free=True`` reproduces the released URSIM driver, which read maps with
``cv::imread(file, IMREAD_GRAYSCALE)`` and used every non-zero pixel as free space. That call
drops the alpha channel without compositing, so in this mode alpha is ignored too (a
transparent white pixel is free); the grey value is libpng's, ``(9797 R + 19234 G + 3737 B)
>> 15`` truncated for non-grey colours, and 16-bit grey keeps its high byte (``v >> 8``). On
the released KTH sketches the transparent pixels are black underneath, so ignoring alpha does
not change their free space. Known differences, which only move grey values of non-grey
(coloured) pixels: libpng converts in linear light when a PNG carries a gAMA/sRGB chunk, and
converts 16-bit colour PNGs to grey before dropping to 8 bits. On every map of the research
datasets the free mask of this mode equals ``cv2.imread(file, IMREAD_GRAYSCALE) > 0`` (a
dataset test checks it).

ROS map_server YAML files (``.yaml`` / ``.yml``) are read as the navigation2 map loader
(``nav2_map_server/src/map_io.cpp``) does, see :func:`load_map`.
"""

from __future__ import annotations

import hashlib
import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ursim_core.errors import MapError, ParameterError
from ursim_core.io.images import (
    Pixels,
    decode_image,
    display_grey,
    imread_grey,
    pixels_from_array,
    read_file_bytes,
    transparent_mask,
)
from ursim_core.io.ros_yaml import (
    OCCUPANCY_FREE,
    OCCUPANCY_OCCUPIED,
    OCCUPANCY_UNKNOWN,
    ROS_SUFFIXES,
    read_ros_yaml,
)

__all__ = [
    "Map",
    "load_map",
    "map_from_array",
    "pixel_to_world",
    "world_to_pixel",
    "check_threshold",
    "check_max_pixels",
    "DEFAULT_FREE_THRESHOLD",
    "DEFAULT_MAX_PIXELS",
    "OCCUPANCY_FREE",
    "OCCUPANCY_OCCUPIED",
    "OCCUPANCY_UNKNOWN",
]

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

    Examples
    --------
    Usually made by :func:`load_map` or :func:`map_from_array`; by hand, a georeferenced map:

    >>> free = np.zeros((10, 20), bool); free[2:8, 2:18] = True
    >>> room = Map(free=free, resolution=0.05, origin=(-1.0, 2.0, 0.0))
    >>> room
    Map(shape=(10, 20), free=96 px, resolution=0.05, origin=(-1.0, 2.0, 0.0))
    >>> room.name, pixel_to_world(room, 9, 0)  # no file; the lower-left pixel's centre in metres
    ('map', (-0.975, 2.025))
    """

    free: np.ndarray
    path: Path | None = None
    sha256: str | None = None
    resolution: float | None = None
    origin: tuple[float, float, float] | None = None
    occupancy: np.ndarray | None = field(default=None, repr=False)
    image: np.ndarray | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        # Not the arrays: a building's map printed as pages of booleans says less than its shape.
        known = {"path": self.path, "resolution": self.resolution, "origin": self.origin}
        shown = "".join(f", {name}={value!r}" for name, value in known.items() if value is not None)
        return f"Map(shape={self.shape}, free={int(np.count_nonzero(self.free))} px{shown})"

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.free.shape)  # type: ignore[return-value]

    @property
    def name(self) -> str:
        """File name without extension ('map' when there is no file)."""
        return self.path.stem if self.path is not None else "map"


# ---------------------------------------------------------------------------------------------
# Public API


def load_map(
    path: str | Path,
    *,
    threshold: float = DEFAULT_FREE_THRESHOLD,
    nonzero_free: bool = False,
    max_pixels: int = DEFAULT_MAX_PIXELS,
) -> Map:
    """Load a map image or a ROS map_server YAML file.

    Parameters
    ----------
    path : str or Path
        An image (PNG, JPEG, BMP, TIFF, PGM/PPM, ...; 8 or 16 bit; grey, grey+alpha, RGB,
        RGBA, palette with or without transparency) or a ROS map YAML (``.yaml``/``.yml``).
    threshold : float, optional
        Images: a pixel is free when its grey value is strictly above this (0..255).
        Ignored for YAML maps, whose own thresholds apply, and when ``nonzero_free``.
    nonzero_free : bool, optional
        Images: reproduce the released URSIM driver, every non-zero grey pixel is free and
        alpha is ignored (see the module docstring). Ignored for YAML maps.
    max_pixels : int, optional
        Refuse images with more pixels than this. The size is read from the file header
        before any pixel is decoded, so a huge or malicious file costs nothing.

    Returns
    -------
    Map
        ``free``, ``image`` (uint8 grey; transparent pixels 0), ``path`` (as given),
        ``sha256`` of the file bytes. YAML maps also have ``resolution``, ``origin``,
        ``occupancy`` (int8, row 0 at the top like the image) and ``free = occupancy == 0``;
        their ``sha256`` is that of the image file, the bytes that define the map.

    Raises
    ------
    MapError
        The file is missing, a directory, not an image, truncated or corrupt, of zero size,
        larger than ``max_pixels``, of an unsupported pixel mode, has no free pixel, or is a
        YAML file with a missing or invalid field (the message names file and field).
    ParameterError
        ``threshold`` outside 0..255 or ``max_pixels`` not a positive integer.

    Notes
    -----
    YAML maps follow nav2's ``loadMapYaml``/``loadMapFromFile``. Keys: ``image`` (relative to
    the YAML's folder unless absolute), ``resolution`` (> 0), ``origin`` ([x, y, yaw]),
    ``negate`` (0/1, default 0), ``occupied_thresh`` (default 0.65), ``free_thresh``
    (default 0.25), ``mode`` (``trinary`` default, ``scale``, ``raw``). Unlike nav2 the last
    four may be omitted. Per pixel, ``shade`` is the mean of R, G, B (grey counts for all
    three) as a fraction of full scale; in trinary mode an image with alpha also averages in
    the alpha channel, as nav2 does "to preserve existing behaviour". ``occ = 1 - shade``
    (``shade`` when negated); ``occ > occupied_thresh`` is occupied (100),
    ``occ < free_thresh`` free (0), otherwise unknown (-1). Scale mode makes every pixel that
    is not fully opaque unknown and scales intermediate values to 1..99 (nav2 rounds to
    0..100, which would let a value equal to ``free_thresh`` read as free). Raw mode takes
    ``round(shade * 255)`` as the occupancy when it is 0..100, else unknown, and ignores
    ``negate``, like nav2. Shades are computed on a 16-bit scale as GraphicsMagick Q16 does.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> grey = np.zeros((4, 6), np.uint8); grey[1:3, 1:5] = 255
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     Image.fromarray(grey).save(Path(folder) / "room.png")
    ...     room = load_map(Path(folder) / "room.png")
    >>> room.shape, int(room.free.sum()), room.name
    ((4, 6), 8, 'room')
    """
    check_threshold(threshold)
    check_max_pixels(max_pixels)
    path = Path(path)
    if path.suffix.lower() in ROS_SUFFIXES:
        ros = read_ros_yaml(path, max_pixels=max_pixels)
        return Map(
            free=ros.occupancy == OCCUPANCY_FREE,
            path=path,
            sha256=ros.sha256,
            resolution=ros.resolution,
            origin=ros.origin,
            occupancy=ros.occupancy,
            image=ros.image,
        )
    data = read_file_bytes(path, empty_problem="empty file (0 bytes): zero-size image", max_pixels=max_pixels)
    pixels = decode_image(data, path, max_pixels=max_pixels, apply_exif_orientation=True)
    return _binary_map(
        pixels,
        threshold=threshold,
        nonzero_free=nonzero_free,
        path=path,
        sha256=hashlib.sha256(data).hexdigest(),
    )


def map_from_array(
    array: np.ndarray,
    *,
    threshold: float = DEFAULT_FREE_THRESHOLD,
    nonzero_free: bool = False,
    path: str | Path | None = None,
) -> Map:
    """Make a map from an in-memory image, with the same rules as :func:`load_map`.

    Parameters
    ----------
    array : array_like
        bool (rows, cols): used as the free mask directly. uint8 or uint16 grey (rows, cols);
        (rows, cols, 1|2|3|4) for grey, grey+alpha, RGB, RGBA (channel order RGB, as Pillow
        and scikit-image; convert OpenCV's BGR first). Other integer dtypes are accepted when
        every value lies in 0..255 (read as 8-bit). Floating-point arrays are refused because
        their scale (0..1 or 0..255) is ambiguous.
    threshold : float, optional
        Free when grey > threshold (0..255).
    nonzero_free : bool, optional
        Every non-zero grey pixel is free and alpha is ignored, as the released driver.
    path : str or Path, optional
        Recorded as ``Map.path`` (the GUI passes the file a sketch will be saved to).

    Returns
    -------
    Map
        ``free`` and ``image`` are new arrays (the input is never aliased); ``sha256`` is None.

    Raises
    ------
    MapError
        Wrong shape or dtype, zero size, or no free pixel.
    ParameterError
        ``threshold`` outside 0..255.

    Examples
    --------
    >>> grey = np.array([[0, 251, 255], [250, 0, 0]], dtype=np.uint8)
    >>> map_from_array(grey).free
    array([[False,  True,  True],
           [False, False, False]])
    >>> map_from_array(grey, nonzero_free=True).free
    array([[False,  True,  True],
           [ True, False, False]])
    """
    check_threshold(threshold)
    path = None if path is None else Path(path)
    values = np.asarray(array)
    if values.size == 0 or values.ndim < 2:
        raise MapError(f"zero-size or not 2-D image array (shape {values.shape})", path=path)
    if values.dtype == np.bool_:
        if values.ndim != 2:
            raise MapError(f"a boolean map must be 2-D, got shape {values.shape}", path=path)
        free = values.copy()
        if not free.any():
            raise MapError("no free pixel: the boolean map is all False", path=path)
        return Map(free=free, path=path, image=np.where(free, 255, 0).astype(np.uint8))
    pixels = pixels_from_array(values, path)
    return _binary_map(pixels, threshold=threshold, nonzero_free=nonzero_free, path=path, sha256=None)


def pixel_to_world(map: Map, rows, cols):
    """World coordinates (x, y) of pixel centres.

    The map's ``origin`` (x, y, yaw) is the world pose of the lower-left corner of the
    lower-left pixel, as in ROS/nav2. Pixel (row, col) has its centre at
    ``((col + 0.5) * res, (n_rows - row - 0.5) * res)`` in the map frame, which is then
    rotated by yaw and translated by (x, y). A map with a resolution but no origin uses
    (0, 0, 0).

    Parameters
    ----------
    map : Map
        A map with a ``resolution`` (ROS YAML maps).
    rows, cols : float or array_like
        Pixel coordinates; fractional values are allowed. They broadcast together.

    Returns
    -------
    x, y : float or ndarray
        Floats for scalar input, else float arrays of the broadcast shape.

    Raises
    ------
    ParameterError
        The map has no resolution.

    Examples
    --------
    >>> free = np.ones((10, 20), dtype=bool)
    >>> m = Map(free=free, resolution=0.5, origin=(1.0, 2.0, 0.0))
    >>> pixel_to_world(m, 9, 0)
    (1.25, 2.25)
    """
    resolution, (origin_x, origin_y, yaw) = _georeference(map)
    rows_arr, cols_arr = np.broadcast_arrays(np.asarray(rows, dtype=float), np.asarray(cols, dtype=float))
    frame_x = (cols_arr + 0.5) * resolution
    frame_y = (map.shape[0] - rows_arr - 0.5) * resolution
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    x = origin_x + cos_yaw * frame_x - sin_yaw * frame_y
    y = origin_y + sin_yaw * frame_x + cos_yaw * frame_y
    return _scalar_or_array(x), _scalar_or_array(y)


def world_to_pixel(map: Map, x, y):
    """Pixel coordinates (rows, cols) of world points; the inverse of :func:`pixel_to_world`.

    Pixel centres come out as whole numbers, so the pixel containing a point is
    ``(floor(rows + 0.5), floor(cols + 0.5))``; it may lie outside the image.

    Parameters
    ----------
    map : Map
        A map with a ``resolution``.
    x, y : float or array_like
        World coordinates in metres. They broadcast together.

    Returns
    -------
    rows, cols : float or ndarray
        Floats for scalar input, else float arrays.

    Raises
    ------
    ParameterError
        The map has no resolution.

    Examples
    --------
    >>> free = np.ones((10, 20), dtype=bool)
    >>> m = Map(free=free, resolution=0.5, origin=(1.0, 2.0, 0.0))
    >>> world_to_pixel(m, 1.25, 2.25)
    (9.0, 0.0)
    """
    resolution, (origin_x, origin_y, yaw) = _georeference(map)
    x_arr, y_arr = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    delta_x = x_arr - origin_x
    delta_y = y_arr - origin_y
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    frame_x = cos_yaw * delta_x + sin_yaw * delta_y
    frame_y = -sin_yaw * delta_x + cos_yaw * delta_y
    cols = frame_x / resolution - 0.5
    rows = map.shape[0] - frame_y / resolution - 0.5
    return _scalar_or_array(rows), _scalar_or_array(cols)


# ---------------------------------------------------------------------------------------------
# Parameter checks


def _is_real_number(value) -> bool:
    # bool is an int subclass; a flag passed by mistake must not read as 0 or 1.
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_threshold(threshold, *, option: str | None = None) -> None:
    """Refuse a free threshold (:func:`load_map`'s ``threshold``) that is not a number in 0..255.

    Parameters
    ----------
    threshold : object
        The value to check; a bool is refused (a flag passed by mistake is no grey value).
    option : str, optional
        The command-line option that gave the value (``"--threshold"``): the message names it
        instead of the parameter, so a user sees what to change.

    Raises
    ------
    ParameterError
        Naming the parameter (its ``field``) or the option, and the value.

    Examples
    --------
    >>> check_threshold(250)
    >>> check_threshold(300, option="--threshold")
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: --threshold must be a number in 0..255, got 300
    """
    if not _is_real_number(threshold) or not math.isfinite(threshold) or not 0 <= threshold <= 255:
        _refuse(option, "threshold", f"must be a number in 0..255, got {threshold!r}")


def check_max_pixels(max_pixels, *, option: str | None = None) -> None:
    """Refuse a pixel limit (:func:`load_map`'s ``max_pixels``) that is not a positive integer.

    Parameters
    ----------
    max_pixels : object
        The value to check; a bool or a float is refused.
    option : str, optional
        The command-line option that gave the value (``"--max-pixels"``), named by the message.

    Raises
    ------
    ParameterError
        Naming the parameter (its ``field``) or the option, and the value.

    Examples
    --------
    >>> check_max_pixels(0, option="--max-pixels")
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: --max-pixels must be a positive integer, got 0
    """
    if not isinstance(max_pixels, numbers.Integral) or isinstance(max_pixels, bool) or max_pixels < 1:
        _refuse(option, "max_pixels", f"must be a positive integer, got {max_pixels!r}")


def _refuse(option: str | None, parameter: str, problem: str) -> None:
    if option is None:
        # The field names the parameter: "field 'threshold': must be ..." (not "threshold" twice).
        raise ParameterError(problem, field=parameter)
    # An option names itself: "field '--threshold'" would read as a place in a file.
    raise ParameterError(f"{option} {problem}")


# ---------------------------------------------------------------------------------------------
# From pixels to a free mask


def _binary_map(pixels: Pixels, *, threshold: float, nonzero_free: bool, path: Path | None, sha256: str | None) -> Map:
    if nonzero_free:
        grey = imread_grey(pixels)
        free = grey > 0
        if not free.any():
            raise MapError("no free pixel: every pixel is black (0)", path=path)
        return Map(free=free, path=path, sha256=sha256, image=grey)

    grey = display_grey(pixels)
    transparent = transparent_mask(pixels.alpha)
    hidden = 0
    if transparent is not None:
        # Free-looking pixels that are transparent: the usual surprise of a palette PNG whose
        # white entry carries tRNS transparency.
        hidden = int(np.count_nonzero(transparent & (grey > threshold)))
        grey[transparent] = 0
    free = grey > threshold
    if not free.any():
        if transparent is not None and transparent.all():
            reason = "every pixel is transparent"
        elif hidden:
            reason = (
                f"the {hidden} pixels brighter than threshold {threshold} are all transparent "
                "(alpha < 50 %, e.g. a palette whose white entry is marked transparent), "
                "and transparent pixels are outside the map"
            )
        else:
            reason = f"no grey value above threshold {threshold} (the brightest is {int(grey.max())})"
        raise MapError(f"no free pixel: {reason}", path=path)
    return Map(free=free, path=path, sha256=sha256, image=grey)


# ---------------------------------------------------------------------------------------------
# Geometry helpers


def _georeference(map_: Map) -> tuple[float, tuple[float, float, float]]:
    if map_.resolution is None:
        raise ParameterError(
            "the map has no resolution: only ROS map_server YAML maps carry a metric scale",
            path=map_.path,
            field="resolution",
        )
    origin = map_.origin if map_.origin is not None else (0.0, 0.0, 0.0)
    return float(map_.resolution), tuple(float(value) for value in origin)  # type: ignore[return-value]


def _scalar_or_array(values: np.ndarray):
    return float(values) if values.ndim == 0 else values
