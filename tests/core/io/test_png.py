"""The OpenCV decoder of plain 8-bit PNGs gives Pillow's pixels, and leaves every other file to Pillow."""

from __future__ import annotations

import io
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, PngImagePlugin

from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.io import images
from ursim_core.io.png import MAX_RAW_BYTES, decode_plain_png, plain_png_size

LIMIT = 64_000_000
RNG = np.random.default_rng(7)
GREY = RNG.integers(0, 256, (37, 53), dtype=np.uint8)
RGB = RNG.integers(0, 256, (37, 53, 3), dtype=np.uint8)
ALPHA = RNG.integers(0, 256, (37, 53), dtype=np.uint8)


def png_bytes(array: np.ndarray, mode: str | None = None, **save) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(array, mode).save(buffer, format="PNG", **save)
    return buffer.getvalue()


def chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    found, position = [], 8
    while position < len(data):
        (length,) = struct.unpack_from(">I", data, position)
        found.append((data[position + 4 : position + 8], data[position + 8 : position + 8 + length]))
        position += 12 + length
    return found


def chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def rebuilt(data: bytes, *, before_idat: bytes = b"", idat: bytes | None = None, after: bytes = b"") -> bytes:
    """The PNG ``data`` with chunks inserted before its IDATs, its stream replaced, or bytes appended."""
    parts = chunks(data)
    header = data[:8] + chunk(*parts[0])
    stream = b"".join(body for kind, body in parts if kind == b"IDAT")
    return header + before_idat + chunk(b"IDAT", stream if idat is None else idat) + chunk(b"IEND", b"") + after


def raw_rows(data: bytes) -> bytes:
    return zlib.decompress(b"".join(body for kind, body in chunks(data) if kind == b"IDAT"))


def pillow_pixels(data: bytes, monkeypatch) -> images.Pixels:
    with monkeypatch.context() as patch:
        patch.setattr(images, "decode_plain_png", lambda data, max_pixels: None)
        return images.decode_image(data, Path("x.png"), max_pixels=LIMIT, apply_exif_orientation=True)


def assert_same_as_pillow(data: bytes, monkeypatch) -> None:
    colour, alpha = decode_plain_png(data, max_pixels=LIMIT)
    expected = pillow_pixels(data, monkeypatch)
    assert colour.dtype == expected.colour.dtype and colour.flags.c_contiguous
    np.testing.assert_array_equal(colour, expected.colour)
    if expected.alpha is None:
        assert alpha is None
    else:
        np.testing.assert_array_equal(alpha, expected.alpha)


PLAIN = {
    "grey": png_bytes(GREY),
    "rgb": png_bytes(RGB),
    "rgba": png_bytes(np.dstack([RGB, ALPHA])),
    "grey+alpha": png_bytes(np.dstack([GREY, ALPHA]), "LA"),
    "dpi (pHYs)": png_bytes(RGB, dpi=(72.009, 72.009)),
    "bKGD and tIME": rebuilt(
        png_bytes(RGB), before_idat=chunk(b"bKGD", bytes(6)) + chunk(b"tIME", b"\x07\xd0\x01\x01\x00\x00\x00")
    ),
    "split IDAT": png_bytes(RGB)[:33]
    + chunk(b"IDAT", zlib.compress(raw_rows(png_bytes(RGB)))[:50])
    + chunk(b"IDAT", zlib.compress(raw_rows(png_bytes(RGB)))[50:])
    + chunk(b"IEND", b""),
    "bytes after IEND": png_bytes(RGB) + b"trailing",
}


@pytest.mark.parametrize("name", PLAIN)
def test_plain_pngs_decode_to_pillows_pixels(name, monkeypatch):
    assert_same_as_pillow(PLAIN[name], monkeypatch)


def _text_chunk() -> bytes:
    info = PngImagePlugin.PngInfo()
    info.add_text("Comment", "a map")
    return png_bytes(RGB, pnginfo=info)


def _palette() -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(RGB).quantize(8).save(buffer, format="PNG")
    return buffer.getvalue()


def _exif_turned() -> bytes:
    exif = Image.Exif()
    exif[0x0112] = 3
    return png_bytes(RGB, exif=exif.tobytes())


