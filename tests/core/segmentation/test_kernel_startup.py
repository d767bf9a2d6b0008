"""Cheap import, one signature per kernel, and the kernel-cache probe."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np


def _run(code: str, **env: str) -> str:
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env={**os.environ, **env}
    )
    return result.stdout.strip()


def test_importing_segmentation_loads_no_numba_scipy_ndimage_or_skimage():
    code = (
        "import sys\n"
        "import ursim_core.segmentation, ursim_core.segmentation.interface, ursim_core.segmentation.graph\n"
        "import ursim_core.segmentation.maoris\n"
        "from ursim_core.segmentation.maoris import kernels_cached, MaorisParams, PRESETS\n"
        "kernels_cached()\n"
        "print(sorted(m for m in ('numba', 'scipy.ndimage', 'skimage') if m in sys.modules))"
    )
    assert _run(code) == "[]"


def test_public_names_stay_importable():
    from ursim_core.segmentation import SEGMENTERS, Segmentation, region_graph, segment  # noqa: F401
    from ursim_core.segmentation.maoris import (  # noqa: F401
        PRESETS,
        MaorisParams,
        ZoneEdge,
        ZoneGraph,
        compile_kernels,
        flat_zones,
        inscribed_circle_image,
        inscribed_circle_radii,
        kernels_cached,
        maoris_labels,
        mark_unbreakable_edges,
        merge_ripples,
        quantize,
        remove_doors,
        remove_isolated_zones,
        remove_small_zones,
        watershed_merge,
    )


def test_every_kernel_called_has_exactly_its_declared_signature(monkeypatch):
    from ursim_core.segmentation.maoris import ZoneGraph, flat_zones, maoris_labels, quantize
    from ursim_core.segmentation.maoris.kernels import contacts, signatures
    from ursim_core.synth import make_large_building

    free = make_large_building(300, seed=3).free
    maoris_labels(free)
    monkeypatch.setattr(contacts, "_BAND_PIXELS", 0)  # also the banded count (join_counts)
    maoris_labels(free)
    values = quantize(np.where(free, 100, 0).astype(np.uint8))
    ZoneGraph(flat_zones(values), values).contact_percent(1, 2)  # contact_table
    for key, types in signatures.SIGNATURES.items():
        compiled = signatures.kernel(key).signatures
        assert compiled == [types], (key, compiled)


def test_kernel_cache_lists_the_declared_kernels():
    from ursim_core.segmentation.maoris.kernel_cache import ENTRY_KERNELS
    from ursim_core.segmentation.maoris.kernels import signatures

    listed = {(module, name) for module, names in ENTRY_KERNELS.items() for name in names}
    assert listed == set(signatures.SIGNATURES)


def test_kernels_cached_is_true_after_compiling_and_false_on_an_empty_cache(tmp_path):
    from ursim_core.segmentation.maoris import compile_kernels, kernels_cached
    from ursim_core.segmentation.maoris.kernel_cache import compile_notice

    compile_kernels(processes=1)
    assert kernels_cached() and compile_notice() is None
    code = (
        "from ursim_core.segmentation.maoris.kernel_cache import compile_notice, kernels_cached\n"
        "print(kernels_cached(), compile_notice())"
    )
    assert _run(code, NUMBA_CACHE_DIR=str(tmp_path)).startswith("False Compiling the segmentation kernels (first run")


def test_region_graph_boxes_are_those_of_scipy_find_objects():
    from scipy import ndimage

    from ursim_core.segmentation.graph import _bounding_boxes

    rng = np.random.default_rng(0)
    for shape in ((1, 1), (7, 1), (1, 9), (40, 33)):
        labels = rng.choice(np.array([0, 1, 2, 5], np.int32), size=shape)  # ids 3 and 4 absent
        count = int(labels.max()) + 1
        boxes = _bounding_boxes(labels, count)
        for index, box in enumerate(ndimage.find_objects(labels), start=1):
            if box is not None:
                assert tuple(boxes[index]) == (box[0].start, box[1].start, box[0].stop, box[1].stop)


def test_kernel_groups_compile_in_processes_and_cover_every_kernel():
    from ursim_core.segmentation.maoris.kernels import signatures
    from ursim_core.segmentation.maoris.pipeline import _compile_in_processes, compile_kernels

    assert sorted(key for group in signatures.GROUPS for key in group) == sorted(signatures.SIGNATURES)
    compile_kernels()
    _compile_in_processes(len(signatures.GROUPS), 2)  # cached: each process loads its group
