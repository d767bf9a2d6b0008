"""Label-image files (ursim_core.segmentation.label_files): ids kept as stored, errors name the file."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from ursim_core.errors import SegmentationError
from ursim_core.segmentation import Segmentation, load_label_image, read_label_array, save_label_image
from ursim_core.segmentation.regions import region_table


def _segmentation(labels) -> Segmentation:
    labels = np.asarray(labels, np.int32)
    return Segmentation(labels=labels, regions=region_table(labels), method="label-image", params={})


def test_a_saved_label_image_loads_with_the_same_ids(tmp_path: Path):
    # Ids above 255 and with gaps: a correspondence file names them, so they stay as they are.
    labels = np.array([[0, 700, 700, 3], [0, 0, 3, 3], [9, 9, 0, 700]], np.int32)
    path = tmp_path / "rooms-labels.png"
    save_label_image(_segmentation(labels), path)
    assert cv2.imread(str(path), cv2.IMREAD_UNCHANGED).dtype == np.uint16
    loaded = load_label_image(path, shape=labels.shape)
    assert loaded.labels.dtype == np.int32 and np.array_equal(loaded.labels, labels)
    assert loaded.method == "label-image" and loaded.source == path
    assert sorted(loaded.graph.nodes) == [3, 9, 700]
    assert [p.name for p in tmp_path.iterdir()] == ["rooms-labels.png"]  # no temporary file left


def test_eight_bit_and_equal_channel_images_are_read(tmp_path: Path):
    grey = tmp_path / "grey.png"
    cv2.imwrite(str(grey), np.array([[0, 5], [5, 2]], np.uint8))
    assert read_label_array(grey).tolist() == [[0, 5], [5, 2]]
    colour = tmp_path / "colour.png"
    cv2.imwrite(str(colour), np.dstack([np.array([[0, 4], [4, 1]], np.uint8)] * 3))
    assert read_label_array(colour).tolist() == [[0, 4], [4, 1]]


@pytest.mark.parametrize(
    ("write", "message"),
    [
        (None, "label image not found"),
        (lambda path: path.write_bytes(b"not a png"), "not a readable image"),
        (
            lambda path: cv2.imwrite(
                str(path), np.dstack([np.ones((2, 2), np.uint8), np.zeros((2, 2), np.uint8)] * 2)[..., :3]
            ),
            "got colour",
        ),
        (lambda path: cv2.imwrite(str(path), np.ones((2, 2), np.float32)), "must be 8 or 16 bit"),
    ],
)
def test_a_bad_label_image_is_refused_naming_the_file(tmp_path: Path, write, message):
    path = tmp_path / ("labels.tiff" if message == "must be 8 or 16 bit" else "labels.png")
    if write is not None:
        write(path)
    with pytest.raises(SegmentationError, match=message) as raised:
        read_label_array(path)
    assert path.name in str(raised.value)


def test_a_label_image_of_another_size_than_the_map_is_refused(tmp_path: Path):
    path = tmp_path / "labels.png"
    save_label_image(_segmentation([[1, 1, 2]]), path)
    with pytest.raises(SegmentationError, match=r"label image is 1x3 \(rows x cols\) but the map is 2x3") as raised:
        load_label_image(path, shape=(2, 3))
    assert "labels.png" in str(raised.value)


def test_more_ids_than_sixteen_bits_hold_are_refused_and_nothing_is_written(tmp_path: Path):
    path = tmp_path / "labels.png"
    with pytest.raises(SegmentationError, match="70000 regions do not fit a 16-bit label image"):
        save_label_image(_segmentation([[1, 70000]]), path)
    assert not list(tmp_path.iterdir())
