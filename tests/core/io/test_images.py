"""Decoding map images (ursim_core.io.images): formats, modes, bit depths, EXIF, pixel limits, broken files."""

from __future__ import annotations

import io
import struct
import warnings
import zlib

import cv2
import numpy as np
import pytest
from io_helpers import GREY, GREY_FREE, _refused, save
from PIL import Image, ImageFile, PngImagePlugin

from ursim_core.errors import MapError
from ursim_core.io.maps import DEFAULT_MAX_PIXELS, load_map, map_from_array


def png_bytes(width: int, height: int, *, with_idat: bool = True) -> bytes:
    """A PNG file with a valid IHDR declaring (width, height) and no real pixel data."""

    def chunk(kind: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    header = chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
    body = chunk(b"IDAT", zlib.compress(b"")) if with_idat else b""
    return b"\x89PNG\r\n\x1a\n" + header + body + chunk(b"IEND", b"")


def cv_luma(rgb: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2GRAY)


# ---------------------------------------------------------------------------------------------
# Formats and modes


@pytest.mark.parametrize(
    ("file_name", "options"),
    [
        ("grey.png", {}),
        ("grey.bmp", {}),
        ("grey.tif", {}),
        ("grey.pgm", {}),  # Pillow writes binary P5
        ("grey.gif", {}),
    ],
)
def test_grey_formats_threshold_above_250(tmp_path, file_name, options):
    path = save(Image.fromarray(GREY), tmp_path / file_name, **options)
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.free, GREY_FREE)
    np.testing.assert_array_equal(loaded.image, GREY)
    assert loaded.free.dtype == np.bool_ and loaded.image.dtype == np.uint8
    assert loaded.occupancy is None and loaded.resolution is None and loaded.origin is None


def test_ascii_pgm_p2(tmp_path):
    path = tmp_path / "ascii.pgm"
    path.write_text("P2\n# a comment line\n4 2\n255\n0 255 251 250\n100 255 0 252\n")
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.free, [[False, True, True, False], [False, True, False, True]])


def test_binary_ppm_p6_colour(tmp_path):
    rgb = np.zeros((2, 3, 3), np.uint8)
    rgb[0, 0] = (255, 255, 255)
    rgb[0, 1] = (255, 255, 200)  # luma 249: not free
    rgb[1, 2] = (251, 251, 251)
    path = save(Image.fromarray(rgb), tmp_path / "colour.ppm")
    assert path.read_bytes().startswith(b"P6")
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.image, cv_luma(rgb))
    np.testing.assert_array_equal(loaded.free, [[True, False, False], [False, False, True]])


def test_rgb_png_uses_opencv_luma(tmp_path):
    rng = np.random.default_rng(3)
    rgb = rng.integers(0, 256, size=(17, 23, 3), dtype=np.uint8)
    rgb[:4, :4] = 255
    loaded = load_map(save(Image.fromarray(rgb), tmp_path / "rgb.png"))
    np.testing.assert_array_equal(loaded.image, cv_luma(rgb))
    np.testing.assert_array_equal(loaded.free, cv_luma(rgb) > 250)


def test_luma_known_values():
    # 0.299 * 255 = 76.2, 0.587 * 255 = 149.7, 0.114 * 255 = 29.1
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]], dtype=np.uint8)
    loaded = map_from_array(rgb, threshold=200)
    np.testing.assert_array_equal(loaded.image, [[76, 150, 29, 255]])


def test_grey_alpha_png_transparent_is_obstacle(tmp_path):
    grey = np.full((2, 3), 255, np.uint8)
    alpha = np.array([[255, 128, 127], [0, 255, 255]], np.uint8)
    grey[1, 2] = 0
    path = save(Image.fromarray(np.dstack([grey, alpha]), "LA"), tmp_path / "la.png")
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.free, [[True, True, False], [False, True, False]])
    np.testing.assert_array_equal(loaded.image, [[255, 255, 0], [0, 255, 0]])


