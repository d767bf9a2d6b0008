"""Benchmarks of the MAORIS segmentation (hooked into ``ursim bench segment``).

Each function returns a list of rows (dicts) and :func:`print_table` prints
them. Timings are medians of several runs; wall time and process CPU time are
both given because the machines are shared (CPU time is less sensitive to
other processes).

* :func:`bench_segmentation`: the largest KTH sketch and the largest robot map
  of the research datasets (targets: 0.5 s and 1 s), those sketches turned by 30 degrees
  and segmented as ``ursim match`` and the app segment them (in their canonical pose and
  the other resamplings the planar matcher votes over), and the learned segmenter on
  the KTH sketches (target: 2 s).
* :func:`bench_scale`: synthetic buildings of growing size (target: 4000 x 4000
  in 5 s), with peak memory.
* :func:`bench_quality`: precision/recall/F1 of presets on the MAORIS
  segmentation ground truth, with the authors' own label images for reference.

Examples
--------
>>> rows = bench_scale(sizes=(200,), repeats=1)
>>> rows[0]["size"], rows[0]["regions"] > 1
(200, True)
"""

from __future__ import annotations

import gc
import resource
import statistics
import time
import tracemalloc
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import numpy as np

from ursim_core.segmentation.maoris import PRESETS, MaorisParams, maoris_labels
from ursim_core.synth import make_large_building

__all__ = [
    "bench_segmentation",
    "bench_scale",
    "bench_quality",
    "print_table",
]

# The largest sketch (pixels) of ursim_kth_sketches and the largest robot map of
# maoris_segmentation, as (dataset-relative path, free-space rule, preset).
_BENCH_MAPS = (
    ("ursim_kth_sketches/sketches/20.png", "threshold", "sketch"),
    ("ursim_kth_sketches/sketches/24.png", "threshold", "sketch"),
    ("maoris_segmentation/robot_maps/maps/Freiburg101_scan.png", "threshold", "robot"),
    ("maoris_segmentation/robot_maps/maps/office_a.png", "threshold", "robot"),
)


def _time(function: Callable[[], object], repeats: int) -> tuple[float, float, object]:
    walls, cpus, result = _times(function, repeats)
    return statistics.median(walls), statistics.median(cpus), result


def _times(function: Callable[[], object], repeats: int) -> tuple[list[float], list[float], object]:
    """Wall and CPU seconds of each of ``repeats`` runs of ``function``, and its last result."""
    walls, cpus, result = [], [], None
    for _ in range(max(1, repeats)):
        # The last run's output goes first: a run is timed with only its own memory, as a
        # program that segments one map is (kept, it held 256 MB of labels at 8000 x 8000 px
        # through the next run, whose memory then came fresh from the host).
        result = None
        gc.collect()
        wall, cpu = time.perf_counter(), time.process_time()
        result = function()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return walls, cpus, result


def _timed_row(name: str, free: np.ndarray, preset: str, segmenter: Callable[[], np.ndarray], repeats: int) -> dict:
    """One row of :func:`bench_segmentation`: the median time of ``segmenter()`` on ``free``."""
    wall, cpu, labels = _time(segmenter, repeats)
    return {
        "map": name,
        "shape": f"{free.shape[0]}x{free.shape[1]}",
        "preset": preset,
        "regions": int(labels.max()),
        "wall_s": round(wall, 3),
        "cpu_s": round(cpu, 3),
    }


def bench_segmentation(dataset_root: Path | None, *, repeats: int = 5) -> list[dict]:
    """Median time to segment the largest sketch and the largest robot map.

    Parameters
    ----------
    dataset_root : Path or None
        The shared datasets folder (``ursim_core.evaluation.datasets.dataset_root()``);
        None gives no rows.
    repeats : int, keyword-only
        Runs per map; the median is reported.

    Returns
    -------
    list of dict
        ``map``, ``shape``, ``preset``, ``regions``, ``wall_s``, ``cpu_s``.
    """
    from ursim_core.io.maps import load_map

    rows: list[dict] = []
    if dataset_root is None:
        return rows
    for relative, _, preset in _BENCH_MAPS:
        path = Path(dataset_root) / relative
        if not path.exists():
            continue
        free = load_map(path).free
        rows.append(_timed_row(relative, free, preset, lambda: maoris_labels(free, PRESETS[preset]), repeats))
    rows.extend(_turned_rows(Path(dataset_root), repeats))
    rows.extend(_learned_rows(Path(dataset_root), repeats))
    rows.extend(_watershed_rows(Path(dataset_root), repeats))
    return rows


