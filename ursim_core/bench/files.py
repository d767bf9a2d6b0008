"""Speed of the correspondence files at scale: save and load of 1k, 10k and 100k cliques.

The target of issue 12 is at most 2 s each way for 100k cliques. Figures are wall-clock
medians and the process CPU time of the same runs (on a shared machine the CPU time says
what the code costs, the wall time what a user waits), plus a 100k-clique ``.dat`` file.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

__all__ = ["bench_files", "make_correspondences"]


def make_correspondences(n_cliques: int):
    """A Correspondences of ``n_cliques`` cliques shaped like real annotations (1-2 points a side)."""
    from ursim_core.correspondences.values import Clique, Correspondences, MapRef

    cliques = tuple(
        Clique(
            id=index + 1,
            sketch_points=[(index % 500, index % 300), (7, 9)] if index % 4 == 0 else [(index % 500, index % 300)],
            metric_points=[(index % 400, 5)],
            sketch_regions=[1 + index % 40],
            metric_regions=[1 + index % 30],
            source="auto" if index % 2 else "manual",
            score=None if index % 2 == 0 else 0.5 + index / max(n_cliques, 1),
            note="checked" if index % 10 == 0 else "",
        )
        for index in range(n_cliques)
    )
    return Correspondences(
        MapRef(path="sketch.png", size=(500, 300), segmentation_method="maoris"),
        MapRef(path="model.png", size=(400, 400), segmentation_method="maoris"),
        cliques=cliques,
        annotator="bench",
    )


def _timed(action: Callable[[], object], repeats: int) -> tuple[float, float]:
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        action()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)


def bench_files(sizes: tuple[int, ...] = (1_000, 10_000, 100_000), *, repeats: int = 3) -> list[dict]:
    """Time save and load of correspondence files of ``sizes`` cliques; print and return the rows.

    Examples
    --------
    >>> rows = bench_files((10,), repeats=1)  # doctest: +ELLIPSIS
    format  cliques ...
    >>> rows[0]["cliques"]
    10
    """
    from ursim_core.correspondences.dat_codec import load_dat, save_dat
    from ursim_core.correspondences.json_codec import load_correspondences, save_correspondences

    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for size in sizes:
            corr = make_correspondences(size)
            for kind, save, load in (
                ("json", lambda c, p: save_correspondences(c, p, now="2024-01-01T00:00:00Z"), load_correspondences),
                ("dat", save_dat, load_dat),
            ):
                target = Path(folder) / f"bench.{kind}"
                save_wall, save_cpu = _timed(lambda: save(corr, target), repeats)
                load_wall, load_cpu = _timed(lambda: load(target), repeats)
                back = load(target)
                if [c.sketch_points for c in back.cliques] != [c.sketch_points for c in corr.cliques]:
                    raise AssertionError(f"{kind} file of {size} cliques did not read back its points")
                rows.append(
                    {
                        "format": kind,
                        "cliques": size,
                        "MB": target.stat().st_size / 1e6,
                        "save_s": save_wall,
                        "save_cpu_s": save_cpu,
                        "load_s": load_wall,
                        "load_cpu_s": load_cpu,
                    }
                )
    print(f"{'format':<7} {'cliques':>8} {'MB':>6} {'save s':>8} {'(cpu)':>7} {'load s':>8} {'(cpu)':>7}")
    for row in rows:
        print(
            f"{row['format']:<7} {row['cliques']:>8} {row['MB']:>6.1f} {row['save_s']:>8.2f} "
            f"{row['save_cpu_s']:>7.2f} {row['load_s']:>8.2f} {row['load_cpu_s']:>7.2f}"
        )
    return rows