def test_rgba_png_transparent_is_obstacle(tmp_path):
    rgba = np.zeros((2, 2, 4), np.uint8)
    rgba[..., :3] = 255
    rgba[..., 3] = [[255, 0], [127, 200]]
    loaded = load_map(save(Image.fromarray(rgba, "RGBA"), tmp_path / "rgba.png"))
    np.testing.assert_array_equal(loaded.free, [[True, False], [False, True]])
    np.testing.assert_array_equal(loaded.image, [[255, 0], [0, 255]])


def test_palette_png_without_transparency(tmp_path):
    image = Image.fromarray(np.array([[0, 1, 2, 3]], np.uint8), "P")
    image.putpalette([0, 0, 0, 255, 255, 255, 255, 255, 200, 251, 251, 251])
    loaded = load_map(save(image, tmp_path / "palette.png"))
    np.testing.assert_array_equal(loaded.image, [[0, 255, 249, 251]])
    np.testing.assert_array_equal(loaded.free, [[False, True, False, True]])


def test_palette_png_with_transparent_index(tmp_path):
    image = Image.fromarray(np.array([[0, 1, 2]], np.uint8), "P")
    image.putpalette([0, 0, 0, 255, 255, 255, 255, 255, 255])
    loaded = load_map(save(image, tmp_path / "palette_t.png", transparency=2))
    np.testing.assert_array_equal(loaded.free, [[False, True, False]])
    np.testing.assert_array_equal(loaded.image, [[0, 255, 0]])


def test_grey_png_with_transparency_key(tmp_path):
    grey = np.array([[255, 254, 200]], np.uint8)
    loaded = load_map(save(Image.fromarray(grey), tmp_path / "key.png", transparency=254))
    np.testing.assert_array_equal(loaded.free, [[True, False, False]])
    np.testing.assert_array_equal(loaded.image, [[255, 0, 200]])


def test_rgb_png_with_transparency_key(tmp_path):
    rgb = np.full((1, 2, 3), 255, np.uint8)
    rgb[0, 1] = (254, 255, 255)
    loaded = load_map(save(Image.fromarray(rgb), tmp_path / "rgbkey.png", transparency=(254, 255, 255)))
    np.testing.assert_array_equal(loaded.free, [[True, False]])


def test_bilevel_png(tmp_path):
    bits = Image.fromarray(np.array([[0, 255, 255], [255, 0, 0]], np.uint8)).convert("1")
    loaded = load_map(save(bits, tmp_path / "bits.png"))
    np.testing.assert_array_equal(loaded.free, [[False, True, True], [True, False, False]])


# 16-bit to 8-bit is round(v / 257): 64378 -> 250.498 -> 250 (not free), 64379 -> 251 (free).
WORDS = np.array([[0, 257 * 251, 64378, 64379, 65535, 257 * 250]], dtype=np.uint16)
WORDS_GREY = np.array([[0, 251, 250, 251, 255, 250]], dtype=np.uint8)


@pytest.mark.parametrize("file_name", ["words.png", "words.tif"])
def test_16_bit_grey_png_and_tiff(tmp_path, file_name):
    path = save(Image.fromarray(WORDS), tmp_path / file_name)
    assert Image.open(path).mode.startswith("I;16")
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.image, WORDS_GREY)
    np.testing.assert_array_equal(loaded.free, WORDS_GREY > 250)


def test_16_bit_pgm(tmp_path):
    path = tmp_path / "words.pgm"
    path.write_bytes(b"P5\n6 1\n65535\n" + WORDS.astype(">u2").tobytes())
    loaded = load_map(path)
    np.testing.assert_array_equal(loaded.image, WORDS_GREY)


def test_32_bit_integer_tiff_within_16_bit_range(tmp_path):
    path = save(Image.fromarray(WORDS.astype(np.int32)), tmp_path / "int32.tif")
    assert Image.open(path).mode == "I"
    np.testing.assert_array_equal(load_map(path).image, WORDS_GREY)


