"""Tests of ursim_core.io.maps: image and ROS YAML loading, errors, pixel/world conversion."""

from __future__ import annotations

import hashlib
import io
import math
import struct
import subprocess
import sys
import warnings
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, ImageFile, PngImagePlugin

from ursim_core.errors import MapError, ParameterError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.io.maps import (
    DEFAULT_MAX_PIXELS,
    OCCUPANCY_FREE,
    OCCUPANCY_OCCUPIED,
    OCCUPANCY_UNKNOWN,
    Map,
    load_map,
    map_from_array,
    pixel_to_world,
    world_to_pixel,
)

# Grey values around the default threshold (250) and 0, the cases binarisation must get right.
GREY = np.array(
    [
        [0, 1, 100, 249, 250, 251],
        [255, 254, 252, 0, 128, 255],
        [250, 251, 0, 255, 10, 200],
    ],
    dtype=np.uint8,
)
GREY_FREE = GREY > 250


def save(image: Image.Image, path: Path, **options) -> Path:
    image.save(path, **options)
    return path


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


def test_path_sha256_and_name(tmp_path):
    path = save(Image.fromarray(GREY), tmp_path / "office.png")
    loaded = load_map(str(path))
    assert loaded.path == path and isinstance(loaded.path, Path)
    assert loaded.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert loaded.name == "office" and loaded.shape == GREY.shape


# ---------------------------------------------------------------------------------------------
# Threshold and nonzero_free


def test_threshold_option(tmp_path):
    path = save(Image.fromarray(GREY), tmp_path / "grey.png")
    np.testing.assert_array_equal(load_map(path, threshold=99).free, GREY > 99)
    np.testing.assert_array_equal(load_map(path, threshold=0).free, GREY > 0)
    np.testing.assert_array_equal(load_map(path, threshold=250.5).free, GREY > 250)


@pytest.mark.parametrize("threshold", [-1, 256, float("nan"), "250", True, None])
def test_threshold_out_of_range_is_parameter_error(tmp_path, threshold):
    path = save(Image.fromarray(GREY), tmp_path / "grey.png")
    with pytest.raises(ParameterError, match="threshold"):
        load_map(path, threshold=threshold)
    with pytest.raises(ParameterError, match="threshold"):
        map_from_array(GREY, threshold=threshold)


@pytest.mark.parametrize("max_pixels", [0, -5, 1.5, True])
def test_max_pixels_must_be_positive_integer(tmp_path, max_pixels):
    path = save(Image.fromarray(GREY), tmp_path / "grey.png")
    with pytest.raises(ParameterError, match="max_pixels"):
        load_map(path, max_pixels=max_pixels)


def test_nonzero_free_every_non_zero_grey_is_free(tmp_path):
    path = save(Image.fromarray(GREY), tmp_path / "grey.png")
    loaded = load_map(path, nonzero_free=True, threshold=250)
    np.testing.assert_array_equal(loaded.free, GREY > 0)


def test_nonzero_free_ignores_alpha_like_imread_grayscale(tmp_path):
    rgba = np.full((1, 3, 4), 255, np.uint8)
    rgba[0, 1, 3] = 0  # transparent white: free for the released driver, obstacle by default
    rgba[0, 2, :3] = 0
    rgba[0, 2, 3] = 255
    path = save(Image.fromarray(rgba, "RGBA"), tmp_path / "sketch.png")
    np.testing.assert_array_equal(load_map(path, nonzero_free=True).free, [[True, True, False]])
    np.testing.assert_array_equal(load_map(path).free, [[True, False, False]])


def test_nonzero_free_uses_libpng_truncated_luma():
    # libpng: (9797 R + 19234 G + 3737 B) >> 15, so a faint red (2, 0, 0) is 0 but (4, 0, 0) is 1,
    # where the rounded OpenCV luma makes both non-zero.
    rgb = np.array([[[2, 0, 0], [4, 0, 0], [255, 255, 255]]], np.uint8)
    np.testing.assert_array_equal(map_from_array(rgb, nonzero_free=True).image, [[0, 1, 255]])
    np.testing.assert_array_equal(map_from_array(rgb, threshold=0).image, [[1, 1, 255]])


