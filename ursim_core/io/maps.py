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

import contextlib
import hashlib
import io
import math
import numbers
import re
import struct
import threading
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ursim_core.errors import MapError, ParameterError

__all__ = [
    "Map",
    "load_map",
    "map_from_array",
    "pixel_to_world",
    "world_to_pixel",
    "DEFAULT_FREE_THRESHOLD",
    "DEFAULT_MAX_PIXELS",
    "OCCUPANCY_FREE",
    "OCCUPANCY_OCCUPIED",
    "OCCUPANCY_UNKNOWN",
]

DEFAULT_FREE_THRESHOLD = 250
DEFAULT_MAX_PIXELS = 64_000_000
# Values of Map.occupancy (ROS nav_msgs/OccupancyGrid); scale-mode maps also hold 1..99.
OCCUPANCY_FREE = 0
OCCUPANCY_OCCUPIED = 100
OCCUPANCY_UNKNOWN = -1


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


# ---------------------------------------------------------------------------------------------
# Constants of the conversions (see the module docstring for where each comes from).

_ROS_SUFFIXES = (".yaml", ".yml")
_ROS_MODES = ("trinary", "scale", "raw")
_ROS_DEFAULTS = {"negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.25, "mode": "trinary"}

# cv2.cvtColor(COLOR_RGB2GRAY) on uint8: fixed point with 15 fractional bits, rounded.
_CV_LUMA = (9798, 19235, 3735)
_CV_LUMA_SHIFT = 15
# libpng png_set_rgb_to_gray(png, 1, 0.299, 0.587) as called by cv::imread(IMREAD_GRAYSCALE):
# coefficients truncated to 15 bits, blue takes the remainder, result truncated.
_LIBPNG_LUMA = (9797, 19234, 32768 - 9797 - 19234)
_LIBPNG_LUMA_SHIFT = 15

# Bounded work arrays: conversions run over blocks of about this many pixels so a map at the
# pixel limit does not need several full-size uint32 temporaries.
_BLOCK_PIXELS = 1 << 20

_SUPPORTED_MODES_TEXT = "grey, grey+alpha, RGB, RGBA or palette, 8 or 16 bit"
_PILLOW_LIMIT_LOCK = threading.Lock()


@dataclass(frozen=True)
class _Pixels:
    """Decoded pixels before any thresholding.

    ``colour`` is (rows, cols) grey or (rows, cols, 3) RGB, uint8 or uint16 (16-bit only for
    grey). ``alpha`` is (rows, cols) uint8 or uint16 opacity (max = opaque) or None.
    """

    colour: np.ndarray
    alpha: np.ndarray | None


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
    _check_threshold(threshold)
    _check_max_pixels(max_pixels)
    path = Path(path)
    if path.suffix.lower() in _ROS_SUFFIXES:
        return _load_ros_yaml(path, max_pixels=max_pixels)
    data = _read_file_bytes(path, empty_problem="empty file (0 bytes): zero-size image")
    pixels = _decode_image(data, path, max_pixels=max_pixels, apply_exif_orientation=True)
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
    _check_threshold(threshold)
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
    pixels = _pixels_from_array(values, path)
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


def _check_threshold(threshold) -> None:
    if not _is_real_number(threshold) or not math.isfinite(threshold) or not 0 <= threshold <= 255:
        raise ParameterError(f"threshold must be a number in 0..255, got {threshold!r}", field="threshold")


def _check_max_pixels(max_pixels) -> None:
    if not isinstance(max_pixels, numbers.Integral) or isinstance(max_pixels, bool) or max_pixels < 1:
        raise ParameterError(f"max_pixels must be a positive integer, got {max_pixels!r}", field="max_pixels")


# ---------------------------------------------------------------------------------------------
# Reading and decoding files


def _read_file_bytes(path: Path, *, empty_problem: str) -> bytes:
    # Reading everything once means the digest describes exactly the bytes that get decoded.
    if path.is_dir():
        raise MapError("is a directory, not a map file", path=path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise MapError("file not found", path=path) from None
    except OSError as error:
        raise MapError(f"cannot read the file: {error.strerror or error}", path=path) from error
    if not data:
        raise MapError(empty_problem, path=path)
    return data


@contextlib.contextmanager
def _pillow_pixel_limit(max_pixels: int) -> Iterator[None]:
    """Let our ``max_pixels`` decide instead of Pillow's decompression-bomb limit.

    Pillow checks ``Image.MAX_IMAGE_PIXELS`` inside ``Image.open`` (a warning above it, an
    error above twice it). When our limit is the smaller one, Pillow can only complain about
    images we refuse anyway, so its warning is silenced and its error translated by the
    caller. Only when the caller allows more than Pillow does is Pillow's global raised, for
    the duration of the open and under a lock, then restored.
    """
    from PIL import Image

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        pillow_limit = Image.MAX_IMAGE_PIXELS
        if pillow_limit is None or max_pixels <= pillow_limit:
            yield
            return
        with _PILLOW_LIMIT_LOCK:
            saved_limit = Image.MAX_IMAGE_PIXELS
            Image.MAX_IMAGE_PIXELS = max_pixels
            try:
                yield
            finally:
                Image.MAX_IMAGE_PIXELS = saved_limit


_NETPBM_SIZE = re.compile(rb"\AP[1-7](?:\s|#[^\n]*\n)+(\d+)(?:\s|#[^\n]*\n)+(\d+)")
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _declared_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG or Netpbm header that Pillow refused, else None.

    Pillow reports a zero-sized file only as "cannot identify image file"; reading the size
    ourselves lets the error say what is actually wrong.
    """
    if data.startswith(_PNG_SIGNATURE) and data[12:16] == b"IHDR" and len(data) >= 24:
        width, height = struct.unpack(">II", data[16:24])
        return width, height
    match = _NETPBM_SIZE.match(data)
    if match:
        return int(match.group(1)), int(match.group(2))
    return None


def _decode_image(data: bytes, path: Path, *, max_pixels: int, apply_exif_orientation: bool) -> _Pixels:
    from PIL import Image, UnidentifiedImageError

    with _pillow_pixel_limit(max_pixels):
        try:
            image = Image.open(io.BytesIO(data))
        except Image.DecompressionBombError as error:
            raise MapError(
                f"image larger than the limit max_pixels={max_pixels} (checked from the header before decoding: {error})",
                path=path,
            ) from None
        except UnidentifiedImageError:
            declared = _declared_size(data)
            if declared is not None and 0 in declared:
                raise MapError(f"zero-size image ({declared[0]} x {declared[1]} pixels)", path=path) from None
            raise MapError("not an image (or a format Pillow cannot read)", path=path) from None
        except MemoryError:
            raise
        except Exception as error:
            raise MapError(f"corrupt image header: {error}", path=path) from error

    width, height = image.size
    if width == 0 or height == 0:
        raise MapError(f"zero-size image ({width} x {height} pixels)", path=path)
    if width * height > max_pixels:
        raise MapError(
            f"image has {width * height} pixels ({width} x {height}), more than the limit "
            f"max_pixels={max_pixels} (checked from the header before decoding)",
            path=path,
        )
    try:
        if image.format == "PNG":
            # Pillow stops decoding once it has all rows, so a PNG cut inside its last
            # chunk loads silently; verify() walks every chunk and checks its CRC.
            with _pillow_pixel_limit(max_pixels):
                Image.open(io.BytesIO(data)).verify()
        image.load()
    except MemoryError:
        raise
    except Exception as error:
        raise MapError(f"truncated or corrupt image data: {error}", path=path) from error
    if apply_exif_orientation:
        image = _exif_oriented(image)
    return _pixels_from_pillow(image, path)


def _exif_oriented(image):
    from PIL import ImageOps

    try:
        orientation = image.getexif().get(0x0112, 1)
    except Exception:
        return image
    if orientation in (2, 3, 4, 5, 6, 7, 8):
        return ImageOps.exif_transpose(image)
    return image


def _pixels_from_pillow(image, path: Path | None) -> _Pixels:
    mode = image.mode
    transparency = image.info.get("transparency")
    if mode == "1":
        image, mode = image.convert("L"), "L"
    elif mode in ("P", "PA"):
        palette_has_alpha = image.palette is not None and "A" in image.palette.mode
        has_alpha = mode == "PA" or transparency is not None or palette_has_alpha
        image = image.convert("RGBA" if has_alpha else "RGB")
        mode, transparency = image.mode, None
    elif mode in ("La", "RGBa"):
        # Premultiplied alpha: un-premultiply so the colour of half-covered pixels is right.
        image = image.convert(mode.upper())
        mode = image.mode

    if mode == "L":
        grey = np.asarray(image).copy()
        return _Pixels(grey, _alpha_from_key(grey, transparency, channel_axis=False))
    if mode == "LA":
        values = np.asarray(image)
        return _Pixels(values[..., 0].copy(), values[..., 1].copy())
    if mode in ("RGB", "RGBX"):
        rgb = np.asarray(image)[..., :3].copy()
        return _Pixels(rgb, _alpha_from_key(rgb, transparency, channel_axis=True))
    if mode == "RGBA":
        values = np.asarray(image)
        return _Pixels(values[..., :3].copy(), values[..., 3].copy())
    if mode in ("I;16", "I;16L", "I;16B", "I;16N", "I"):
        values = np.asarray(image)
        if mode == "I" and values.size and (values.min() < 0 or values.max() > 65535):
            raise MapError(
                f"unsupported image mode 'I': 32-bit integer values outside 0..65535 "
                f"(supported: {_SUPPORTED_MODES_TEXT})",
                path=path,
            )
        grey = values.astype(np.uint16)
        return _Pixels(grey, _alpha_from_key(grey, transparency, channel_axis=False))
    raise MapError(f"unsupported image mode '{mode}' (supported: {_SUPPORTED_MODES_TEXT})", path=path)


def _alpha_from_key(colour: np.ndarray, key, *, channel_axis: bool) -> np.ndarray | None:
    """Opacity from a PNG tRNS colour key: the one colour that is fully transparent."""
    if key is None:
        return None
    try:
        key_values = np.asarray(key, dtype=np.int64).reshape(-1)
    except (TypeError, ValueError):
        return None
    expected = 3 if channel_axis else 1
    if key_values.size != expected:
        # A key of the wrong shape cannot match any pixel; Pillow keeps such keys verbatim.
        return None
    matches = np.all(colour == key_values, axis=-1) if channel_axis else colour == key_values[0]
    return np.where(matches, 0, 255).astype(np.uint8)


def _pixels_from_array(values: np.ndarray, path: Path | None) -> _Pixels:
    if values.ndim == 3 and values.shape[2] not in (1, 2, 3, 4):
        raise MapError(f"an image array needs 1, 2, 3 or 4 channels, got shape {values.shape}", path=path)
    if values.ndim > 3:
        raise MapError(
            f"an image array must be (rows, cols) or (rows, cols, channels), got shape {values.shape}", path=path
        )
    if values.dtype not in (np.uint8, np.uint16):
        if not np.issubdtype(values.dtype, np.integer):
            raise MapError(
                f"unsupported array dtype {values.dtype}: use bool (free mask), uint8 or uint16",
                path=path,
            )
        if values.min() < 0 or values.max() > 255:
            raise MapError(
                f"integer array of dtype {values.dtype} has values outside 0..255; pass uint16 for 16-bit images",
                path=path,
            )
        values = values.astype(np.uint8)
    if values.ndim == 2:
        return _Pixels(values.copy(), None)
    channels = values.shape[2]
    if channels in (1, 2):
        alpha = values[..., 1].copy() if channels == 2 else None
        return _Pixels(values[..., 0].copy(), alpha)
    rgb = _to_uint8(values[..., :3])
    alpha = values[..., 3].copy() if channels == 4 else None
    return _Pixels(rgb, alpha)


# ---------------------------------------------------------------------------------------------
# Pixel conversions


def _row_blocks(n_rows: int, n_cols: int) -> Iterator[slice]:
    step = max(1, _BLOCK_PIXELS // max(n_cols, 1))
    for start in range(0, n_rows, step):
        yield slice(start, min(start + step, n_rows))


def _to_uint8(values: np.ndarray) -> np.ndarray:
    """16-bit to 8-bit by rounding v / 257; 8-bit data is returned as a copy."""
    if values.dtype == np.uint8:
        return values.copy()
    return ((values.astype(np.uint32) + 128) // 257).astype(np.uint8)


def _luma(rgb: np.ndarray, *, weights: tuple[int, int, int], shift: int, rounded: bool, grey_exact: bool) -> np.ndarray:
    grey = np.empty(rgb.shape[:2], dtype=np.uint8)
    offset = (1 << (shift - 1)) if rounded else 0
    for block in _row_blocks(*rgb.shape[:2]):
        part = rgb[block].astype(np.uint32)
        red, green, blue = part[..., 0], part[..., 1], part[..., 2]
        value = (red * weights[0] + green * weights[1] + blue * weights[2] + offset) >> shift
        if grey_exact:
            # libpng copies grey pixels (R == G == B) unchanged; truncation would darken them.
            value = np.where((red == green) & (green == blue), red, value)
        grey[block] = value
    return grey


def _display_grey(pixels: _Pixels) -> np.ndarray:
    """uint8 grey by the default rules (rounded 16-bit scaling, OpenCV luma)."""
    if pixels.colour.ndim == 2:
        return _to_uint8(pixels.colour)
    return _luma(pixels.colour, weights=_CV_LUMA, shift=_CV_LUMA_SHIFT, rounded=True, grey_exact=False)


def _imread_grey(pixels: _Pixels) -> np.ndarray:
    """uint8 grey as cv::imread(IMREAD_GRAYSCALE) gives it for a PNG (libpng transforms)."""
    if pixels.colour.ndim == 2:
        if pixels.colour.dtype == np.uint16:
            return (pixels.colour >> 8).astype(np.uint8)
        return pixels.colour.copy()
    return _luma(pixels.colour, weights=_LIBPNG_LUMA, shift=_LIBPNG_LUMA_SHIFT, rounded=False, grey_exact=True)


def _transparent(alpha: np.ndarray | None) -> np.ndarray | None:
    if alpha is None:
        return None
    half = (int(np.iinfo(alpha.dtype).max) + 1) // 2
    return alpha < half


def _binary_map(pixels: _Pixels, *, threshold: float, nonzero_free: bool, path: Path | None, sha256: str | None) -> Map:
    if nonzero_free:
        grey = _imread_grey(pixels)
        free = grey > 0
        if not free.any():
            raise MapError("no free pixel: every pixel is black (0)", path=path)
        return Map(free=free, path=path, sha256=sha256, image=grey)

    grey = _display_grey(pixels)
    transparent = _transparent(pixels.alpha)
    if transparent is not None:
        grey[transparent] = 0
    free = grey > threshold
    if not free.any():
        if transparent is not None and transparent.all():
            reason = "every pixel is transparent"
        else:
            reason = f"no grey value above threshold {threshold} (the brightest is {int(grey.max())})"
        raise MapError(f"no free pixel: {reason}", path=path)
    return Map(free=free, path=path, sha256=sha256, image=grey)


# ---------------------------------------------------------------------------------------------
# ROS map_server YAML


def _load_ros_yaml(yaml_path: Path, *, max_pixels: int) -> Map:
    import yaml

    text = _read_file_bytes(yaml_path, empty_problem="empty file (0 bytes): not a ROS map YAML")
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
        data = _read_file_bytes(image_path, empty_problem="empty file (0 bytes): zero-size image")
        # nav2 loads through GraphicsMagick without auto-orientation, so EXIF is ignored here.
        pixels = _decode_image(data, image_path, max_pixels=max_pixels, apply_exif_orientation=False)
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
    image = _display_grey(pixels)
    transparent = _transparent(pixels.alpha)
    if transparent is not None:
        image[transparent] = 0
    return Map(
        free=free,
        path=yaml_path,
        sha256=hashlib.sha256(data).hexdigest(),
        resolution=settings["resolution"],
        origin=settings["origin"],
        occupancy=occupancy,
        image=image,
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
    pixels: _Pixels, *, mode: str, negate: int, free_thresh: float, occupied_thresh: float
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
    for block in _row_blocks(*colour.shape[:2]):
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
