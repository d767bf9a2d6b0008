"""An image file read as stored (OpenCV's ``IMREAD_UNCHANGED``: 16-bit and colour kept), guarded.

Label images are read this way: their ids are the stored values. OpenCV decodes whatever it is
given, so the file is checked first, as the map loader checks maps: a FIFO or a directory, a
header declaring more pixels than allowed (OpenCV raised a traceback or ran out of memory), a
format whose size cannot be read, or a PNG with a cut or damaged chunk (OpenCV only logs a
warning on stderr for it) is an error naming the file.
"""

from __future__ import annotations

import io
import warnings
import zlib
from pathlib import Path

import numpy as np

__all__ = ["read_unchanged", "read_label_array"]


def read_unchanged(path: str | Path, *, max_pixels: int | None = None, error=None) -> np.ndarray | None:
    """The pixels of the image at ``path`` as stored, or None when OpenCV cannot decode them.

    Parameters
    ----------
    path : path
        The image file.
    max_pixels : int, optional
        Largest image read (default :data:`~ursim_core.io.maps.DEFAULT_MAX_PIXELS`, the map loader's).
    error : type, optional
        The :class:`~ursim_core.errors.UrsimError` class raised, naming ``path``
        (default :class:`~ursim_core.errors.MapError`).

    Examples
    --------
    >>> import tempfile, cv2
    >>> path = Path(tempfile.mkdtemp()) / "labels.png"
    >>> _ = cv2.imwrite(str(path), np.array([[0, 1], [2, 300]], np.uint16))
    >>> read_unchanged(path)
    array([[  0,   1],
           [  2, 300]], dtype=uint16)
    """
    import cv2

    from ursim_core.errors import MapError, file_not_found
    from ursim_core.io.images import read_file_bytes
    from ursim_core.io.maps import DEFAULT_MAX_PIXELS
    from ursim_core.io.png import plain_png_size

    path, error = Path(path), error or MapError
    max_pixels = DEFAULT_MAX_PIXELS if max_pixels is None else max_pixels
    try:
        data = read_file_bytes(path, empty_problem="empty file, not an image", max_pixels=max_pixels)
    except MapError as problem:
        if isinstance(problem, FileNotFoundError):
            raise file_not_found(error, problem.problem, path=path) from None
        raise error(problem.problem, path=path) from None
    if plain_png_size(data, max_pixels=max_pixels) is None:
        # The header check lets through a file whose head Pillow cannot read alone (a small file,
        # a format that keeps its size late): the size is read from the whole file.
        from PIL import Image

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                width, height = Image.open(io.BytesIO(data)).size
            except Image.DecompressionBombError:
                raise error("not read: more pixels than Pillow's decompression-bomb limit", path=path) from None
            except Exception:  # Pillow raises many kinds for what it cannot identify
                raise error("not a readable image", path=path) from None
        if not 0 < width * height <= max_pixels:
            raise error(f"image of {width} x {height} pixels (at most max_pixels={max_pixels} are read)", path=path)
    if data.startswith(b"\x89PNG") and not _png_chunks_intact(data):
        raise error("truncated or corrupt image data (a PNG chunk is cut or fails its CRC)", path=path)
    try:
        return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error:
        return None


def _png_chunks_intact(data: bytes) -> bool:
    """Whether every chunk of a PNG up to IEND is whole and passes its CRC (nothing decoded).

    Checked here rather than by Pillow's verify: importing Pillow takes 12 ms, on the path every
    label image takes.
    """
    view, position = memoryview(data), 8
    while position + 12 <= len(data):
        length = int.from_bytes(view[position : position + 4], "big")
        end = position + 8 + length
        if end + 4 > len(data) or zlib.crc32(view[position + 4 : end]) != int.from_bytes(view[end : end + 4], "big"):
            return False
        if view[position + 4 : position + 8] == b"IEND":
            return True
        position = end + 4
    return False


def read_label_array(path: str | Path, *, max_pixels: int | None = None) -> np.ndarray:
    """Read a label image file as an int32 array of the stored ids (0 = no region).

    Accepts 8- or 16-bit single-channel images, and colour images whose channels are equal.
    Raises :class:`~ursim_core.errors.SegmentationError` naming the file otherwise, or when the
    file is not a regular file, is cut, or declares more than ``max_pixels`` pixels in its header
    (checked before decoding, :func:`ursim_core.io.unchanged.read_unchanged`; default
    :data:`~ursim_core.io.maps.DEFAULT_MAX_PIXELS`, the map loader's).
    """
    from ursim_core.errors import SegmentationError, SegmentationFileNotFoundError

    path = Path(path)
    if not path.exists():
        raise SegmentationFileNotFoundError("label image not found", path=path)
    labels = read_unchanged(path, max_pixels=max_pixels, error=SegmentationError)
    if labels is None:
        raise SegmentationError("not a readable image", path=path)
    if labels.ndim == 3:
        channels = labels[..., :3]
        if not (
            np.array_equal(channels[..., 0], channels[..., 1]) and np.array_equal(channels[..., 0], channels[..., 2])
        ):
            raise SegmentationError("a label image must have one channel (grey, 8 or 16 bit), got colour", path=path)
        labels = channels[..., 0]
    if labels.dtype not in (np.uint8, np.uint16):
        raise SegmentationError(f"a label image must be 8 or 16 bit, got {labels.dtype}", path=path)
    return labels.astype(np.int32)
