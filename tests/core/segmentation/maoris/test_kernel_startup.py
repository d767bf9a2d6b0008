"""Cheap import, one signature per kernel, and the kernel-cache probe."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest


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


@pytest.fixture
def jit_kernels(monkeypatch):
    """The steps use numba's JIT dispatchers (``URSIM_KERNELS=jit``) for this test."""
    from ursim_core.segmentation.maoris import compiled

    monkeypatch.setenv("URSIM_KERNELS", "jit")
    compiled.forget()
    yield compiled.kernels()
    compiled.forget()


def test_every_kernel_called_has_exactly_its_declared_signature(monkeypatch, jit_kernels):
    from ursim_core.segmentation.flooding import watershed_flood
    from ursim_core.segmentation.maoris import (
        ZoneGraph,
        contact_tracking,
        flat_zones,
        inscribed_circle_image,
        maoris_labels,
        merge_ripples,
        quantize,
    )
    from ursim_core.segmentation.maoris.kernels import signatures
    from ursim_core.segmentation.watershed import watershed_labels
    from ursim_core.synth import make_large_building

    assert jit_kernels.source == "jit"
    free = make_large_building(300, seed=3).free
    maoris_labels(free)
    # Free space touching every side: its window is the whole, C-contiguous image, converted
    # to the declared layout of distance_transform and paint_discs, not compiled again.
    rows, cols = np.flatnonzero(free.any(axis=1)), np.flatnonzero(free.any(axis=0))
    maoris_labels(free[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1].copy())
    monkeypatch.setattr(contact_tracking, "_BAND_PIXELS", 0)  # also the banded count (join_counts)
    maoris_labels(free)
    values = quantize(np.where(free, 100, 0).astype(np.uint8))
    ZoneGraph(flat_zones(values), values).contact_percent(1, 2)  # contact_table
    merge_ripples(ZoneGraph(flat_zones(values), values))  # expand_graph: the step on its own keeps the ids
    flat_zones(np.array([[5, 5, 0], [0, 5, 7]]))  # another dtype goes through the one signature too
    inscribed_circle_image(free)  # lookup_bytes: the public value image (segmentations make none)
    watershed_labels(free)  # the flooding kernels of the watershed segmenter
    watershed_flood(np.arange(6.0).reshape(2, 3), np.array([[1, 0, 0], [0, 0, 2]]), connectivity=2)
    for key, types in signatures.SIGNATURES.items():
        compiled = signatures.kernel(key).signatures
        assert compiled == [types], (key, compiled)
        # The ahead-of-time build exports this return type without typing the kernel.
        returned = signatures.kernel(key).overloads[types].signature.return_type
        assert returned == signatures.RETURN_TYPES[key], (key, returned)


def test_helpers_once_given_literals_compile_once(tmp_path):
    """Typed values, not literals, at their call sites: numba types a call with what it knows
    so far and compiled these helpers for a literal first, in vain (seconds of the first
    build); and the bodies contact_table shares are not entry kernels compiled twice."""
    code = (
        "from ursim_core.segmentation.maoris.kernels import signatures, adjacency, contacts, discs, flooding\n"
        "for key in [('adjacency', 'build_adjacency'), ('flooding', 'flood_levels'), "
        "('discs', 'centre_rectangles'), ('contacts', 'contact_table')]:\n"
        "    signatures.kernel(key).compile(signatures.SIGNATURES[key])\n"
        "helpers = [adjacency._contacts_in_order, flooding._heap_flood, flooding._bucket_flood, "
        "flooding._last_tie, discs._load_radii, contacts._counted, contacts._compacted]\n"
        "print([len(helper.signatures) for helper in helpers], len(contacts.count_contacts.signatures))"
    )
    assert _run(code, NUMBA_CACHE_DIR=str(tmp_path)) == "[1, 1, 1, 1, 1, 1, 1] 0"


def test_ahead_of_time_kernels_give_the_jit_labels(monkeypatch):
    """The built module and the JIT: the same labels on maps of every step (banded contacts too)."""
    from ursim_core.segmentation.maoris import PRESETS, compile_kernels, compiled, contact_tracking, maoris_labels
    from ursim_core.synth import make_large_building

    compile_kernels()
    assert compiled.ahead_module_path() is not None
    maps = [make_large_building(size, seed=seed).free for size, seed in ((300, 1), (500, 4))]
    labels = {}
    for way in ("ahead", "jit"):
        monkeypatch.setenv("URSIM_KERNELS", way)
        compiled.forget()
        assert compiled.kernels().source == way
        labels[way] = [maoris_labels(free, PRESETS[preset]) for free in maps for preset in ("default", "sketch")]
        with monkeypatch.context() as banded:
            banded.setattr(contact_tracking, "_BAND_PIXELS", 0)
            banded.setattr(contact_tracking, "usable_cpus", lambda: 3)
            labels[way].append(maoris_labels(maps[1], PRESETS["robot"]))
    compiled.forget()
    assert max(int(image.max()) for image in labels["jit"]) > 5
    for ahead, jit in zip(labels["ahead"], labels["jit"]):
        np.testing.assert_array_equal(ahead, jit)


