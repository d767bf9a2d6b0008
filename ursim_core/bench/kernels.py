"""Compilation of the segmentation kernels on an empty cache, as a fresh install pays it.

``bench_compile()`` runs :func:`ursim_core.segmentation.maoris.compile_kernels` in a new
process whose numba cache (``NUMBA_CACHE_DIR``) is an empty temporary folder, and prints
the seconds: wall clock (what the user waits) and CPU (less sensitive to a busy machine).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

__all__ = ["bench_compile"]

_CHILD = """
import json, resource, time
start = time.perf_counter()
from ursim_core.segmentation.maoris import compile_kernels, kernels_cached
seconds = compile_kernels({processes})
own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({{"compile_s": seconds, "process_s": time.perf_counter() - start,
    "cpu_s": own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime, "cached": kernels_cached()}}))
"""


def bench_compile(*, processes: int | None = None, repeats: int = 1) -> list[dict[str, float]]:
    """Compile the kernels into an empty cache in a subprocess; print and return the figures.

    Parameters
    ----------
    processes : int, optional
        Passed to ``compile_kernels`` (default: its default, one process).
    repeats : int
        Runs, each on a new empty cache.

    Returns
    -------
    list of dict
        Per run: ``compile_s`` (inside compile_kernels), ``process_s`` (the whole process
        less the interpreter's start), ``cpu_s`` (user + system, with the helper processes)
        and ``cached`` (``kernels_cached()`` afterwards).
    """
    rows = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="ursim-numba-cache-") as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            code = _CHILD.format(processes="" if processes is None else f"processes={int(processes)}")
            result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            row = json.loads(result.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(
            f"kernel compilation on an empty cache: {row['compile_s']:.1f} s "
            f"(process {row['process_s']:.1f} s, CPU {row['cpu_s']:.1f} s, "
            f"processes={1 if processes is None else processes}, cached after: {row['cached']})"
        )
    return rows