def test_nonzero_free_16_bit_keeps_high_byte(tmp_path):
    words = np.array([[255, 256, 65535]], np.uint16)
    path = save(Image.fromarray(words), tmp_path / "faint.png")
    np.testing.assert_array_equal(load_map(path, nonzero_free=True).free, [[False, True, True]])
    # The default rounding scales 255 to 1, which is non-zero.
    np.testing.assert_array_equal(load_map(path, threshold=0).free, [[True, True, True]])


def test_nonzero_free_matches_opencv_imread_grayscale(tmp_path):
    rng = np.random.default_rng(7)
    rgba = rng.integers(0, 256, size=(40, 50, 4), dtype=np.uint8)
    rgba[:10, :10, :3] = rng.integers(0, 4, size=(10, 10, 3))  # near-black colours
    rgba[10:20, :10, :3] = 0
    words = rng.integers(0, 65536, size=(20, 30), dtype=np.uint16)
    words[:5, :5] = rng.integers(0, 600, size=(5, 5))
    palette_image = Image.fromarray(rng.integers(0, 8, size=(12, 9), dtype=np.uint8), "P")
    palette_image.putpalette(rng.integers(0, 4, size=24).tolist())
    paths = [
        save(Image.fromarray(rgba, "RGBA"), tmp_path / "rgba.png"),
        save(Image.fromarray(words), tmp_path / "words.png"),
        save(palette_image, tmp_path / "palette.png", transparency=1),
        save(Image.fromarray(rgba[..., :2].copy(), "LA"), tmp_path / "la.png"),
    ]
    for path in paths:
        reference = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        loaded = load_map(path, nonzero_free=True)
        np.testing.assert_array_equal(loaded.image, reference, err_msg=path.name)
        np.testing.assert_array_equal(loaded.free, reference > 0, err_msg=path.name)


# ---------------------------------------------------------------------------------------------
# Errors on image files


def test_missing_file(tmp_path):
    with pytest.raises(MapError, match="file not found") as caught:
        load_map(tmp_path / "nowhere.png")
    assert "nowhere.png" in str(caught.value)


def test_directory(tmp_path):
    folder = tmp_path / "maps.png"
    folder.mkdir()
    with pytest.raises(MapError, match="is a directory") as caught:
        load_map(folder)
    assert "maps.png" in str(caught.value)


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


def test_no_free_pixel(tmp_path):
    path = save(Image.fromarray(np.full((4, 4), 200, np.uint8)), tmp_path / "dark.png")
    with pytest.raises(MapError, match="no free pixel") as caught:
        load_map(path)
    message = str(caught.value)
    assert "dark.png" in message and "threshold 250" in message and "brightest is 200" in message


def test_no_free_pixel_all_transparent(tmp_path):
    rgba = np.zeros((3, 3, 4), np.uint8)
    rgba[..., :3] = 255
    path = save(Image.fromarray(rgba, "RGBA"), tmp_path / "ghost.png")
    with pytest.raises(MapError, match="every pixel is transparent") as caught:
        load_map(path)
    assert "ghost.png" in str(caught.value)


def test_no_free_pixel_nonzero_free(tmp_path):
    path = save(Image.fromarray(np.zeros((3, 3), np.uint8)), tmp_path / "black.png")
    with pytest.raises(MapError, match="every pixel is black") as caught:
        load_map(path, nonzero_free=True)
    assert "black.png" in str(caught.value)


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


# ---------------------------------------------------------------------------------------------
# ROS map_server YAML