def test_jpeg_with_block_aligned_content(tmp_path):
    # Uniform 8x8-aligned blocks survive JPEG compression (only the DC term is non-zero).
    grey = np.zeros((32, 48), np.uint8)
    grey[8:24, 16:40] = 255
    loaded = load_map(save(Image.fromarray(grey), tmp_path / "room.jpg", quality=95))
    np.testing.assert_array_equal(loaded.free, grey > 250)


def test_jpeg_exif_orientation_is_applied(tmp_path):
    grey = np.zeros((16, 32), np.uint8)
    grey[:, :16] = 255
    exif = Image.Exif()
    exif[0x0112] = 6  # "rotate 90 degrees clockwise to display"
    loaded = load_map(save(Image.fromarray(grey), tmp_path / "phone.jpg", quality=95, exif=exif))
    displayed = np.rot90(grey, k=-1)
    assert loaded.shape == (32, 16)
    np.testing.assert_array_equal(loaded.free, displayed > 250)


# ---------------------------------------------------------------------------------------------
# Errors on image files


def test_text_file_with_png_extension(tmp_path):
    path = tmp_path / "notes.png"
    path.write_text("this is not a picture\n")
    with pytest.raises(MapError, match="not an image") as caught:
        load_map(path)
    assert "notes.png" in str(caught.value)


@pytest.mark.parametrize("cut", ["half", "last_chunk"])
def test_truncated_png(tmp_path, cut):
    rng = np.random.default_rng(1)
    data = io.BytesIO()
    Image.fromarray(rng.integers(0, 256, size=(60, 60), dtype=np.uint8)).save(data, "PNG")
    full = data.getvalue()
    # "last_chunk" drops IEND (12 bytes) and the end of IDAT (its CRC and the zlib checksum)
    # but keeps every image row, which Pillow's decoder alone accepts.
    kept = len(full) // 2 if cut == "half" else len(full) - 20
    path = tmp_path / "cut.png"
    path.write_bytes(full[:kept])
    with pytest.raises(MapError, match="truncated or corrupt") as caught:
        load_map(path)
    assert "cut.png" in str(caught.value)


def test_png_with_corrupted_pixel_data(tmp_path):
    buffer = io.BytesIO()
    Image.fromarray(np.full((30, 30), 255, np.uint8)).save(buffer, "PNG")
    data = bytearray(buffer.getvalue())
    idat = data.index(b"IDAT")
    data[idat + 6] ^= 0xFF  # flip bits inside the compressed stream; the CRC no longer matches
    path = tmp_path / "flipped.png"
    path.write_bytes(bytes(data))
    with pytest.raises(MapError, match="truncated or corrupt") as caught:
        load_map(path)
    assert "flipped.png" in str(caught.value)