def _watershed_rows(dataset_root: Path, repeats: int, *, building: int = 4000) -> list[dict]:
    """The watershed segmenter (:mod:`ursim_core.segmentation.watershed`, the robot-map
    default) on the robot maps of :data:`_BENCH_MAPS` and a generated building of
    ``building`` px a side (target: 4000 px <= 5 s); at most 3 runs of the building."""
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation.watershed import watershed_labels
    from ursim_core.synth import make_large_building

    maps = []
    for relative, _, preset in _BENCH_MAPS:
        path = dataset_root / relative
        if preset != "sketch" and path.exists():
            maps.append((relative, load_map(path).free, repeats))
    if building:
        maps.append((f"generated building {building} px", make_large_building(building, seed=1).free, min(repeats, 3)))
    return [_timed_row(name, free, "watershed", lambda: watershed_labels(free), runs) for name, free, runs in maps]


def _turned_rows(dataset_root: Path, repeats: int, *, degrees: float = 30.0) -> list[dict]:
    """The KTH sketches of :data:`_BENCH_MAPS` turned by ``degrees`` on a canvas that holds them
    and segmented as a sketch is matched: ``segment_canonical(..., resampled=True)``, the
    canonical pose and its other resamplings (six segmentations); ``regions`` is the first's."""
    from ursim_core.evaluation.augment import Orientation, transform_image
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import canonical, segment_canonical

    rows = []
    for relative, _, preset in _BENCH_MAPS:
        path = dataset_root / relative
        if preset != "sketch" or not path.exists():
            continue
        free = transform_image(load_map(path).free, Orientation(degrees))

        def resampled(free=free):
            canonical._voted_angle.cache_clear()  # the wall angle is remembered by content: timed as new
            return segment_canonical(free, preset="default", resampled=True).labels

        rows.append(_timed_row(f"{relative} turned {degrees:g} deg", free, "default x6", resampled, repeats))
    return rows


def _learned_rows(dataset_root: Path, repeats: int) -> list[dict]:
    """The learned segmenter (:mod:`ursim_core.segmentation.learned`) on the KTH sketches of
    :data:`_BENCH_MAPS` (target: <= 2 s each); at most 3 runs, it is the slow one."""
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation.learned.merging import learned_labels

    rows = []
    for relative, _, preset in _BENCH_MAPS:
        path = dataset_root / relative
        if preset != "sketch" or not path.exists():
            continue
        free = load_map(path).free
        rows.append(_timed_row(relative, free, "learned", lambda: learned_labels(free), min(repeats, 3)))
    return rows


