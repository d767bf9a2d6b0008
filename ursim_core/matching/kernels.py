"""The matcher's loops in C (:file:`csrc`), and when they are used.

The planar matcher's seed-and-expand loop runs in C (:file:`csrc/planar.c`), a port of
:mod:`ursim_core.matching.planar`, which stays the reference (tests compare both) and runs where
the C module cannot be built. Long neighbour orders (a building's corridor borders thousands of
rooms) are aligned bit-parallel (:file:`csrc/bitalign.c`, a port of
:mod:`ursim_core.matching.edit_kernel`'s packed kernel; see :data:`TABLE_CELLS`).
:func:`sweep_compiled` runs the loop over every m of a sweep in one call (:file:`csrc/sweep.c`):
seeds, relation and pair costs at each m as :func:`~ursim_core.matching.single.match_at` makes
them, the values of m shared between threads when asked (the module releases the GIL).
:func:`fit_axes_compiled` is the position refit's robust line fit (:file:`csrc/refit.c`, a port of :mod:`ursim_core.matching.refit`), and
:func:`overlap_search_compiled` the orientation overlap's pattern search (:file:`csrc/overlap.c`, a
port of :mod:`ursim_core.matching.alignment`'s, with OpenCV's nearest-neighbour warp done as OpenCV
does it), and :func:`correspondences_compiled` the vote's region correspondences
(:file:`csrc/correspondences.c`, a port of
:func:`~ursim_core.matching.resampling.region_correspondences`).

:func:`match_compiled` takes the planar matcher's common case (no constraints, no alternatives
kept), graphs of any size, and gives the same pairs in the same order, the same cost (the pair
costs summed in pair order, as Python 3.11's ``sum``) and the same counts;
:func:`sweep_compiled` gives, at every m, what :func:`~ursim_core.matching.single.match_at` would.
Graphs over a million (sketch, metric) cells, or with two neighbour orders whose table passed
65,536 cells, went to Python before issue 14: the 8000 px generated pair's automatic-m sweep (4250
regions a map, 19 distinct m) took 12.3 s there; it takes 2.6 s in C on one thread, 1.5 s on two.

The module is compiled on the installed machine (:class:`ursim_core.native.NativeModule`; ``make``
builds it with the segmentation kernels, else the first match does, in about a second). With no C
compiler, or ``URSIM_KERNELS=jit`` (which also keeps the MAORIS kernels in numba), the matcher
runs in Python, about three times as slow on a turned KTH sketch (127 ms against 44 ms, round 40).

Examples
--------
>>> from ursim_core.matching.planar import PlanarGraph
>>> p = PlanarGraph(nodes=[0, 1, 2], neighbours=[[1], [0, 2], [1]], edges=[(0, 1), (1, 2)])
>>> result = match_compiled(p, p, np.eye(3, dtype=bool), [(0, 0), (1, 1), (2, 2)])
>>> result is None or result[:2] == ([(0, 0), (1, 1), (2, 2)], 0)
True
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from ursim_core.native import NativeModule

__all__ = [
    "MODULE",
    "TABLE_CELLS",
    "kernel",
    "build",
    "match_compiled",
    "sweep_compiled",
    "fit_axes_compiled",
    "overlap_search_compiled",
    "correspondences_compiled",
    "forget",
]

MODULE = NativeModule("_matching_kernels", Path(__file__).resolve().parent / "csrc")
"""The extension module: its sources and where it is built."""

#: Alignments of neighbour orders whose table has more cells than this (``(rows + 1) x (cols +
#: 1)``) run bit-parallel in the C loop (:file:`csrc/bitalign.c`), the others fill a table: a
#: building's corridor borders thousands of rooms, and a table of two such orders would be 72 MB.
#: Both give the same pairs (tests lower it to send every alignment through the bit-parallel path).
TABLE_CELLS = 1 << 16

_UNSET = object()
_loaded = _UNSET


def build() -> Path:
    """Compile the kernel (:meth:`NativeModule.build`) and load it on the next :func:`kernel`."""
    path = MODULE.build()
    forget()
    return path


def kernel():
    """The loaded module, or None (no C compiler, ``URSIM_KERNELS=jit``, or a failed build).

    The first call builds the module when it is missing or stale, or cannot be loaded; a failure
    is warned about once and the matcher runs in Python.
    """
    global _loaded
    if _loaded is _UNSET:
        _loaded = None
        if os.environ.get("URSIM_KERNELS", "auto").strip().lower() != "jit":
            _loaded = _built_and_loaded()
    return _loaded


def _built_and_loaded():
    """The module, built first when missing or stale, and built again when the one on disk cannot
    be loaded (cut short, foreign); None, with a warning, when that fails too."""
    path = MODULE.built_path()
    if path is not None:
        try:
            return MODULE.load(path)
        except (ImportError, OSError) as error:
            warnings.warn(
                f"the matcher's C kernels at {path} cannot be loaded ({type(error).__name__}: {error}); "
                "building them again",
                RuntimeWarning,
                stacklevel=3,
            )
    try:
        return MODULE.load(MODULE.build())
    except (RuntimeError, ImportError, OSError) as error:
        warnings.warn(
            f"could not build the matcher's C kernels ({type(error).__name__}: {error}); "
            "matching runs in Python, about three times as slow",
            RuntimeWarning,
            stacklevel=3,
        )
        return None


def forget() -> None:
    """Look for the module again on the next :func:`kernel` (after a build, or in tests)."""
    global _loaded
    _loaded = _UNSET


def _taken(first, second):
    """``(module, graphs)`` when the C loop is built, ``graphs`` being the loop's first arguments
    (both graphs' offsets and flat orders, both edge counts); else None."""
    module = kernel()
    if module is None:
        return None
    first_offsets, first_orders, _ = first.flat_orders
    second_offsets, second_orders, _ = second.flat_orders
    return module, (first_offsets, first_orders, second_offsets, second_orders, len(first.edges), len(second.edges))


def match_compiled(
    first, second, same, seeds, *, rotation_search="min", reflections=False, pair_costs=None, pair_cost_weight=0.0
):
    """``(pairs, cost, structural_cost, hypotheses, seeds_expanded)`` from the C loop, or None
    when it does not take this case (see the module docstring); ``seeds`` must not be empty."""
    taken = _taken(first, second)
    if taken is None:
        return None
    module, graphs = taken
    same = np.ascontiguousarray(same, dtype=np.bool_)
    weighted = pair_costs is not None and pair_cost_weight != 0
    costs = np.ascontiguousarray(pair_costs, dtype=np.float64) if weighted else None
    return module.planar_match(
        *graphs,
        same,
        seeds,
        costs,
        float(pair_cost_weight),
        int(rotation_search == "min"),
        int(bool(reflections)),
        TABLE_CELLS,
    )


#: ``hypothesis_score`` of :class:`~ursim_core.matching.MatchConfig` as the sweep kernel's ``score``
#: argument (see :func:`~ursim_core.matching.single.pair_cost_matrix`).
SWEEP_SCORES = {"structure": 0, "signature": 1, "substitutions": 2}


def sweep_compiled(
    first, second, c_matrix, order, values, cap, ms, *, score="signature", weight=0.0, rotation_search="min",
    reflections=False, threads=1,
):  # fmt: skip
    """The planar matcher at every m of ``ms`` from the C loop, or None when it does not take this
    case (see the module docstring; also a ``c_matrix`` with NaN).

    ``order``, ``values`` and ``cap`` are a :class:`~ursim_core.matching.single.SeedSelector`'s:
    the positions of the lowest values of the flattened c, sorted by value (ties by position),
    their values, and the seed cap. ``score`` is the ``hypothesis_score`` (with ``weight`` 0 the
    structural cost alone). Returns, per m, ``(pairs, cost, structural_cost, hypotheses,
    seeds_expanded, seeds_count)``; with no seed at m, ``([], None, 0, 0, 0, 0)``. ``threads``:
    how many threads of the C module share the values of m (the same results).
    """
    taken = _taken(first, second) if rotation_search in ("min", "first") else None
    if taken is None:
        return None
    module, graphs = taken
    c_matrix = np.ascontiguousarray(c_matrix, dtype=np.float64)
    if np.isnan(c_matrix).any():
        return None
    return module.planar_sweep(
        *graphs,
        c_matrix,
        np.ascontiguousarray(order, dtype=np.int64),
        np.ascontiguousarray(values, dtype=np.float64),
        int(cap),
        np.ascontiguousarray(ms, dtype=np.float64),
        SWEEP_SCORES[score] if weight != 0 else 0,
        float(weight),
        int(rotation_search == "min"),
        int(bool(reflections)),
        max(1, int(threads)),
        TABLE_CELLS,
    )


#: What :func:`fit_axes_compiled` returns when a reweighting round keeps fewer than two pairs.
NO_FIT = "no fit"


def fit_axes_compiled(source, target, weights, *, rounds: int, cutoff: float):
    """The refit's scale and shift per axis (:func:`~ursim_core.matching.refit.fit_axis_transform`
    after the ptp checks, before the scale check) from the C loop: ``((row scale, row shift), (col
    scale, col shift))``, :data:`NO_FIT`, or None where NumPy must fit (no C module, or an axis
    whose weighted points all but share one x, where NumPy keeps lstsq's minimum-norm answer).

    The sums run in index order: the fits equal NumPy's to rounding (a test compares them).
    """
    module = kernel()
    if module is None:
        return None
    found = module.fit_axes(
        np.ascontiguousarray(source, dtype=np.float64),
        np.ascontiguousarray(target, dtype=np.float64),
        np.ascontiguousarray(weights, dtype=np.float64),
        int(rounds),
        float(cutoff),
    )
    if found == 1:
        return NO_FIT
    return None if found == 2 else found


def overlap_search_compiled(sketch, target, target_area: int, numbers: dict, *, first_steps, smallest_step, max_rounds):
    """The pattern search of :func:`ursim_core.matching.alignment.fit_alignment` in C: ``(best
    overlap, params)`` as the Python search finds them (a test compares both), or None without
    the C module.

    ``sketch`` and ``target`` are the shrunk uint8 free-space images; ``numbers`` holds ``turn``
    (t00, t01, t10, t11), ``scale`` and ``centre`` (rows, cols), ``metric_centre`` and
    ``metric_extent`` (rows, cols), ``to_coarse`` and ``factor``, as the Python search reads them.
    """
    module = kernel()
    if module is None:
        return None
    return module.overlap_search(
        np.ascontiguousarray(sketch, dtype=np.uint8),
        np.ascontiguousarray(target, dtype=np.uint8),
        int(target_area),
        tuple(map(float, numbers["turn"])),
        tuple(map(float, numbers["scale"])),
        tuple(map(float, numbers["centre"])),
        tuple(map(float, numbers["metric_centre"])),
        tuple(map(float, numbers["metric_extent"])),
        float(numbers["to_coarse"]),
        float(numbers["factor"]),
        tuple(map(float, first_steps)),
        float(smallest_step),
        int(max_rounds),
    )


#: Histograms of more (their region, our region) cells than this are counted by NumPy (whose
#: bincount needs as many): the C kernel would hold them all at once, one per segmentation.
LARGEST_HISTOGRAM = 1 << 22


def correspondences_compiled(labels, others):
    """:func:`~ursim_core.matching.resampling.region_correspondences` in one pass over the pixels
    (:file:`csrc/correspondences.c`): the same dicts, or None without the C module, for arrays
    that are not int32 of one size, or for histograms over :data:`LARGEST_HISTOGRAM` cells."""
    module = kernel()
    if module is None:
        return None
    labels = np.asarray(labels)
    others = [np.asarray(other) for other in others]
    if labels.dtype != np.int32 or any(other.dtype != np.int32 or other.shape != labels.shape for other in others):
        return None
    return module.region_correspondences(
        np.ascontiguousarray(labels), [np.ascontiguousarray(other) for other in others], LARGEST_HISTOGRAM
    )