def test_stale_or_missing_build_is_not_used(tmp_path, monkeypatch):
    from ursim_core.segmentation.maoris import compiled

    path = compiled.ahead_module_path()
    if path is None:
        pytest.skip("no ahead-of-time build in this install (make builds it)")
    digest = path.parent / compiled.DIGEST_NAME
    original = digest.read_text(encoding="ascii")
    monkeypatch.setattr(compiled, "build_directories", lambda: [path.parent])
    monkeypatch.setattr(compiled, "sources_digest", lambda: "0" * 64)  # as if a kernel was edited
    assert compiled.ahead_module_path() is None
    monkeypatch.setattr(compiled, "build_directories", lambda: [tmp_path])
    assert compiled.ahead_module_path() is None
    assert digest.read_text(encoding="ascii") == original
    monkeypatch.setenv("URSIM_KERNELS", "ahead")
    compiled.forget()
    with pytest.raises(compiled.SegmentationError, match="URSIM_KERNELS=ahead"):
        compiled.kernels()
    monkeypatch.setenv("URSIM_KERNELS", "fast")
    compiled.forget()
    with pytest.raises(compiled.SegmentationError, match="auto, jit or ahead"):
        compiled.kernels()
    compiled.forget()


def test_a_broken_build_is_reported_and_left_for_the_jit(tmp_path, monkeypatch):
    from ursim_core.segmentation.maoris import compiled

    module = tmp_path / (compiled.MODULE_NAME + compiled.importlib.machinery.EXTENSION_SUFFIXES[0])
    module.write_bytes(b"\x7fELF truncated")
    (tmp_path / compiled.DIGEST_NAME).write_text(compiled.sources_digest() + "\n", encoding="ascii")
    monkeypatch.setattr(compiled, "build_directories", lambda: [tmp_path])
    rebuilds = []
    monkeypatch.setattr(compiled, "build_or_warn", lambda: rebuilds.append(1))  # no build here
    monkeypatch.setenv("URSIM_KERNELS", "auto")
    compiled.forget()
    with pytest.warns(RuntimeWarning, match="cannot be loaded.*building them again"):
        assert compiled.kernels().source == "jit"
    assert rebuilds == [1]
    monkeypatch.setenv("URSIM_KERNELS", "ahead")
    compiled.forget()
    with pytest.raises(compiled.SegmentationError, match=str(module.name)):
        compiled.kernels()
    compiled.forget()


def test_importing_the_kernels_for_a_segmentation_loads_no_numba():
    from ursim_core.segmentation.maoris import compile_kernels

    compile_kernels()
    code = (
        "import sys, numpy as np\n"
        "from ursim_core.segmentation.maoris import maoris_labels\n"
        "free = np.zeros((30, 30), bool); free[3:27, 3:27] = True\n"
        "maoris_labels(free)\n"
        "print(sorted(m for m in ('numba', 'llvmlite') if m in sys.modules))"
    )
    assert _run(code) == "[]"


def test_kernel_cache_lists_the_declared_kernels():
    from ursim_core.segmentation.maoris.compiled import ENTRY_KERNELS
    from ursim_core.segmentation.maoris.kernels import signatures

    listed = {(module, name) for module, names in ENTRY_KERNELS.items() for name in names}
    assert listed == set(signatures.SIGNATURES)


def test_kernels_cached_is_true_after_compiling_and_false_on_an_empty_cache(tmp_path):
    from ursim_core.segmentation.maoris import compile_kernels, kernels_cached
    from ursim_core.segmentation.maoris.kernel_cache import compile_notice

    compile_kernels(processes=1)
    assert kernels_cached() and compile_notice() is None
    compile_kernels(jit=True)
    code = (
        "from ursim_core.segmentation.maoris.kernel_cache import compile_notice, kernels_cached\n"
        "print(kernels_cached(), compile_notice())"
    )
    assert _run(code, NUMBA_CACHE_DIR=str(tmp_path / "numba")).startswith("True None")
    jit = _run(code, NUMBA_CACHE_DIR=str(tmp_path / "numba"), URSIM_KERNELS="jit")
    assert jit.startswith("False Compiling the segmentation kernels (first run")


def test_kernel_groups_compile_in_processes_and_cover_every_kernel():
    from ursim_core.segmentation.maoris.kernels import signatures
    from ursim_core.segmentation.maoris.pipeline import _compile_in_processes, compile_kernels

    assert sorted(key for group in signatures.GROUPS for key in group) == sorted(signatures.SIGNATURES)
    compile_kernels(jit=True)
    _compile_in_processes(len(signatures.GROUPS), 2)  # cached: each process loads its group
