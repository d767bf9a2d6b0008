"""ROS map_server YAML maps (ursim_core.io.ros_yaml): nav2's occupancy rules, image paths, every bad file."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
from io_helpers import VALID_YAML, _png, _refused, _yaml
from PIL import Image

from ursim_core.errors import MapError
from ursim_core.io.maps import OCCUPANCY_FREE, OCCUPANCY_OCCUPIED, OCCUPANCY_UNKNOWN, load_map, pixel_to_world


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


# --------------------------------------------------------------------------- issue 12, items 8 and 9: YAML structure


def test_yaml_alias_bomb_is_refused_quickly(tmp_path):
    lines = ['a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for level in range(1, 9):
        previous = f"*a{level - 1}"
        lines.append(f"a{level}: &a{level} [{', '.join([previous] * 9)}]")
    lines.append("image: *a8\nresolution: 0.05\norigin: [0, 0, 0]")
    message = _refused(_yaml(tmp_path, "\n".join(lines) + "\n"))
    assert "alias" in message


@pytest.mark.parametrize("depth", [200, 5000])
def test_deep_yaml_is_a_map_error(tmp_path, depth):
    text = VALID_YAML + "zz: " + "[" * depth + "]" * depth + "\n"
    _refused(_yaml(tmp_path, text), "nest")


def test_long_values_are_cut_in_messages(tmp_path):
    message = _refused(_yaml(tmp_path, "image: room.png\nresolution: '" + "x" * 100_000 + "'\norigin: [0, 0, 0]\n"))
    assert "resolution" in message and "..." in message


# --------------------------------------------------------------------------- issue 12, item 10: numbers


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("image: room.png\nresolution: " + "9" * 400 + "\norigin: [0, 0, 0]\n", "resolution"),
        ("image: room.png\nresolution: 0.05\norigin: [" + "9" * 400 + ", 0, 0]\n", "origin"),
        ("image: room.png\nresolution: 0.05\norigin: [0, 0, 0]\nfree_thresh: " + "9" * 400 + "\n", "free_thresh"),
        ("image: room.png\nresolution: " + "9" * 5000 + "\norigin: [0, 0, 0]\n", None),
        ("image: room.png\nresolution: 1e400\norigin: [0, 0, 0]\n", "resolution"),
    ],
)
def test_huge_yaml_numbers_are_map_errors(tmp_path, text, field):
    _png(tmp_path)
    message = _refused(_yaml(tmp_path, text))
    if field is not None:
        assert f"field '{field}'" in message


@pytest.mark.parametrize(
    ("numbers", "field"),
    [
        # Each number finite, the far corner not: 1e306 m a pixel x 8 pixels, or past the origin.
        ("resolution: 1.0e+306\norigin: [0, 0, 0]", "resolution"),
        ("resolution: 1.0e+306\norigin: [1.7e+308, 1.7e+308, 0.0]", "origin"),
        ("resolution: 0.05\norigin: [1.0e+12, 0, 0]", "origin"),
        ("resolution: 2.0e+10\norigin: [0, 0, 0.7]", "resolution"),
    ],
)
def test_a_georeference_whose_corners_overflow_is_refused_when_loaded(tmp_path, numbers, field):
    _png(tmp_path)
    message = _refused(_yaml(tmp_path, f"image: room.png\n{numbers}\n"), "from the world origin")
    assert f"field '{field}'" in message


def test_a_georeference_far_but_within_the_bound_loads(tmp_path):
    _png(tmp_path)
    # UTM-like coordinates: millions of metres from the world's origin.
    the_map = load_map(_yaml(tmp_path, "image: room.png\nresolution: 0.05\norigin: [654321.5, 5432109.25, 1.2]\n"))
    x, y = pixel_to_world(the_map, 0, 0)
    assert abs(x - 654321.5) < 1 and abs(y - 5432109.25) < 1


def test_nul_in_the_yaml_image_is_a_map_error(tmp_path):
    _refused(_yaml(tmp_path, 'image: "room\\0.png"\nresolution: 0.05\norigin: [0, 0, 0]\n'), "image")


# --------------------------------------------------------------------------- issue 12, item 12: one line


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("image: room.png\nresolution: [0.05\norigin: [0, 0, 0]\n", "line"),
        ("image: room.png\n\tresolution: 0.05\norigin: [0, 0, 0]\n", "tab"),
        (VALID_YAML + "---\n" + VALID_YAML, "document"),
        ("image: !!python/object/apply:os.system ['true']\nresolution: 0.05\norigin: [0, 0, 0]\n", "tag"),
    ],
)
def test_yaml_errors_are_one_line(tmp_path, text, words):
    _png(tmp_path)
    assert words in _refused(_yaml(tmp_path, text)).lower()


def test_non_utf8_yaml_is_one_line(tmp_path):
    path = tmp_path / "map.yaml"
    path.write_bytes(b"image: r\xe9oom.png\nresolution: 0.05\norigin: [0, 0, 0]\n")
    assert "utf-8" in _refused(path).lower()


def test_nul_at_the_start_of_a_yaml_file_is_a_map_error(tmp_path):
    # Found by tests/fuzz: PyYAML's reader refuses it while the loader is being made.
    path = tmp_path / "map.yaml"
    path.write_bytes(b"\x00image: room.png\n")
    _refused(path, "YAML")
