"""The whole MAORIS pipeline, and the compiled kernels' first run.

:func:`maoris_labels` runs the seven steps; :func:`compile_kernels` compiles (or loads) the
kernels; :func:`kernels_cached` says, without importing numba, whether this install has them
compiled on disk.
"""

from __future__ import annotations

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.segmentation.canonical import free_window
from ursim_core.segmentation.maoris.compiled import kernels
from ursim_core.segmentation.maoris.inscribed_circle import (
    _as_free_mask,
    _quantization_table,
    _radii_in_storage,
)
from ursim_core.segmentation.maoris.params import PRESETS, MaorisParams
from ursim_core.segmentation.maoris.steps import (
    mark_unbreakable_edges,
    merge_ripples,
    remove_doors,
    remove_isolated_zones,
    remove_small_zones,
    watershed_merge,
)
from ursim_core.segmentation.maoris.warm_memory import warm_memory
from ursim_core.segmentation.maoris.zone_graph import _PAD, ZoneGraph

__all__ = ["maoris_labels", "compile_kernels"]

#: The output is made in the zone graph's memory when that memory need grow by at most this
#: factor to hold it (maps whose border around the free space is thin; 1.02 at 8000 px).
OUTPUT_IN_STORAGE_GROWTH = 1.25


def maoris_labels(free: np.ndarray, params: MaorisParams = PRESETS["default"]) -> np.ndarray:
    """Segment a free-space mask into rooms with MAORIS.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True = free space.
    params : MaorisParams
        See :data:`PRESETS`.

    Returns
    -------
    ndarray of int32
        0 = no region; regions 1..N in the raster order of their first pixel.

    Notes
    -----
    As in the C++, some free pixels get no region: the row and column just
    above and left of walls (the one-pixel shift of the inscribed discs),
    regions deleted for having no neighbour when there are several, and
    everything when the map has no obstacle pixel at all (the inscribed-circle
    image is then constant and normalises to 0). A map without free pixels
    gives all zeros.

    Examples
    --------
    >>> free = np.zeros((30, 30), bool); free[3:27, 3:27] = True
    >>> int(maoris_labels(free, PRESETS["robot"]).max())
    1
    """
    if not isinstance(params, MaorisParams):
        raise ParameterError(f"expected MaorisParams, got {type(params).__name__}", field="params")
    free = _as_free_mask(free)
    shape = free.shape
    # Everything outside the free pixels' bounding box is obstacle: work on the box.
    window = free_window(free, 1)
    if window is None:
        return np.zeros(shape, np.int32)
    free = free[window]
    # When the map's border around its free space is thin, the output is made in the memory of
    # the zone graph's labels, grown to hold it (a few % at 8000 px), rather than in a fresh
    # image: see ZoneGraph._label_image_in_storage. A wide border is mostly zeros, which a fresh
    # image gives for free.
    padded_size = (free.shape[0] + 2 * _PAD) * (free.shape[1] + 2 * _PAD)
    in_storage = shape[0] * shape[1] <= OUTPUT_IN_STORAGE_GROWTH * padded_size
    # The zone graph's memory is faulted in on a second thread meanwhile (see .warm_memory).
    warming = warm_memory(free)
    # The window is its own bounding box: the radii of inscribed_circle_radii(free).
    radii, storage = _radii_in_storage(
        free, params.max_radius, padding=_PAD, size=shape[0] * shape[1] if in_storage else 0
    )
    # The zones are labelled over the radii, read only for the values, and the graph pads
    # them in place (a fresh image of that size costs more in page faults than the pass); their
    # values and sizes are counted as they are labelled. The values come from the radii through
    # the quantisation's table row by row as they are labelled: no value image is made (64 MB
    # of fresh memory at 8000 x 8000 px: on the virtual machines this was measured on, memory
    # touched for the first time cost 1-2.5 s per GB, the host backing each page on its first
    # touch, against 0.07 s to reuse it).
    zones, value, size = kernels().label_radii_zones_counted(radii, *_quantization_table(radii, params.quantum))
    # Large temporaries go as soon as they are read, before the graph is built (the step of the
    # peak memory).
    del free, radii
    if warming is not None:
        warming.release()
    graph = ZoneGraph._of_zone_values(zones, value, size, storage=storage)
    del zones, storage
    remove_small_zones(graph, min_size=params.small_before)
    merge_ripples(graph, ripples=params.ripples, _renumber=True)
    mark_unbreakable_edges(graph, threshold=params.threshold)
    watershed_merge(graph, threshold=params.threshold, margin=params.margin)
    remove_doors(graph, doors=params.doors)
    remove_small_zones(graph, min_size=params.small_after)
    remove_isolated_zones(graph)
    labels = graph._label_image_in_storage(shape, (window[0].start, window[1].start)) if in_storage else None
    if labels is not None:
        return labels
    labels = np.zeros(shape, np.int32)
    graph._write_label_image(labels[window])
    return labels


def compile_kernels(*, processes: int = 1, jit: bool = False) -> float:
    """Make the MAORIS kernels ready for use; return the seconds it took.

    By default this compiles the C kernels into an extension module
    (:func:`ursim_core.segmentation.maoris.compiled.build_ahead`, seconds, once per install
    and kernel source) unless a fresh one exists, and loads it: processes start without
    numba (:mod:`ursim_core.segmentation.maoris.compiled`).
    When that build fails (no C compiler) or ``jit`` is true, numba's JIT
    compiles the kernels into its cache instead. The first segmentation in a new
    environment otherwise pays this; benchmarks call it so that their timings exclude it.
    Prints nothing (callers say what is happening:
    :func:`~ursim_core.segmentation.maoris.kernel_cache.kernels_cached` tells whether it
    will take long).

    Parameters
    ----------
    processes : int, keyword-only
        JIT only: when more than 1 and the kernels are not all cached, compile their groups
        (:data:`~ursim_core.segmentation.maoris.kernels.signatures.GROUPS`) in this many
        processes at once into numba's cache, then load them here. Default 1: on the
        shared 2-CPU machine it was measured on (load 7-8), two processes took longer
        (66 s wall, 42 s CPU) than one (53 s, 34 s); on idle CPUs they may be faster
        (not measured).
    jit : bool, keyword-only
        Compile numba's JIT cache (what ``URSIM_KERNELS=jit`` uses) rather than the C module.

    Examples
    --------
    >>> compile_kernels() >= 0
    True
    """
    import time

    from ursim_core.segmentation.maoris import compiled

    start = time.perf_counter()
    if not jit:
        if compiled.ahead_module_path() is None:
            compiled.build_or_warn()
        if compiled.ahead_module_path() is not None:
            return time.perf_counter() - start
    _compile_jit(processes)
    return time.perf_counter() - start


def _compile_jit(processes: int) -> None:
    from ursim_core.segmentation.maoris.kernel_cache import jit_kernels_cached
    from ursim_core.segmentation.maoris.kernels import signatures

    if processes > 1 and not jit_kernels_cached():
        _compile_in_processes(len(signatures.GROUPS), processes)
    signatures.compile_group()


def _compile_in_processes(groups: int, processes: int) -> None:
    import subprocess
    import sys

    code = "from ursim_core.segmentation.maoris.kernels.signatures import compile_group; compile_group({})"
    pending = list(range(groups))
    running: list[subprocess.Popen] = []
    while pending or running:
        while pending and len(running) < processes:
            running.append(subprocess.Popen([sys.executable, "-c", code.format(pending.pop(0))]))
        running.pop(0).wait()
    # A failed group is compiled again in this process (compile_group), with its error.