RGB_PNG = png_bytes(RGB)
ROWS = raw_rows(RGB_PNG)
LEFT_TO_PILLOW = {
    "palette": _palette(),
    "transparency key": png_bytes(GREY, transparency=255),
    "16-bit grey": png_bytes(GREY.astype(np.uint16) * 257),
    "1-bit": png_bytes(GREY > 127),
    "text chunk (may hold EXIF or XMP)": _text_chunk(),
    "EXIF orientation": _exif_turned(),
    "gAMA": rebuilt(RGB_PNG, before_idat=chunk(b"gAMA", struct.pack(">I", 45455))),
    "unknown ancillary chunk": rebuilt(RGB_PNG, before_idat=chunk(b"abcd", b"x")),
    "unknown critical chunk": rebuilt(RGB_PNG, before_idat=chunk(b"ABCD", b"x")),
    "repeated pHYs": rebuilt(RGB_PNG, before_idat=2 * chunk(b"pHYs", bytes(9))),
    "bKGD above 255": rebuilt(RGB_PNG, before_idat=chunk(b"bKGD", b"\x01\x00" + bytes(4))),
    "invalid tIME": rebuilt(RGB_PNG, before_idat=chunk(b"tIME", b"\x07\xd0\x0d\x01\x00\x00\x00")),
    "bad CRC": RGB_PNG[:-30] + bytes([RGB_PNG[-30] ^ 0xFF]) + RGB_PNG[-29:],
    "truncated": RGB_PNG[:-20],
    "no IEND": RGB_PNG[: -len(chunk(b"IEND", b""))],
    "extra compressed data": rebuilt(RGB_PNG, idat=zlib.compress(ROWS) + b"junk"),
    "too much image data": rebuilt(RGB_PNG, idat=zlib.compress(ROWS + bytes(54))),
    "not enough image data": rebuilt(RGB_PNG, idat=zlib.compress(ROWS[:-100])),
    "bad filter type": rebuilt(RGB_PNG, idat=zlib.compress(b"\x07" + ROWS[1:])),
    "corrupt stream": rebuilt(RGB_PNG, idat=b"\x78\x9c" + bytes(40)),
    "IDAT after the stream ended": rebuilt(RGB_PNG, after=b"")[:-12] + chunk(b"IDAT", b"") + chunk(b"IEND", b""),
    "chunk after the IDATs": rebuilt(RGB_PNG)[:-12]
    + chunk(b"tIME", b"\x07\xd0\x01\x01\x00\x00\x00")
    + chunk(b"IEND", b""),
    "not a PNG": b"GIF89a" + bytes(100),
    "empty": b"",
}


@pytest.mark.parametrize("name", LEFT_TO_PILLOW)
def test_other_files_are_left_to_pillow(name):
    # OpenCV never sees these: libpng would print a warning or an error on stderr for many.
    assert decode_plain_png(LEFT_TO_PILLOW[name], max_pixels=LIMIT) is None


def test_limits_leave_the_file_to_pillow():
    data = PLAIN["grey"]
    assert decode_plain_png(data, max_pixels=GREY.size - 1) is None
    side = int((MAX_RAW_BYTES // 4) ** 0.5) + 2
    big = png_bytes(np.zeros((side, side, 4), np.uint8))
    assert decode_plain_png(big, max_pixels=LIMIT) is None


def test_header_size_only_when_well_formed_and_within_the_limit():
    data = PLAIN["rgb"]
    assert plain_png_size(data[:100], max_pixels=LIMIT) == (53, 37)
    assert plain_png_size(data[:100], max_pixels=100) is None
    assert plain_png_size(LEFT_TO_PILLOW["not a PNG"], max_pixels=LIMIT) is None
    broken = data[:20] + bytes([data[20] ^ 1]) + data[21:]  # IHDR CRC no longer matches
    assert plain_png_size(broken, max_pixels=LIMIT) is None


def test_loading_a_plain_png_map_does_not_import_pillow(tmp_path):
    path = tmp_path / "room.png"
    room = np.zeros((30, 40, 4), np.uint8)
    room[5:25, 5:35] = 255
    room[..., 3] = 255
    path.write_bytes(png_bytes(room))
    code = f"import sys; from ursim_core.io import load_map; load_map({str(path)!r}); print('PIL' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False" and result.stderr == ""


@pytest.mark.dataset
def test_every_dataset_png_it_takes_decodes_to_pillows_pixels(monkeypatch):
    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    taken = 0
    for path in sorted(root.rglob("*.png")):
        data = path.read_bytes()
        if decode_plain_png(data, max_pixels=LIMIT) is not None:
            taken += 1
            assert_same_as_pillow(data, monkeypatch)
    assert taken > 100  # the KTH sketches and most robot maps are plain PNGs
