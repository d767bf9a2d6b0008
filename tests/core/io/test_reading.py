"""Bounded reads of regular files (ursim_core.io.reading): missing files, folders, pipes, devices, huge files, links."""

from __future__ import annotations

import os
import sys
import threading
import tracemalloc
from pathlib import Path

import pytest
from io_helpers import VALID_YAML, _png, _refused, _yaml

from ursim_core.errors import MapError
from ursim_core.io.maps import load_map

posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX special files")

# ---------------------------------------------------------------------------------------------
# Missing files and folders


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


# --------------------------------------------------------------------------- issue 12, items 6 and 7: what is read


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


# --------------------------------------------------------------------------- issue 12, item 14: symbolic links


@posix_only
def test_symlink_loop_in_yaml_image_says_so(tmp_path):
    (tmp_path / "loop.png").symlink_to(tmp_path / "loop.png")
    message = _refused(_yaml(tmp_path, VALID_YAML.replace("room.png", "loop.png")))
    assert "symbolic link loop" in message and "not found" not in message


@posix_only
def test_dangling_symlink_says_so(tmp_path):
    (tmp_path / "gone.png").symlink_to(tmp_path / "nowhere.png")
    assert "nowhere.png" in _refused(tmp_path / "gone.png")


def test_a_missing_file_is_also_a_file_not_found_error_for_every_loader(tmp_path):
    # ``except FileNotFoundError`` (what a Python caller writes) missed the loaders' errors; each
    # stays its own kind too (MapError, FormatError, SegmentationError), naming the file.
    from ursim_core.correspondences import load_correspondences, load_dat
    from ursim_core.errors import FormatError, MapError, SegmentationError
    from ursim_core.io import load_map
    from ursim_core.segmentation import load_label_image

    (tmp_path / "map.yaml").write_text("image: gone.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    cases = [
        (load_map, tmp_path / "gone.png", MapError, tmp_path / "gone.png"),
        (load_map, tmp_path / "map.yaml", MapError, tmp_path / "gone.pgm"),
        (load_correspondences, tmp_path / "gone.json", FormatError, tmp_path / "gone.json"),
        (load_dat, tmp_path / "gone.dat", FormatError, tmp_path / "gone.dat"),
        (load_label_image, tmp_path / "gone.labels.png", SegmentationError, tmp_path / "gone.labels.png"),
    ]
    for loader, path, kind, missing in cases:
        with pytest.raises(FileNotFoundError) as raised:
            loader(path)
        assert isinstance(raised.value, kind) and raised.value.path == path
        assert Path(raised.value.filename) == missing and "\n" not in str(raised.value)


def test_a_yaml_whose_image_is_a_dangling_link_names_the_image_as_missing(tmp_path):
    from ursim_core.io import load_map

    (tmp_path / "map.pgm").symlink_to(tmp_path / "gone.pgm")
    (tmp_path / "map.yaml").write_text("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(FileNotFoundError, match="dangling symbolic link") as raised:
        load_map(tmp_path / "map.yaml")
    assert raised.value.path == tmp_path / "map.yaml" and Path(raised.value.filename) == tmp_path / "map.pgm"
