"""The Map value and its loaders (ursim_core.io.maps): thresholds, nonzero_free, map_from_array, pixel <-> world."""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from io_helpers import GREY, GREY_FREE, _refused, save
from PIL import Image

from ursim_core.errors import MapError, ParameterError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.io.maps import Map, load_map, map_from_array, pixel_to_world, world_to_pixel


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


def test_the_parameter_checks_are_public_and_name_a_command_line_option():
    # One rule for the loader and the command line (ursim_core.cli.common.check_map_options).
    from ursim_core.io import maps

    assert {"check_threshold", "check_max_pixels"} <= set(maps.__all__)
    maps.check_threshold(0)
    maps.check_threshold(255.0)
    maps.check_max_pixels(1)
    with pytest.raises(ParameterError) as caught:
        maps.check_threshold(256)
    # The field names the parameter once: not "field 'threshold': threshold must be ...".
    assert str(caught.value) == "field 'threshold': must be a number in 0..255, got 256"
    with pytest.raises(ParameterError) as caught:
        maps.check_threshold(256, option="--threshold")
    assert str(caught.value) == "--threshold must be a number in 0..255, got 256" and caught.value.field is None
    with pytest.raises(ParameterError) as caught:
        maps.check_max_pixels(0, option="--max-pixels")
    assert str(caught.value) == "--max-pixels must be a positive integer, got 0"


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
# No free pixel


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


# --------------------------------------------------------------------------- issue 12, item 14: say so


def test_palette_png_with_a_transparent_white_says_so(tmp_path):
    image = Image.new("P", (6, 6), 0)
    image.putpalette([0, 0, 0, 255, 255, 255] + [0] * 762)
    image.paste(1, (1, 1, 5, 5))
    path = tmp_path / "palette.png"
    image.save(path, transparency=1)
    assert "transparent" in _refused(path)


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


def test_a_maps_repr_is_one_short_line():
    free = np.zeros((400, 600), bool)
    free[10:20, 10:30] = True
    text = repr(Map(free=free, resolution=0.05, origin=(1.0, 2.0, 0.0)))
    assert text == "Map(shape=(400, 600), free=200 px, resolution=0.05, origin=(1.0, 2.0, 0.0))"
