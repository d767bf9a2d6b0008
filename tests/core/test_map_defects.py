"""Issue 12, map images and ROS YAML: each defect the reliability pass found, reproduced.

Items: 6 (named pipes, non-regular files), 7 (bounded reads), 8 (YAML bombs), 9 (deep YAML),
10 (huge YAML numbers), 12 (one-line messages), 14 (transparent palette white, symlink loops).
Every failure is one :class:`MapError` whose one-line message names the file.
"""

from __future__ import annotations

import io
import os
import struct
import sys
import threading
import tracemalloc
import warnings
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ursim_core.errors import MapError
from ursim_core.io import load_map

posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX special files")


def _png(folder: Path, name: str = "room.png") -> Path:
    grey = np.zeros((8, 8), np.uint8)
    grey[2:6, 2:6] = 255
    path = folder / name
    Image.fromarray(grey).save(path)
    return path


def _yaml(folder: Path, text: str, name: str = "map.yaml") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _png_header(width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` grey pixels (no pixel data follows)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b"")


VALID_YAML = "image: room.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"


def _refused(path: Path, match: str | None = None) -> str:
    with pytest.raises(MapError) as caught:
        load_map(path)
    message = str(caught.value)
    assert "\n" not in message, message
    assert len(message) < 400, message
    assert str(path) in message, message
    if match is not None:
        assert match in message, message
    return message


# --------------------------------------------------------------------------- 6, 7: what is read


@posix_only
@pytest.mark.parametrize("name", ["pipe.png", "pipe.yaml"])
def test_named_pipe_as_a_map_is_refused_without_blocking(tmp_path, name):
    pipe = tmp_path / name
    os.mkfifo(pipe)
    result = {}
    worker = threading.Thread(target=lambda: result.setdefault("message", _refused(pipe, "named pipe")), daemon=True)
    worker.start()
    worker.join(10)
    if worker.is_alive():
        with open(pipe, "wb"):  # unblock the reader so the test process can end
            pass
        pytest.fail("load_map blocked on a named pipe")
    assert "message" in result


@posix_only
def test_named_pipe_as_a_yaml_image_is_refused(tmp_path):
    os.mkfifo(tmp_path / "room.png")
    message = _refused(_yaml(tmp_path, VALID_YAML), "named pipe")
    assert "image" in message


@posix_only
def test_device_is_refused(tmp_path):
    link = tmp_path / "zero.png"
    link.symlink_to("/dev/zero")
    _refused(link, "not a regular file")


def test_sparse_file_is_refused_from_its_size_and_header(tmp_path):
    big = tmp_path / "huge.png"
    with open(big, "wb") as handle:
        handle.truncate(3 * 1024**3)
    tracemalloc.start()
    try:
        message = _refused(big)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 1024**2, peak
    assert "max_pixels" in message or "not an image" in message


def test_real_header_with_a_huge_tail_is_refused_before_reading_it(tmp_path):
    path = _png(tmp_path)
    with open(path, "ab") as handle:
        handle.truncate(2 * 1024**3)
    tracemalloc.start()
    try:
        _refused(path, "bytes")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 1024**2, peak


def test_huge_yaml_is_refused_from_its_size(tmp_path):
    path = tmp_path / "map.yaml"
    with open(path, "wb") as handle:
        handle.write(VALID_YAML.encode())
        handle.truncate(200 * 1024**2)
    _refused(path, "bytes")


# --------------------------------------------------------------------------- 8, 9: YAML structure


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


# --------------------------------------------------------------------------- 10: numbers


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


def test_nul_in_the_yaml_image_is_a_map_error(tmp_path):
    _refused(_yaml(tmp_path, 'image: "room\\0.png"\nresolution: 0.05\norigin: [0, 0, 0]\n'), "image")


# --------------------------------------------------------------------------- 12: one line


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


# --------------------------------------------------------------------------- 14: say so


def test_palette_png_with_a_transparent_white_says_so(tmp_path):
    image = Image.new("P", (6, 6), 0)
    image.putpalette([0, 0, 0, 255, 255, 255] + [0] * 762)
    image.paste(1, (1, 1, 5, 5))
    path = tmp_path / "palette.png"
    image.save(path, transparency=1)
    assert "transparent" in _refused(path)


@posix_only
def test_symlink_loop_in_yaml_image_says_so(tmp_path):
    (tmp_path / "loop.png").symlink_to(tmp_path / "loop.png")
    message = _refused(_yaml(tmp_path, VALID_YAML.replace("room.png", "loop.png")))
    assert "symbolic link loop" in message and "not found" not in message


@posix_only
def test_dangling_symlink_says_so(tmp_path):
    (tmp_path / "gone.png").symlink_to(tmp_path / "nowhere.png")
    assert "nowhere.png" in _refused(tmp_path / "gone.png")


def test_nul_at_the_start_of_a_yaml_file_is_a_map_error(tmp_path):
    # Found by tests/fuzz: PyYAML's reader refuses it while the loader is being made.
    path = tmp_path / "map.yaml"
    path.write_bytes(b"\x00image: room.png\n")
    _refused(path, "YAML")
