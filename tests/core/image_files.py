"""Image files for the bad-input tests: a PNG whose header declares any size, with almost no data."""

from __future__ import annotations

import struct
import zlib


def png_header_only(path, width: int, height: int):
    """A PNG whose header declares ``width`` x ``height`` pixels (grey, 8 bit), with almost no data."""

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\0" * 100)) + chunk(b"IEND", b"")
    )
    return path
