"""The plain 8-bit PNGs most maps are, decoded by OpenCV instead of Pillow: the same pixels, sooner.

Why: a ``ursim segment`` of a sketch is a process of a few tenths of a second, and importing
Pillow took about 20 ms of it, where OpenCV, which the segmentation loads anyway, decodes the
same file in a few. Pillow stays the decoder of everything else (other formats, palettes,
transparency keys, 16 bits, interlacing, text or colour-profile chunks, EXIF, any file that is
not entirely well formed) and of every error message.

The contract of :func:`decode_plain_png`: it returns the colour and alpha arrays
that Pillow's path of :func:`~ursim_core.io.images.decode_image` would give, or None ("ask
Pillow"); it never raises and never lets libpng print. OpenCV's libpng writes a warning or an
error on stderr for many defects that Pillow decodes quietly (extra compressed data, an odd
ancillary chunk), so only a file checked here to have none of them reaches OpenCV:

* the signature, then IHDR (8 bits; grey, grey+alpha, RGB or RGBA; not interlaced; at most
  ``max_pixels`` and :data:`MAX_RAW_BYTES` of filtered rows), then only ``pHYs``, ``tIME``
  and ``bKGD`` with the values libpng accepts silently, one run of IDAT, and IEND, each chunk
  with its CRC right;
* the zlib stream of the IDATs inflates, with the window its header declares (as libpng
  does), to exactly the filtered rows, ends exactly where the IDAT data ends, and every row
  starts with a filter type of 0 to 4.

Checking the stream costs one more inflate, so files of more than :data:`MAX_RAW_BYTES`
of filtered rows, where that would cost more than importing Pillow saves, go to Pillow. A test
compares the two decoders on every image of the research datasets and on hand-made defects.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

__all__ = ["decode_plain_png", "plain_png_size", "MAX_RAW_BYTES"]

#: The largest PNG (bytes of filtered rows, ``rows * (1 + row bytes)``) decoded here: the
#: extra inflate costs about 2.5 ms per MB, Pillow's import about 20 ms.
MAX_RAW_BYTES = 8 << 20

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# Colour type -> channels, for the colour types decoded here (no palette).
_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}
# OpenCV's own limit on either side (CV_IO_MAX_IMAGE_WIDTH / HEIGHT) is 2**20.
_MAX_SIDE = 1 << 16


def _ihdr(data: bytes) -> tuple[int, int, int, int, int, int, int] | None:
    """The fields of a well-formed IHDR that opens ``data`` (CRC checked), else None."""
    if len(data) < 33 or not data.startswith(_SIGNATURE) or data[8:16] != b"\x00\x00\x00\x0dIHDR":
        return None
    body = data[16:29]
    if zlib.crc32(data[12:29]) != struct.unpack_from(">I", data, 29)[0]:
        return None
    return struct.unpack(">IIBBBBB", body)


def plain_png_size(head: bytes, *, max_pixels: int) -> tuple[int, int] | None:
    """(width, height) of a PNG whose IHDR is well formed and within ``max_pixels``, else None.

    For the header check before the whole file is read: where this gives a size, Pillow
    would either give the same or fail to open the head, and both let the file through.
    """
    fields = _ihdr(head)
    if fields is None:
        return None
    width, height = fields[0], fields[1]
    if width == 0 or height == 0 or width * height > max_pixels:
        return None
    return width, height


def _chunks(data: bytes):
    """(type, body) of each chunk after the signature up to IEND; None on any defect."""
    chunks = []
    position, end = 8, len(data)
    while True:
        if position + 12 > end:
            return None
        (length,) = struct.unpack_from(">I", data, position)
        body_end = position + 8 + length
        if length > 0x7FFFFFFF or body_end + 4 > end:
            return None
        kind = data[position + 4 : position + 8]
        view = memoryview(data)[position + 8 : body_end]
        if zlib.crc32(view, zlib.crc32(kind)) != struct.unpack_from(">I", data, body_end)[0]:
            return None
        chunks.append((kind, view))
        position = body_end + 4
        if kind == b"IEND":
            return chunks


def _ancillary_is_quiet(kind: bytes, body: memoryview, colour_type: int) -> bool:
    """A chunk libpng reads without a word (before the IDATs, once, its values in range)."""
    if kind == b"pHYs":
        return len(body) == 9
    if kind == b"tIME":
        if len(body) != 7:
            return False
        _, month, day, hour, minute, second = struct.unpack(">HBBBBB", body)
        return 1 <= month <= 12 and 1 <= day <= 31 and hour <= 23 and minute <= 59 and second <= 60
    if kind == b"bKGD":
        values = bytes(body)
        expected = 2 if colour_type in (0, 4) else 6
        # 8-bit images: a 16-bit sample above 255 is "invalid" to libpng (a warning).
        return len(values) == expected and not any(values[0::2])
    return False


def _filtered_rows(idat: list[memoryview], expected: int) -> bytes | None:
    """The IDAT stream inflated, when it is exactly ``expected`` bytes and nothing more."""
    inflater = zlib.decompressobj(wbits=0)  # the window of the zlib header, as libpng reads it
    parts = []
    size = 0
    try:
        for body in idat:
            if inflater.eof:
                return None  # an IDAT after the end of the stream
            # At most what is expected (plus one byte to see an excess) is ever held.
            part = inflater.decompress(body, expected + 1 - size)
            size += len(part)
            parts.append(part)
            if inflater.unconsumed_tail or size > expected:
                return None
    except zlib.error:
        return None
    if not inflater.eof or inflater.unused_data or size != expected:
        return None
    return b"".join(parts)


def decode_plain_png(data: bytes, *, max_pixels: int) -> tuple[np.ndarray, np.ndarray | None] | None:
    """``(colour, alpha)`` of a plain 8-bit PNG, as :class:`~ursim_core.io.images.Pixels` holds them, or None.

    Parameters
    ----------
    data : bytes
        The whole file.
    max_pixels : int
        A larger image is left to Pillow's path, which refuses it with its own message.

    Returns
    -------
    tuple of ndarray or None
        ``colour`` (rows, cols) grey or (rows, cols, 3) RGB, uint8, and ``alpha`` (rows, cols)
        uint8 or None: what Pillow's path gives for this file. None when this decoder does not
        take the file.
    """
    fields = _ihdr(data)
    if fields is None:
        return None
    width, height, depth, colour_type, compression, filtering, interlace = fields
    channels = _CHANNELS.get(colour_type)
    if channels is None or depth != 8 or compression or filtering or interlace:
        return None
    if not (0 < width <= _MAX_SIDE and 0 < height <= _MAX_SIDE) or width * height > max_pixels:
        return None
    row_bytes = 1 + width * channels
    if height * row_bytes > MAX_RAW_BYTES:
        return None
    chunks = _chunks(data)
    if chunks is None:
        return None
    idat, seen = [], set()
    for kind, body in chunks[1:-1]:
        if kind == b"IDAT":
            idat.append(body)
        elif idat or kind in seen or not _ancillary_is_quiet(kind, body, colour_type):
            return None  # after the IDATs, repeated or not one of ours: Pillow's business
        else:
            seen.add(kind)
    if not idat or len(chunks[-1][1]) != 0:
        return None
    rows = _filtered_rows(idat, height * row_bytes)
    if rows is None or max(rows[0::row_bytes]) > 4:
        return None
    import cv2

    decoded = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    # OpenCV gives grey as 2-D, colour as BGR(A), and expands grey+alpha to BGRA.
    expected_shape = (height, width) if channels == 1 else (height, width, 4 if channels == 2 else channels)
    if decoded is None or decoded.dtype != np.uint8 or decoded.shape != expected_shape:
        return None
    if channels == 1:
        return decoded, None
    if channels == 2:
        return decoded[..., 0].copy(), decoded[..., 3].copy()
    alpha = decoded[..., 3].copy() if channels == 4 else None
    return decoded[..., 2::-1].copy(), alpha
