"""The whole MAORIS pipeline, and the compiled kernels' first run.

:func:`maoris_labels` runs the seven steps; :func:`compile_kernels` compiles (or loads) the
kernels; :func:`kernels_cached` says, without importing numba, whether this install has them
compiled on disk.
"""

from __future__ import annotations

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.segmentation.maoris.inscribed_circle import _as_free_mask, _free_bbox, inscribed_circle_image, quantize
from ursim_core.segmentation.maoris.kernels import contacts as _contacts
from ursim_core.segmentation.maoris.params import PRESETS, MaorisParams
from ursim_core.segmentation.maoris.steps import (
    mark_unbreakable_edges,
    merge_ripples,
    remove_doors,
    remove_isolated_zones,
    remove_small_zones,
    watershed_merge,
)
from ursim_core.segmentation.maoris.zone_graph import _PAD, ZoneGraph, flat_zones

__all__ = ["maoris_labels", "compile_kernels"]


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
    labels = np.zeros(free.shape, np.int32)
    # Everything outside the free pixels' bounding box is obstacle: work on the box.
    window = _free_bbox(free, margin=1)
    if window is None:
        return labels
    free = free[window]
    values = quantize(inscribed_circle_image(free, max_radius=params.max_radius), quantum=params.quantum)
    graph = ZoneGraph(flat_zones(values), values)
    remove_small_zones(graph, min_size=params.small_before)
    merge_ripples(graph, ripples=params.ripples)
    mark_unbreakable_edges(graph, threshold=params.threshold)
    watershed_merge(graph, threshold=params.threshold, margin=params.margin)
    remove_doors(graph, doors=params.doors)
    remove_small_zones(graph, min_size=params.small_after)
    remove_isolated_zones(graph)
    labels[window] = graph.label_image()
    return labels


def compile_kernels() -> float:
    """Compile (or load from numba's cache) the compiled steps; return the seconds it took.

    The first segmentation in a new environment otherwise pays this (about
    43 s; under a second once cached). Benchmarks call it
    so that their timings exclude it.

    Examples
    --------
    >>> compile_kernels() >= 0
    True
    """
    import time

    start = time.perf_counter()
    free = np.zeros((40, 60), bool)
    free[3:37, 3:28] = free[3:37, 31:57] = free[15:22, 28:31] = True  # two rooms and a door
    labels = maoris_labels(free, PRESETS["default"])
    # Large images count contacts in bands of rows, which this small one does not.
    padded = np.pad(labels, _PAD)
    alive = np.arange(int(labels.max()) + 1) > 0
    _contacts.start_tracking(padded.ravel(), padded.shape[1], alive, bands=2)
    return time.perf_counter() - start
