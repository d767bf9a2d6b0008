"""Image decoding: file bytes to pixels, and pixels to grey values.

The shared first half of every map loader (:mod:`ursim_core.io.maps` for plain images,
:mod:`ursim_core.io.ros_yaml` for ROS map_server maps): read the file's bytes, decode them with
Pillow under our own pixel limit (a plain 8-bit PNG with OpenCV, to the same pixels:
:mod:`ursim_core.io.png`), and turn the decoded image into :class:`Pixels` (colour and
alpha arrays, 8 or 16 bit). The conversions to grey follow OpenCV (:func:`display_grey`) or
``cv::imread(IMREAD_GRAYSCALE)`` on a PNG (:func:`imread_grey`); the module docstring of
:mod:`ursim_core.io.maps` says where each constant comes from.

These are building blocks for the loaders, not a public API: use :func:`ursim_core.io.load_map`.
"""

from __future__ import annotations

import contextlib
import io
import re
import struct
import threading
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ursim_core.errors import MapError
from ursim_core.io.png import decode_plain_png, plain_png_size
from ursim_core.io.reading import read_regular_file

__all__ = [
    "Pixels",
    "read_file_bytes",
    "max_image_bytes",
    "decode_image",
    "pixels_from_array",
    "row_blocks",
    "display_grey",
    "imread_grey",
    "transparent_mask",
]


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
class Pixels:
    """Decoded pixels before any thresholding.

    ``colour`` is (rows, cols) grey or (rows, cols, 3) RGB, uint8 or uint16 (16-bit only for
    grey). ``alpha`` is (rows, cols) uint8 or uint16 opacity (max = opaque) or None.
    """

    colour: np.ndarray
    alpha: np.ndarray | None


# ---------------------------------------------------------------------------------------------
# Reading and decoding files


def max_image_bytes(max_pixels: int) -> int:
    """The largest file accepted for an image of at most ``max_pixels`` pixels.

    16 bytes a pixel (uncompressed 16-bit RGBA is 8; a PNG's filter bytes and a TIFF's strips
    add little) plus 64 MiB of metadata: no real image within the pixel limit is refused,
    and nothing much larger than it is ever read into memory.
    """
    return 16 * max_pixels + 64 * 1024**2


def read_file_bytes(path: Path, *, empty_problem: str, max_pixels: int) -> bytes:
    """The bytes of an image file, refused early when its size or header says it is unusable.

    The size comes from ``stat`` (see :mod:`ursim_core.io.reading`); the pixel count from
    the header in the first MiB, before the rest is read.
    """
    # Reading everything once means the digest describes exactly the bytes that get decoded.
    return read_regular_file(
        path,
        max_bytes=max_image_bytes(max_pixels),
        error=MapError,
        what="map file",
        empty_problem=empty_problem,
        limit_reason=f" (an image of at most max_pixels={max_pixels} pixels)",
        check_head=lambda head, complete: _check_header(head, path, max_pixels=max_pixels, complete=complete),
    )


# Formats whose header Pillow may need more than the first MiB to read (a TIFF's first
# directory can sit at the end of the file; a JPEG may carry large APP segments first).
_LATE_HEADER_SIGNATURES = (b"II*\x00", b"MM\x00*", b"\xff\xd8", b"\x89PNG", b"8BPS")


def _check_header(head: bytes, path: Path, *, max_pixels: int, complete: bool) -> None:
    """Refuse from the first bytes alone: not an image, zero size, or too many pixels."""
    if plain_png_size(head, max_pixels=max_pixels) is not None:
        return  # a well-formed PNG header within the limit: what Pillow would let through too
    from PIL import Image

    with _quiet_pillow(max_pixels):
        try:
            width, height = Image.open(io.BytesIO(head)).size
        except Image.DecompressionBombError:
            raise MapError(_too_many_pixels(head, max_pixels), path=path) from None
        except Exception:
            if complete or head.startswith(_LATE_HEADER_SIGNATURES):
                return  # the full decode gives the precise message
            raise MapError("not an image (or a format Pillow cannot read)", path=path) from None
    _check_dimensions(width, height, path, max_pixels=max_pixels)


def _check_dimensions(width: int, height: int, path: Path, *, max_pixels: int) -> None:
    if width == 0 or height == 0:
        raise MapError(f"zero-size image ({width} x {height} pixels)", path=path)
    if width * height > max_pixels:
        raise MapError(
            f"image has {width * height} pixels ({width} x {height}), more than the limit "
            f"max_pixels={max_pixels} (checked from the header before decoding)",
            path=path,
        )


def _too_many_pixels(data: bytes, max_pixels: int) -> str:
    declared = _declared_size(data)
    size = f"{declared[0] * declared[1]} pixels ({declared[0]} x {declared[1]}), " if declared else ""
    return f"image has {size}more than the limit max_pixels={max_pixels} (checked from the header before decoding)"


