"""Reading label images (ursim_core.segmentation.label_files) through the map loader's guarded
reading: a header declaring too many pixels, a cut file or a FIFO is a SegmentationError naming it."""

from __future__ import annotations

import os

import cv2
import numpy as np
import pytest
from image_files import png_header_only

from ursim_core.errors import SegmentationError
from ursim_core.segmentation import Segmentation, load_label_image, read_label_array, save_label_image
from ursim_core.segmentation.regions import region_table


def test_a_header_claiming_too_many_pixels_is_refused_before_decoding(tmp_path):
    path = png_header_only(tmp_path / "huge.png", 100_000, 100_000)
    with pytest.raises(SegmentationError, match="max_pixels") as raised:
        read_label_array(path)
    assert raised.value.path == path
    with pytest.raises(SegmentationError, match="max_pixels"):
        load_label_image(path, shape=(40, 60))


def test_the_pixel_limit_can_be_lowered(tmp_path):
    path = tmp_path / "labels.png"
    cv2.imwrite(str(path), np.ones((40, 60), np.uint16))
    assert read_label_array(path).shape == (40, 60)
    with pytest.raises(SegmentationError, match="max_pixels=100"):
        read_label_array(path, max_pixels=100)


def test_a_cut_label_image_is_refused_by_name_without_an_opencv_warning(tmp_path, capfd):
    path = tmp_path / "labels.png"
    cv2.imwrite(str(path), np.arange(40 * 60, dtype=np.uint16).reshape(40, 60))
    path.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(SegmentationError) as raised:
        read_label_array(path)
    assert raised.value.path == path and capfd.readouterr().err == ""


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_fifo_is_refused_not_waited_on(tmp_path):
    path = tmp_path / "labels.png"
    os.mkfifo(path)
    with pytest.raises(SegmentationError) as raised:
        read_label_array(path)
    assert raised.value.path == path


def test_saved_labels_read_back_exactly(tmp_path):
    labels = np.zeros((40, 60), np.int32)
    labels[2:20, 3:30], labels[20:38, 30:58] = 65535, 4
    path = tmp_path / "labels.png"
    save_label_image(Segmentation(labels=labels, regions=region_table(labels), method="x", params={}), path)
    assert np.array_equal(read_label_array(path), labels)
    grey = tmp_path / "grey.png"
    cv2.imwrite(str(grey), np.dstack([labels.astype(np.uint8)] * 3))
    assert np.array_equal(read_label_array(grey), labels.astype(np.uint8))
