"""Whole-process ``ursim match`` of generated buildings of growing size (``ursim bench scale``).

At each size two different buildings (seeds 0 and 1 of :func:`~ursim_core.synth.make_large_building`)
are written as PNGs and matched by a fresh ``python -m ursim_core.cli match`` process, as a user
runs it: loading, both segmentations, the region graphs, the
orientation search, the automatic m, the figure and the files. Wall time, CPU time (user +
system) and peak resident memory are those of that child process and of any process it starts
(``os.wait4`` in a small intermediate process, which also sums the resident sizes of the process
tree: issue 14's memory bar is on that sum; ``ursim match`` starts none since its automatic m's
sweep runs on two threads of the matcher's C loop instead of a helper process).

Two different maps, not one file twice: a map against itself is the easy case (every region has
an identical twin, so few seeds expand) and any cache of identical inputs would flatter it. Until
round 7 this benchmark matched each building against itself: 54 s at 8000 px then, while two
different buildings took 220 s.

Issue 14 targets: two 8000 x 8000 maps in 30 s and 3 GB; time growth per doubling of the side
(4x the pixels) at most 4.5x.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ursim_core.bench.segmentation import add_growth
from ursim_core.synth import make_large_building

__all__ = ["bench_match_process"]


# Run by a fresh interpreter between the benchmark and the measured process: on Linux a child's
# peak RSS starts at its parent's resident size at fork time, and the benchmark's own process
# is large after the in-process segmentations; this small one is not. ``ru_maxrss`` is the peak
# of the largest single process of the tree; the resident sizes of every process of the tree are
# also summed every 20 ms (Linux /proc; shared pages count in each process, so the
# sum can only overstate) and the peak of that sum is reported too.
_MEASURE = """
import json, os, subprocess, sys, time

def tree(pid):
    pids = [pid]
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as f:
                for child in map(int, f.read().split()):
                    pids += tree(child)
    except OSError:
        pass
    return pids

def resident(pid):
    try:
        with open(f"/proc/{pid}/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0

started = time.perf_counter()
child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)
tree_peak = 0
while True:
    pid, status, usage = os.wait4(child.pid, os.WNOHANG)
    if pid:
        break
    tree_peak = max(tree_peak, sum(resident(p) for p in tree(child.pid)))
    time.sleep(0.02)
print(json.dumps({"wall": time.perf_counter() - started, "cpu": usage.ru_utime + usage.ru_stime,
                  "rss_kb": usage.ru_maxrss, "tree_kb": tree_peak // 1024, "code": os.waitstatus_to_exitcode(status)}))
"""


def _run(command: list[str]) -> tuple[float, float, float, float, int]:
    """Wall s, CPU s (user + system), peak RSS MB (largest process; summed over the process tree)
    and exit code of one child process."""
    done = subprocess.run([sys.executable, "-c", _MEASURE, *command], capture_output=True, text=True)
    if done.returncode != 0:
        sys.stderr.write(done.stderr)
        return 0.0, 0.0, 0.0, 0.0, done.returncode
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    if figures["code"] != 0:
        sys.stderr.write(done.stderr)
    # The samples can miss a short peak of one process that wait4 saw: the sum is at least that.
    tree = max(figures["tree_kb"], figures["rss_kb"]) / 1024
    return figures["wall"], figures["cpu"], figures["rss_kb"] / 1024, tree, figures["code"]


#: Seeds of the two buildings matched at every size (sketch, metric).
SEEDS = (0, 1)


def bench_match_process(sizes: Iterable[int] = (1000, 2000, 4000, 8000)) -> list[dict]:
    """Time and peak memory of ``ursim match`` of two different generated buildings.

    Returns
    -------
    list of dict
        ``size``, ``wall_s``, ``cpu_s`` (of the child and any process it starts), ``maxrss_mb`` (the peak
        resident size of its largest process), ``tree_rss_mb`` (the peak of the resident sizes of
        all its processes summed, sampled every 20 ms) and,
        from the second size on, ``time_ratio`` (wall time over the previous size's) and
        ``pixel_ratio``. A failed run has ``error`` (its exit code) instead of figures.
    """
    import cv2

    rows: list[dict] = []
    previous: tuple[int, float] | None = None
    with tempfile.TemporaryDirectory(prefix="ursim-bench-scale-") as folder:
        for size in sizes:
            size = int(size)
            images = [Path(folder) / f"building-{size}-{seed}.png" for seed in SEEDS]
            for image, seed in zip(images, SEEDS):
                cv2.imwrite(str(image), make_large_building(size, seed=seed).free.astype(np.uint8) * 255)
            out = Path(folder) / f"match-{size}"
            command = [sys.executable, "-m", "ursim_core.cli", "match", *map(str, images), "-o", str(out)]
            wall, cpu, rss, tree_rss, code = _run(command)
            row: dict = {"size": size, "pixels": size * size}
            if code != 0:
                row["error"] = f"exit {code}"
                rows.append(row)
                continue
            row.update(
                wall_s=round(wall, 2), cpu_s=round(cpu, 2), maxrss_mb=round(rss, 1), tree_rss_mb=round(tree_rss, 1)
            )
            previous = add_growth(row, previous, wall)
            rows.append(row)
    return rows