def test_truncated_jpeg(tmp_path):
    rng = np.random.default_rng(2)
    buffer = io.BytesIO()
    Image.fromarray(rng.integers(0, 256, size=(64, 64), dtype=np.uint8)).save(buffer, "JPEG")
    path = tmp_path / "cut.jpg"
    path.write_bytes(buffer.getvalue()[: len(buffer.getvalue()) // 2])
    with pytest.raises(MapError, match="truncated or corrupt") as caught:
        load_map(path)
    assert "cut.jpg" in str(caught.value)


def test_zero_byte_file(tmp_path):
    path = tmp_path / "empty.png"
    path.write_bytes(b"")
    with pytest.raises(MapError, match="zero-size") as caught:
        load_map(path)
    assert "empty.png" in str(caught.value) and "0 bytes" in str(caught.value)


def test_pgm_with_zero_width(tmp_path):
    path = tmp_path / "flat.pgm"
    path.write_bytes(b"P5\n0 5\n255\n")
    with pytest.raises(MapError, match=r"zero-size image \(0 x 5 pixels\)") as caught:
        load_map(path)
    assert "flat.pgm" in str(caught.value)


def test_png_with_zero_height(tmp_path):
    path = tmp_path / "flat.png"
    path.write_bytes(png_bytes(7, 0))
    with pytest.raises(MapError, match=r"zero-size image \(7 x 0 pixels\)") as caught:
        load_map(path)
    assert "flat.png" in str(caught.value)


def test_pixel_limit_checked_from_header_before_decoding(tmp_path, monkeypatch):
    path = save(Image.fromarray(np.full((20, 20), 255, np.uint8)), tmp_path / "big.png")

    def refuse_to_decode(*args, **kwargs):
        raise AssertionError("pixels were decoded before the size check")

    monkeypatch.setattr(ImageFile.ImageFile, "load", refuse_to_decode)
    monkeypatch.setattr(PngImagePlugin.PngImageFile, "verify", refuse_to_decode)
    with pytest.raises(MapError, match="max_pixels=100") as caught:
        load_map(path, max_pixels=100)
    message = str(caught.value)
    assert "big.png" in message and "400 pixels" in message and "20 x 20" in message


def test_pixel_limit_allows_exactly_the_limit(tmp_path):
    path = save(Image.fromarray(np.full((10, 10), 255, np.uint8)), tmp_path / "hundred.png")
    assert load_map(path, max_pixels=100).free.all()


@pytest.mark.parametrize(("width", "height"), [(10_000, 9_000), (100_000, 100_000)])
def test_huge_header_is_refused_with_our_limit(tmp_path, width, height):
    # 9e7 pixels makes Pillow warn (above its 89M limit); 1e10 makes it raise
    # DecompressionBombError. Both must become our MapError, with no warning leaking out.
    path = tmp_path / "bomb.png"
    path.write_bytes(png_bytes(width, height))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(MapError, match=f"max_pixels={DEFAULT_MAX_PIXELS}") as caught:
            load_map(path)
    assert "bomb.png" in str(caught.value)


def test_limit_above_pillows_own_is_honoured(tmp_path, monkeypatch):
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 50)
    path = save(Image.fromarray(np.full((20, 20), 255, np.uint8)), tmp_path / "wide.png")
    assert load_map(path, max_pixels=1000).free.all()
    assert Image.MAX_IMAGE_PIXELS == 50
    with pytest.raises(MapError, match="max_pixels=300"):
        load_map(path, max_pixels=300)


@pytest.mark.parametrize(
    ("mode", "file_name"),
    [("F", "float.tif"), ("CMYK", "print.jpg")],
)
def test_unsupported_mode(tmp_path, mode, file_name):
    path = save(Image.new(mode, (4, 4)), tmp_path / file_name)
    with pytest.raises(MapError, match=f"unsupported image mode '{mode}'") as caught:
        load_map(path)
    assert file_name in str(caught.value)


def test_32_bit_values_beyond_16_bit_are_unsupported(tmp_path):
    path = save(Image.fromarray(np.array([[0, 70_000]], np.int32)), tmp_path / "deep.tif")
    with pytest.raises(MapError, match="unsupported image mode 'I'") as caught:
        load_map(path)
    assert "deep.tif" in str(caught.value)


# --------------------------------------------------------------------------- issue 12, items 12 and 14: no Pillow warning, our limit only


def _png_header(width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` grey pixels (no pixel data follows)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b"")


def test_truncated_tiff_prints_no_pillow_warning(tmp_path):
    buffer = io.BytesIO()
    Image.fromarray(np.full((64, 64), 255, np.uint8)).save(buffer, format="TIFF")
    path = tmp_path / "cut.tif"
    path.write_bytes(buffer.getvalue()[:-3000])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _refused(path)


def test_bomb_message_quotes_our_limit_only(tmp_path):
    path = tmp_path / "bomb.png"
    path.write_bytes(_png_header(20_000, 20_000))
    with pytest.raises(MapError) as caught:
        load_map(path, max_pixels=1000)
    assert "178956970" not in str(caught.value)
    assert "max_pixels=1000" in str(caught.value)
    with pytest.raises(MapError) as caught:
        load_map(path)
    assert "178956970" not in str(caught.value) and "357913941" not in str(caught.value)
