"""Shared fixtures of the GUI tests: offscreen Qt, small synthetic maps and segmentations."""

from __future__ import annotations

import os

# Must happen before QApplication exists (pytest-qt creates it lazily in the qapp fixture).
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np
import pytest


def two_room_free(rows: int = 60, cols: int = 130) -> np.ndarray:
    """Two rooms joined by a door: the smallest map with two regions and one edge."""
    free = np.zeros((rows, cols), bool)
    free[5:55, 5:60] = True
    free[5:55, 70:125] = True
    free[27:33, 60:70] = True
    return free


def three_room_labels() -> np.ndarray:
    """Label image of three rooms in a row (1 | 2 | 3), walls 0, 60x150."""
    labels = np.zeros((60, 150), np.int32)
    labels[5:55, 5:48] = 1
    labels[5:55, 52:98] = 2
    labels[5:55, 102:145] = 3
    labels[28:32, 48:52] = 1
    labels[28:32, 98:102] = 2
    return labels


@pytest.fixture
def labels3() -> np.ndarray:
    return three_room_labels()


@pytest.fixture
def segmentation3(labels3):
    from ursim_core.graph import region_graph
    from ursim_core.segmentation import Segmentation

    return Segmentation(labels=labels3, graph=region_graph(labels3), method="label-image")


@pytest.fixture
def grey3(labels3) -> np.ndarray:
    return np.where(labels3 > 0, 255, 0).astype(np.uint8)


@pytest.fixture(autouse=True)
def _user_data_dir(tmp_path, monkeypatch):
    """Keep logs and autosaves of every test in its own temporary folder."""
    monkeypatch.setenv("URSIM_GUI_DATA_DIR", str(tmp_path / "userdata"))
