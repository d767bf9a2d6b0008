"""The whole MAORIS segmentation (ursim_core.segmentation.maoris.pipeline), and the released C++'s region counts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage as ndi

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.segmentation.maoris import PRESETS, maoris_labels


def two_rooms(door: bool = True) -> np.ndarray:
    free = np.zeros((44, 90), bool)
    free[2:42, 2:42] = True
    free[2:42, 48:88] = True
    if door:
        free[19:25, 42:48] = True
    return free


# --------------------------------------------------------------------------
# Whole segmentation


def test_two_rooms_and_a_door_give_two_regions():
    free = two_rooms()
    labels = maoris_labels(free)
    assert labels.max() == 2
    assert labels[20, 20] != labels[20, 70]
    # Door pixels go to a room (except the row/column the C++ shift leaves out).
    assert set(np.unique(labels[19:24, 42:48])) <= {labels[20, 20], labels[20, 70]}
    assert labels[19:24, 42:47].all()


def test_corridor_with_side_rooms():
    free = np.zeros((110, 220), bool)
    free[48:62, 2:218] = True  # corridor
    room_cols = [(6, 66), (80, 140), (154, 214)]
    for left, right in room_cols:
        free[2:44, left:right] = True  # rooms above
        free[66:108, left:right] = True  # and below
        middle = (left + right) // 2
        free[44:48, middle - 3 : middle + 3] = True
        free[62:66, middle - 3 : middle + 3] = True
    labels = maoris_labels(free, PRESETS["robot"])
    rooms = [labels[20, (l + r) // 2] for l, r in room_cols] + [labels[90, (l + r) // 2] for l, r in room_cols]
    corridor = set(np.unique(labels[50:60, 4:216])) - {0}
    assert len(set(rooms)) == 6 and 0 not in rooms
    assert len(corridor) == 1 and corridor.isdisjoint(rooms)
    assert labels.max() == 7


def test_labels_are_consecutive_in_raster_order_and_deterministic():
    rng = np.random.default_rng(11)
    free = ndi.binary_opening(rng.random((80, 120)) < 0.75, iterations=2)
    first = maoris_labels(free, PRESETS["sketch"])
    second = maoris_labels(free.copy(), PRESETS["sketch"])
    np.testing.assert_array_equal(first, second)
    assert first.dtype == np.int32
    present = np.unique(first[first > 0])
    np.testing.assert_array_equal(present, np.arange(1, len(present) + 1))
    _, first_index = np.unique(first.ravel(), return_index=True)
    assert np.all(np.diff(first_index[1:]) > 0)  # label k appears before label k+1


def test_labels_do_not_depend_on_the_surrounding_obstacle_margin():
    free = two_rooms()
    bigger = np.zeros((80, 150), bool)
    bigger[20:64, 30:120] = free
    np.testing.assert_array_equal(maoris_labels(bigger)[20:64, 30:120], maoris_labels(free))


def test_a_map_reaching_its_border_is_labelled_alike_in_the_graphs_memory():
    # Free space up to the image's border: the window is the whole image, and the output is
    # made in the zone graph's own memory (its padding squeezed out) rather than copied.
    free = two_rooms()[1:-1, 1:-1]
    labels = maoris_labels(free)
    bigger = np.zeros((free.shape[0] + 6, free.shape[1] + 9), bool)
    bigger[3:-3, 4:-5] = free
    assert labels.flags.c_contiguous and labels.flags.writeable and labels.dtype == np.int32
    assert labels.shape == free.shape and labels.max() >= 2
    np.testing.assert_array_equal(maoris_labels(bigger)[3:-3, 4:-5], labels)


def test_empty_map_gives_no_region():
    assert not maoris_labels(np.zeros((10, 12), bool)).any()


def test_bad_input_is_rejected():
    with pytest.raises(SegmentationError):
        maoris_labels(np.zeros((3, 3, 3), bool))
    with pytest.raises(ParameterError, match="params"):
        maoris_labels(two_rooms(), {"threshold": 0.3})


# --------------------------------------------------------------------------
# Research data: the released C++ region counts (released_code_results.md)

RELEASED_COUNTS = {  # map: (ursim_t050 grey != 0, icra_t030_bin grey > 250, default_t025 grey != 0)
    "00": (6, 8, 9), "01": (6, 6, 7), "03": (4, 4, 5), "04": (5, 6, 5), "06": (4, 5, 5),
    "07": (2, 4, 4), "08": (4, 6, 6), "10": (6, 7, 7), "11": (3, 4, 4), "12": (7, 7, 8),
    "14": (6, 9, 8), "15": (4, 8, 7), "17": (4, 4, 4), "18": (7, 8, 8), "20": (5, 8, 8),
    "21": (8, 8, 8), "23": (5, 6, 6), "24": (6, 6, 6), "model_simple": (6, 8, 8),
}  # fmt: skip


@pytest.fixture(scope="module")
def datasets() -> Path:
    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

    root = dataset_root()
    if root is None or not (root / "ursim_kth_sketches").is_dir():
        pytest.skip(MISSING_REASON)
    return root


@pytest.mark.dataset
@pytest.mark.slow
def test_region_counts_close_to_the_released_cpp(datasets):
    from ursim_core.io.maps import load_map

    kth = datasets / "ursim_kth_sketches"
    differences = []
    for name, expected in RELEASED_COUNTS.items():
        path = kth / ("model" if name == "model_simple" else "sketches") / f"{name}.png"
        grey_free = load_map(path, nonzero_free=True).free
        binary_free = load_map(path, threshold=250).free
        runs = (
            (grey_free, PRESETS["ursim-released"]),
            (binary_free, PRESETS["icra"]),
            (grey_free, PRESETS["default"]),
        )
        for (free, params), count in zip(runs, expected):
            differences.append(int(maoris_labels(free, params).max()) - count)
    differences = np.abs(differences)
    # Measured: 43 of 57 equal, 52 within 1, all within 2.
    assert (differences == 0).sum() >= 41
    assert (differences <= 1).sum() >= 50
    assert differences.max() <= 2
