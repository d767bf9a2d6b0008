"""Fixtures shared by the core tests: a small generated dataset in the KTH layout, and the folders
fsynced while a test runs."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from PIL import Image
from synthetic_kth import MODEL_SCALE, SKETCH_SCALES, dat_text, plan_image


@pytest.fixture(scope="module")
def synthetic_dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("synthetic_kth")
    (root / "sketches").mkdir()
    (root / "model").mkdir()
    Image.fromarray(plan_image(MODEL_SCALE)).save(root / "model" / "model_simple.png")
    for name, scale in SKETCH_SCALES.items():
        Image.fromarray(plan_image(scale)).save(root / "sketches" / f"{name}.png")
        # malcolm annotated the three rooms, vasiliki only the first two.
        for annotator, rooms in (("malcolm", 3), ("vasiliki", 2)):
            folder = root / "gt_correspondences" / annotator
            folder.mkdir(parents=True, exist_ok=True)
            (folder / f"gt_{name}_model_simple.dat").write_text(dat_text(scale, MODEL_SCALE, rooms))
    return root


@pytest.fixture
def directory_syncs(monkeypatch) -> list[str]:
    """The paths of the folders fsynced while the test runs, in order (read from /proc: Linux)."""
    if not Path("/proc/self/fd").is_dir():
        pytest.skip("reads the synced folders' paths from /proc (Linux)")
    synced: list[str] = []
    real_fsync = os.fsync

    def fsync(descriptor):
        if stat.S_ISDIR(os.fstat(descriptor).st_mode):
            synced.append(os.readlink(f"/proc/self/fd/{descriptor}"))
        return real_fsync(descriptor)

    monkeypatch.setattr(os, "fsync", fsync)
    return synced
