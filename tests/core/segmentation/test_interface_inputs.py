"""segment() takes a Map or a bool mask: a grey image or a path is refused with a clear error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ursim_core.errors import ParameterError
from ursim_core.io import map_from_array
from ursim_core.segmentation import segment, segment_canonical
from ursim_core.segmentation.interface import with_resamplings


def two_rooms_grey():
    """Two rooms joined by a door: free 255, walls 0, and a grey 100 smudge (not free for the loader)."""
    grey = np.zeros((60, 130), np.uint8)
    grey[5:55, 5:60] = 255
    grey[5:55, 70:125] = 255
    grey[27:33, 60:70] = 255
    grey[20:40, 62:68] = 100  # beside the door: a pencil mark, an obstacle when loaded
    return grey


@pytest.mark.parametrize("dtype", [np.uint8, np.int64, np.float64])
def test_a_non_bool_array_is_a_parameter_error_naming_map_from_array(dtype):
    with pytest.raises(ParameterError, match=r"got an array of .*ursim_core\.io\.map_from_array"):
        segment(two_rooms_grey().astype(dtype), preset="default")


def test_a_grey_image_made_a_map_is_segmented_with_the_loaders_rule():
    grey = two_rooms_grey()
    the_map = map_from_array(grey)
    assert np.array_equal(the_map.free, grey > 250)
    assert np.array_equal(segment(the_map, preset="default").labels, segment(grey > 250, preset="default").labels)


@pytest.mark.parametrize("path", ["x.png", Path("maps") / "x.png"])
def test_a_path_is_a_parameter_error_saying_what_to_pass(path):
    with pytest.raises(ParameterError, match=r"pass a Map \(ursim_core\.io\.load_map\(path\)\) or a bool array"):
        segment(path)


def test_the_canonical_and_resampled_segmentations_refuse_grey_images_too():
    grey = two_rooms_grey()
    with pytest.raises(ParameterError, match="map_from_array"):
        segment_canonical(grey, preset="default")
    base = segment_canonical(grey > 250, preset="default")
    with pytest.raises(ParameterError, match="map_from_array"):
        with_resamplings(base, grey, method="maoris", params=base.params)