def bench_scale(sizes: Iterable[int] = (1000, 2000, 4000), *, repeats: int = 1, preset: str = "robot") -> list[dict]:
    """Time and peak memory of segmenting generated buildings of growing size.

    The buildings come from :func:`ursim_core.synth.make_large_building` (bands of rooms along
    corridors; about a thousand rooms at 4000 x 4000).

    Returns
    -------
    list of dict
        ``size``, ``pixels``, ``regions``, ``wall_s`` and ``cpu_s`` (medians of ``repeats``
        runs), ``wall_range_s`` (the fastest and slowest run), ``peak_traced_mb`` (tracemalloc:
        numpy and Python allocations), ``maxrss_mb`` (process peak resident size so far; it only
        grows), ``time_ratio`` (median wall time over the previous size's) and ``pixel_ratio``.
    """
    rows: list[dict] = []
    previous: tuple[int, float] | None = None
    for size in sizes:
        free = make_large_building(int(size)).free
        walls, cpus, labels = _times(lambda: maoris_labels(free, PRESETS[preset]), repeats)
        regions = int(labels.max())
        del labels  # nor is it held through the next runs (see _times)
        wall, cpu = statistics.median(walls), statistics.median(cpus)
        gc.collect()
        tracemalloc.start()
        maoris_labels(free, PRESETS[preset])
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        row = {
            "size": int(size),
            "pixels": int(size) ** 2,
            "regions": regions,
            "wall_s": round(wall, 3),
            # The spread of the runs: on a shared machine one run's growth ratio varies by +-20 %.
            "wall_range_s": f"{min(walls):.3f}-{max(walls):.3f}",
            "cpu_s": round(cpu, 3),
            "peak_traced_mb": round(peak / 2**20, 1),
            "maxrss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        }
        previous = add_growth(row, previous, wall)
        rows.append(row)
    return rows


def add_growth(row: dict, previous: tuple[int, float] | None, wall: float) -> tuple[int, float]:
    """Add ``pixel_ratio`` and ``time_ratio`` against the previous size's ``(pixels, wall)``
    to ``row`` (none for the first); return this size's ``(pixels, wall)``."""
    if previous is not None:
        row["pixel_ratio"] = round(row["pixels"] / previous[0], 2)
        row["time_ratio"] = round(wall / previous[1], 2) if previous[1] > 0 else None
    return (row["pixels"], wall)


def bench_quality(
    dataset_root: Path | None,
    *,
    presets: Mapping[str, MaorisParams] | None = None,
    maps: str = "sketches",
) -> list[dict]:
    """Segmentation quality of presets on ``maoris_segmentation``.

    Parameters
    ----------
    dataset_root : Path or None
        None gives no rows.
    presets : mapping of name to MaorisParams, keyword-only
        Default: every entry of :data:`~ursim_core.segmentation.maoris.PRESETS`.
    maps : {"sketches", "robot_maps"}, keyword-only
        Sketches are scored against ``gt_lex`` and ``gt_ezvin`` and the
        authors' label images (``maoris_output``) are scored too, as
        "authors"; robot maps against ``gt``.

    Returns
    -------
    list of dict
        ``method``, ``gt``, ``maps`` (count), mean ``precision``, ``recall``,
        ``f1``, ``evaluator_f1`` over the maps.
    """
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation.scoring import (
        gt_labels_from_separator_image,
        load_label_array,
        score_segmentation,
    )

    if dataset_root is None:
        return []
    root = Path(dataset_root) / "maoris_segmentation" / maps
    gt_folders = ("gt_lex", "gt_ezvin") if maps == "sketches" else ("gt",)
    presets = dict(PRESETS if presets is None else presets)
    scores: dict[tuple[str, str], list] = {}
    for map_path in sorted((root / "maps").glob("*.png")):
        predictions = {}
        if maps == "sketches":
            predictions["authors"] = load_label_array(root / "maoris_output" / map_path.name)
        free = load_map(map_path).free
        for name, params in presets.items():
            predictions[name] = maoris_labels(free, params)
        for gt_folder in gt_folders:
            gt = gt_labels_from_separator_image(root / gt_folder / map_path.name)
            for name, labels in predictions.items():
                scores.setdefault((name, gt_folder), []).append(score_segmentation(labels, gt))
    rows = []
    for (name, gt_folder), values in scores.items():
        rows.append(
            {
                "method": name,
                "gt": gt_folder,
                "maps": len(values),
                "precision": round(float(np.mean([s.precision for s in values])), 3),
                "recall": round(float(np.mean([s.recall for s in values])), 3),
                "f1": round(float(np.mean([s.f1 for s in values])), 3),
                "evaluator_f1": round(float(np.mean([s.evaluator_f1 for s in values])), 3),
            }
        )
    return rows


def print_table(rows: list[dict]) -> None:
    """Print rows as an aligned text table (columns = union of the keys).

    Examples
    --------
    >>> print_table([{"a": 1, "b": "x"}, {"a": 22}])
    a   b
    1   x
    22
    """
    if not rows:
        print("(no rows)")
        return
    columns: list[str] = []
    for row in rows:
        columns.extend(key for key in row if key not in columns)
    cells = [[str(row.get(column, "")) for column in columns] for row in rows]
    widths = [max(len(column), *(len(line[i]) for line in cells)) for i, column in enumerate(columns)]
    print("  ".join(column.ljust(width) for column, width in zip(columns, widths)).rstrip())
    for line in cells:
        print("  ".join(cell.ljust(width) for cell, width in zip(line, widths)).rstrip())


if __name__ == "__main__":  # pragma: no cover - manual run
    from ursim_core.evaluation.datasets import dataset_root

    print_table(bench_segmentation(dataset_root()))
    print_table(bench_scale())