@contextlib.contextmanager
def _quiet_pillow(max_pixels: int) -> Iterator[None]:
    """Our pixel limit, and no Pillow warning on the console: our errors say what is wrong."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with _pillow_pixel_limit(max_pixels):
            yield


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


def decode_image(data: bytes, path: Path, *, max_pixels: int, apply_exif_orientation: bool) -> Pixels:
    # Most maps are plain 8-bit PNGs, which OpenCV decodes to the same pixels without Pillow's
    # import (:mod:`ursim_core.io.png`); everything else, and every error, is Pillow's.
    plain = decode_plain_png(data, max_pixels=max_pixels)
    if plain is not None:
        return Pixels(*plain)
    from PIL import Image, UnidentifiedImageError

    with _quiet_pillow(max_pixels):
        try:
            image = Image.open(io.BytesIO(data))
        except Image.DecompressionBombError:
            raise MapError(_too_many_pixels(data, max_pixels), path=path) from None
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
    _check_dimensions(width, height, path, max_pixels=max_pixels)
    with _quiet_pillow(max_pixels):
        try:
            if image.format == "PNG":
                # Pillow stops decoding once it has all rows, so a PNG cut inside its last
                # chunk loads silently; verify() walks every chunk and checks its CRC.
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


def _pixels_from_pillow(image, path: Path | None) -> Pixels:
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
        return Pixels(grey, _alpha_from_key(grey, transparency, channel_axis=False))
    if mode == "LA":
        values = np.asarray(image)
        return Pixels(values[..., 0].copy(), values[..., 1].copy())
    if mode in ("RGB", "RGBX"):
        rgb = np.asarray(image)[..., :3].copy()
        return Pixels(rgb, _alpha_from_key(rgb, transparency, channel_axis=True))
    if mode == "RGBA":
        values = np.asarray(image)
        return Pixels(values[..., :3].copy(), values[..., 3].copy())
    if mode in ("I;16", "I;16L", "I;16B", "I;16N", "I"):
        values = np.asarray(image)
        if mode == "I" and values.size and (values.min() < 0 or values.max() > 65535):
            raise MapError(
                f"unsupported image mode 'I': 32-bit integer values outside 0..65535 "
                f"(supported: {_SUPPORTED_MODES_TEXT})",
                path=path,
            )
        grey = values.astype(np.uint16)
        return Pixels(grey, _alpha_from_key(grey, transparency, channel_axis=False))
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


def pixels_from_array(values: np.ndarray, path: Path | None) -> Pixels:
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
        return Pixels(values.copy(), None)
    channels = values.shape[2]
    if channels in (1, 2):
        alpha = values[..., 1].copy() if channels == 2 else None
        return Pixels(values[..., 0].copy(), alpha)
    rgb = _to_uint8(values[..., :3])
    alpha = values[..., 3].copy() if channels == 4 else None
    return Pixels(rgb, alpha)


# ---------------------------------------------------------------------------------------------
# Pixel conversions


def row_blocks(n_rows: int, n_cols: int) -> Iterator[slice]:
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
    for block in row_blocks(*rgb.shape[:2]):
        part = rgb[block].astype(np.uint32)
        red, green, blue = part[..., 0], part[..., 1], part[..., 2]
        value = (red * weights[0] + green * weights[1] + blue * weights[2] + offset) >> shift
        if grey_exact:
            # libpng copies grey pixels (R == G == B) unchanged; truncation would darken them.
            value = np.where((red == green) & (green == blue), red, value)
        grey[block] = value
    return grey


def display_grey(pixels: Pixels) -> np.ndarray:
    """uint8 grey by the default rules (rounded 16-bit scaling, OpenCV luma)."""
    if pixels.colour.ndim == 2:
        return _to_uint8(pixels.colour)
    return _luma(pixels.colour, weights=_CV_LUMA, shift=_CV_LUMA_SHIFT, rounded=True, grey_exact=False)


def imread_grey(pixels: Pixels) -> np.ndarray:
    """uint8 grey as cv::imread(IMREAD_GRAYSCALE) gives it for a PNG (libpng transforms)."""
    if pixels.colour.ndim == 2:
        if pixels.colour.dtype == np.uint16:
            return (pixels.colour >> 8).astype(np.uint8)
        return pixels.colour.copy()
    return _luma(pixels.colour, weights=_LIBPNG_LUMA, shift=_LIBPNG_LUMA_SHIFT, rounded=False, grey_exact=True)


def transparent_mask(alpha: np.ndarray | None) -> np.ndarray | None:
    if alpha is None:
        return None
    half = (int(np.iinfo(alpha.dtype).max) + 1) // 2
    return alpha < half