def write_ros_map(
    folder: Path, pixels: np.ndarray, yaml_text: str, *, image_name: str = "map.png", yaml_name: str = "map.yaml"
) -> Path:
    image_path = folder / image_name
    image_path.parent.mkdir(parents=True, exist_ok=True)
    mode = "LA" if pixels.ndim == 3 and pixels.shape[2] == 2 else None
    Image.fromarray(pixels, mode).save(image_path)
    yaml_path = folder / yaml_name
    yaml_path.write_text(yaml_text)
    return yaml_path


# Occupancy = 1 - p / 255: 0 -> 1.0, 89 -> 0.651, 90 -> 0.647, 100 -> 0.608, 205 -> 0.19608,
# 254 -> 0.0039, 255 -> 0.0.
ROS_GREY = np.array([[0, 89, 90, 100], [205, 254, 255, 255]], np.uint8)


def test_ros_yaml_trinary(tmp_path):
    yaml_path = write_ros_map(
        tmp_path,
        ROS_GREY,
        "image: map.png\nresolution: 0.05\norigin: [-1.5, 2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    loaded = load_map(yaml_path)
    occupied, free, unknown = OCCUPANCY_OCCUPIED, OCCUPANCY_FREE, OCCUPANCY_UNKNOWN
    np.testing.assert_array_equal(
        loaded.occupancy, [[occupied, occupied, unknown, unknown], [unknown, free, free, free]]
    )
    assert loaded.occupancy.dtype == np.int8
    np.testing.assert_array_equal(loaded.free, loaded.occupancy == 0)
    np.testing.assert_array_equal(loaded.image, ROS_GREY)
    assert loaded.resolution == 0.05 and loaded.origin == (-1.5, 2.0, 0.0)
    assert loaded.path == yaml_path
    assert loaded.sha256 == hashlib.sha256((tmp_path / "map.png").read_bytes()).hexdigest()


def test_ros_yaml_negate(tmp_path):
    # Negated: occ = p / 255, so black is free and white occupied; 89 -> 0.349 and
    # 100 -> 0.392 lie between the default thresholds 0.25 and 0.65, 205 -> 0.804 is occupied.
    yaml_path = write_ros_map(tmp_path, ROS_GREY, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 1\n")
    loaded = load_map(yaml_path)
    np.testing.assert_array_equal(loaded.occupancy, [[0, -1, -1, -1], [100, 100, 100, 100]])


def test_ros_yaml_defaults(tmp_path):
    # Defaults negate 0, occupied 0.65, free 0.25: 205 (occ 0.196) is free, 100 (0.608) unknown.
    yaml_path = write_ros_map(tmp_path, ROS_GREY, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\n")
    loaded = load_map(yaml_path)
    np.testing.assert_array_equal(loaded.occupancy, [[100, 100, -1, -1], [0, 0, 0, 0]])


def test_ros_yaml_scale_mode(tmp_path):
    # 150: occ 0.41176 -> (0.41176 - 0.25) / 0.4 * 100 = 40.4 -> 40; 166: occ 0.349 -> 24.8 -> 25.
    # 191: occ 0.25098 -> 0.2 -> would round to 0, kept at 1 so that 0 keeps meaning free.
    grey = np.array([[150, 166, 191, 0, 255]], np.uint8)
    yaml_path = write_ros_map(tmp_path, grey, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nmode: scale\n")
    np.testing.assert_array_equal(load_map(yaml_path).occupancy, [[40, 25, 1, 100, 0]])


def test_ros_yaml_scale_mode_not_opaque_is_unknown(tmp_path):
    pixels = np.zeros((1, 3, 2), np.uint8)
    pixels[..., 0] = 255
    pixels[..., 1] = [255, 254, 0]
    yaml_path = write_ros_map(tmp_path, pixels, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nmode: scale\n")
    np.testing.assert_array_equal(load_map(yaml_path).occupancy, [[0, -1, -1]])


def test_ros_yaml_trinary_averages_alpha_in(tmp_path):
    # nav2 averages (R, G, B, alpha) in trinary mode: white with alpha 0 -> shade 0.75 ->
    # occ 0.25, not below free_thresh 0.25, so unknown; black transparent -> occupied.
    pixels = np.array([[[255, 255], [255, 0], [0, 0], [255, 128]]], np.uint8)
    yaml_path = write_ros_map(tmp_path, pixels, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\n")
    loaded = load_map(yaml_path)
    # (3 * 255 + 128) / 4 / 255 = 0.8755 -> occ 0.1245 -> free
    np.testing.assert_array_equal(loaded.occupancy, [[0, -1, 100, 0]])
    # The display image shows transparent pixels as 0 whatever the occupancy.
    np.testing.assert_array_equal(loaded.image, [[255, 0, 0, 255]])


def test_ros_yaml_raw_mode(tmp_path):
    grey = np.array([[0, 50, 100, 101, 255]], np.uint8)
    yaml_path = write_ros_map(
        tmp_path, grey, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nmode: raw\nnegate: 1\n"
    )
    loaded = load_map(yaml_path)
    np.testing.assert_array_equal(loaded.occupancy, [[0, 50, 100, -1, -1]])
    np.testing.assert_array_equal(loaded.free, [[True, False, False, False, False]])


def test_ros_yaml_16_bit_image(tmp_path):
    # A 16-bit pixel of 257 * p has exactly the shade of the 8-bit pixel p.
    words = (ROS_GREY.astype(np.uint16) * 257).astype(np.uint16)
    yaml_path = write_ros_map(
        tmp_path, words, "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nfree_thresh: 0.196\n"
    )
    np.testing.assert_array_equal(load_map(yaml_path).occupancy, [[100, 100, -1, -1], [-1, 0, 0, 0]])


def test_ros_yaml_relative_image_path_and_yml_suffix(tmp_path):
    yaml_path = write_ros_map(
        tmp_path,
        ROS_GREY,
        "image: images/floor.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n",
        image_name="images/floor.pgm",
        yaml_name="floor.yml",
    )
    loaded = load_map(yaml_path)
    assert loaded.shape == ROS_GREY.shape and loaded.name == "floor"


def test_ros_yaml_absolute_image_path(tmp_path):
    image_path = tmp_path / "elsewhere" / "floor.png"
    (tmp_path / "conf").mkdir()
    yaml_path = write_ros_map(
        tmp_path,
        ROS_GREY,
        f"image: {image_path}\nresolution: 0.1\norigin: [0, 0, 0]\n",
        image_name="elsewhere/floor.png",
        yaml_name="conf/floor.yaml",
    )
    assert load_map(yaml_path).shape == ROS_GREY.shape


def test_ros_yaml_row_zero_is_top_and_world_frame(tmp_path):
    grey = np.zeros((4, 5), np.uint8)
    grey[3, 0] = 255  # lower-left pixel free
    yaml_path = write_ros_map(tmp_path, grey, "image: map.png\nresolution: 0.5\norigin: [10.0, 20.0, 0.0]\n")
    loaded = load_map(yaml_path)
    assert loaded.free[3, 0] and loaded.free.sum() == 1
    # The lower-left pixel's centre is half a cell from the origin along x and y.
    assert pixel_to_world(loaded, 3, 0) == (10.25, 20.25)


ROS_VALID = {"image": "map.png", "resolution": "0.05", "origin": "[0.0, 0.0, 0.0]"}


def ros_yaml_text(**overrides) -> str:
    keys = {**ROS_VALID, **overrides}
    return "".join(f"{key}: {value}\n" for key, value in keys.items() if value is not None)


@pytest.mark.parametrize(
    ("yaml_text", "field", "problem"),
    [
        (ros_yaml_text(image=None), "image", "missing required key 'image'"),
        (ros_yaml_text(resolution=None), "resolution", "missing required key 'resolution'"),
        (ros_yaml_text(origin=None), "origin", "missing required key 'origin'"),
        (ros_yaml_text(image="''"), "image", "non-empty file path"),
        (ros_yaml_text(image="[a, b]"), "image", "non-empty file path"),
        (ros_yaml_text(resolution="-0.05"), "resolution", "positive number"),
        (ros_yaml_text(resolution="0"), "resolution", "positive number"),
        (ros_yaml_text(resolution="'0.05'"), "resolution", "positive number"),
        (ros_yaml_text(resolution="true"), "resolution", "positive number"),
        (ros_yaml_text(origin="[0.0, 0.0]"), "origin", "3 finite numbers"),
        (ros_yaml_text(origin="[0.0, 0.0, a]"), "origin", "3 finite numbers"),
        (ros_yaml_text(origin="[0.0, .nan, 0.0]"), "origin", "3 finite numbers"),
        (ros_yaml_text(origin="5"), "origin", "3 finite numbers"),
        (ros_yaml_text(occupied_thresh="1.5"), "occupied_thresh", r"in \[0, 1\]"),
        (ros_yaml_text(free_thresh="-0.1"), "free_thresh", r"in \[0, 1\]"),
        (ros_yaml_text(free_thresh="high"), "free_thresh", r"in \[0, 1\]"),
        (ros_yaml_text(free_thresh="0.7"), "free_thresh", "below occupied_thresh"),
        (ros_yaml_text(free_thresh="0.65"), "free_thresh", "below occupied_thresh"),
        (ros_yaml_text(negate="2"), "negate", "0 or 1"),
        (ros_yaml_text(mode="Trinary"), "mode", "one of trinary, scale, raw"),
        (ros_yaml_text(mode="bogus"), "mode", "one of trinary, scale, raw"),
        (ros_yaml_text(image="missing.png"), "image", "image file not found"),
        (ros_yaml_text(image="notes.png"), "image", "not an image"),
        (ros_yaml_text(image="dark.png"), None, "no free cell in dark.png"),
    ],
)
def test_ros_yaml_errors_name_file_and_field(tmp_path, yaml_text, field, problem):
    Image.fromarray(ROS_GREY).save(tmp_path / "map.png")
    Image.fromarray(np.zeros((3, 3), np.uint8)).save(tmp_path / "dark.png")
    (tmp_path / "notes.png").write_text("not a picture")
    yaml_path = tmp_path / "site.yaml"
    yaml_path.write_text(yaml_text)
    with pytest.raises(MapError, match=problem) as caught:
        load_map(yaml_path)
    message = str(caught.value)
    assert str(yaml_path) in message
    if field is not None:
        assert caught.value.field == field and f"field '{field}'" in message


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        ("image: [unclosed\n", "not valid YAML"),
        ("- image\n- resolution\n", "not a ROS map_server YAML file"),
        ("just a sentence\n", "not a ROS map_server YAML file"),
        ("", "empty file"),
    ],
)
def test_ros_yaml_not_a_map_document(tmp_path, content, problem):
    yaml_path = tmp_path / "broken.yaml"
    yaml_path.write_text(content)
    with pytest.raises(MapError, match=problem) as caught:
        load_map(yaml_path)
    assert "broken.yaml" in str(caught.value)


def test_ros_yaml_missing_file(tmp_path):
    with pytest.raises(MapError, match="file not found") as caught:
        load_map(tmp_path / "gone.yaml")
    assert "gone.yaml" in str(caught.value)


def test_ros_yaml_image_over_pixel_limit(tmp_path):
    yaml_path = write_ros_map(tmp_path, ROS_GREY, ros_yaml_text())
    with pytest.raises(MapError, match="max_pixels=4") as caught:
        load_map(yaml_path, max_pixels=4)
    assert caught.value.field == "image" and "map.yaml" in str(caught.value) and "map.png" in str(caught.value)


# ---------------------------------------------------------------------------------------------
# map_from_array


def test_map_from_bool_array_is_used_directly_and_copied():
    mask = np.array([[True, False], [False, True]])
    loaded = map_from_array(mask, threshold=255)
    mask[0, 0] = False
    np.testing.assert_array_equal(loaded.free, [[True, False], [False, True]])
    np.testing.assert_array_equal(loaded.image, [[255, 0], [0, 255]])
    assert loaded.path is None and loaded.sha256 is None and loaded.name == "map"


def test_map_from_uint8_and_uint16_agree():
    words = GREY.astype(np.uint16) * 257
    np.testing.assert_array_equal(map_from_array(words).free, GREY_FREE)
    np.testing.assert_array_equal(map_from_array(words).image, GREY)


def test_map_from_array_channel_layouts():
    np.testing.assert_array_equal(map_from_array(GREY[..., None]).free, GREY_FREE)
    alpha = np.full(GREY.shape, 255, np.uint8)
    alpha[1, 0] = 0
    expected = GREY_FREE.copy()
    expected[1, 0] = False
    np.testing.assert_array_equal(map_from_array(np.dstack([GREY, alpha])).free, expected)
    rgb = np.dstack([GREY, GREY, GREY])
    np.testing.assert_array_equal(map_from_array(rgb).free, GREY_FREE)
    np.testing.assert_array_equal(map_from_array(np.dstack([rgb, alpha])).free, expected)


def test_map_from_array_small_int64_values_read_as_8_bit():
    np.testing.assert_array_equal(map_from_array(GREY.astype(np.int64)).free, GREY_FREE)


def test_map_from_array_records_path():
    assert map_from_array(GREY, path="sketch.png").path == Path("sketch.png")


@pytest.mark.parametrize(
    ("array", "problem"),
    [
        (np.array([[0, 300]], np.int64), "outside 0..255"),
        (np.array([[0.0, 1.0]]), "unsupported array dtype"),
        (np.zeros((2, 2, 5), np.uint8), "1, 2, 3 or 4 channels"),
        (np.zeros((2, 2, 3, 1), np.uint8), "must be"),
        (np.zeros(4, np.uint8), "not 2-D"),
        (np.zeros((0, 3), np.uint8), "zero-size"),
        (np.zeros((2, 2), bool), "all False"),
        (np.zeros((2, 2), np.uint8), "no free pixel"),
    ],
)
def test_map_from_array_errors(array, problem):
    with pytest.raises(MapError, match=problem) as caught:
        map_from_array(array, path="canvas.png")
    assert "canvas.png" in str(caught.value)


# ---------------------------------------------------------------------------------------------
# Pixel <-> world


def georeferenced(rows=10, cols=20, resolution=0.5, origin=(1.0, 2.0, 0.0)) -> Map:
    return Map(free=np.ones((rows, cols), bool), resolution=resolution, origin=origin)


def test_pixel_to_world_known_answers_without_yaw():
    grid = georeferenced()
    assert pixel_to_world(grid, 9, 0) == (1.25, 2.25)
    assert pixel_to_world(grid, 0, 0) == (1.25, 2.0 + 9.5 * 0.5)
    assert pixel_to_world(grid, 9, 19) == (1.0 + 19.5 * 0.5, 2.25)
    # The lower-left corner of the lower-left pixel is the origin.
    assert pixel_to_world(grid, 9.5, -0.5) == (1.0, 2.0)


def test_pixel_to_world_with_quarter_turn():
    grid = georeferenced(origin=(1.0, 2.0, math.pi / 2))
    # Map-frame centre (0.25, 0.25) turned by +90 degrees is (-0.25, 0.25).
    x, y = pixel_to_world(grid, 9, 0)
    assert x == pytest.approx(0.75) and y == pytest.approx(2.25)
    # Map-frame (10.25, 0.25) turns to (-0.25, 10.25).
    x, y = pixel_to_world(grid, 9, 20)
    assert x == pytest.approx(0.75) and y == pytest.approx(12.25)


@pytest.mark.parametrize("yaw", [0.0, 0.3, -2.0, math.pi])
def test_pixel_world_round_trip(yaw):
    grid = georeferenced(rows=37, cols=53, resolution=0.05, origin=(-12.5, 3.25, yaw))
    rng = np.random.default_rng(11)
    rows = rng.uniform(-5, 42, size=200)
    cols = rng.uniform(-5, 58, size=200)
    x, y = pixel_to_world(grid, rows, cols)
    back_rows, back_cols = world_to_pixel(grid, x, y)
    np.testing.assert_allclose(back_rows, rows, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back_cols, cols, rtol=0, atol=1e-9)
    # The rotation keeps distances: neighbouring pixel centres are one resolution apart.
    x0, y0 = pixel_to_world(grid, 4, 4)
    x1, y1 = pixel_to_world(grid, 4, 5)
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(0.05)


def test_world_to_pixel_scalars_and_broadcasting():
    grid = georeferenced()
    rows, cols = world_to_pixel(grid, 1.25, 2.25)
    assert (rows, cols) == (9.0, 0.0) and isinstance(rows, float)
    rows, cols = pixel_to_world(grid, np.arange(3)[:, None], np.arange(4)[None, :])
    assert rows.shape == (3, 4) and cols.shape == (3, 4)


def test_missing_origin_means_zero_pose():
    grid = Map(free=np.ones((2, 2), bool), resolution=1.0)
    assert pixel_to_world(grid, 1, 0) == (0.5, 0.5)


def test_geometry_needs_a_resolution(tmp_path):
    plain = map_from_array(GREY, path=tmp_path / "sketch.png")
    with pytest.raises(ParameterError, match="no resolution") as caught:
        pixel_to_world(plain, 0, 0)
    assert "sketch.png" in str(caught.value)
    with pytest.raises(ParameterError, match="no resolution"):
        world_to_pixel(plain, 0.0, 0.0)


# ---------------------------------------------------------------------------------------------
# Module hygiene


def test_import_does_not_load_pillow_or_yaml():
    code = "import sys, ursim_core.io.maps; print('PIL' in sys.modules, 'yaml' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.split() == ["False", "False"]


# ---------------------------------------------------------------------------------------------
# Research datasets

DATASET_FOLDERS = ("ursim_kth_sketches", "maoris_segmentation", "ursim_halmstad_robot_maps")
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm"}


def dataset_images(root: Path) -> list[Path]:
    images = []
    for folder in DATASET_FOLDERS:
        for path in sorted((root / folder).rglob("*")):
            # maoris_output holds MAORIS label images (0 = wall, 1..N region ids), not maps.
            if path.suffix.lower() in IMAGE_SUFFIXES and "maoris_output" not in path.parts:
                images.append(path)
    return images


@pytest.mark.dataset
def test_every_dataset_map_loads_with_free_space():
    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    images = dataset_images(root)
    assert len(images) > 100
    failures = []
    for path in images:
        try:
            loaded = load_map(path)
        except MapError as error:
            failures.append(str(error))
            continue
        if loaded.free.sum() < 1000 or loaded.sha256 != hashlib.sha256(path.read_bytes()).hexdigest():
            failures.append(f"{path}: {int(loaded.free.sum())} free pixels")
    assert failures == []


@pytest.mark.dataset
def test_nonzero_free_reproduces_released_driver_on_kth_sketches():
    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    sketches = sorted((root / "ursim_kth_sketches" / "sketches").glob("*.png"))
    assert sketches
    for path in sketches:
        loaded = load_map(path, nonzero_free=True)
        driver_free = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) > 0
        np.testing.assert_array_equal(loaded.free, driver_free, err_msg=path.name)
        # Ignoring alpha is harmless on this data: no transparent pixel is free.
        rgba = np.asarray(Image.open(path).convert("RGBA"))
        assert not (loaded.free & (rgba[..., 3] < 128)).any(), path.name
