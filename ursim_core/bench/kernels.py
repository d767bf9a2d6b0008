"""First-run preparation of the segmentation and matching kernels, as a fresh install pays it.

``bench_compile()`` prepares the MAORIS kernels in a new process on empty caches, both ways
:mod:`ursim_core.segmentation.maoris.compiled` knows: compiling the C kernels (the default,
into an empty temporary folder; the C compiler runs once per source file, as many at once as
there are CPUs) and numba's JIT (``URSIM_KERNELS=jit``, into an empty ``NUMBA_CACHE_DIR``). It
prints the seconds: wall clock (what the user waits) and CPU (less sensitive to a busy
machine; it counts the compiler processes), and the kernels' load time in a later process
(what every later command pays before its first segmentation). It also builds the matcher's C
module (:mod:`ursim_core.matching.kernels`, one source file) into an empty folder.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

__all__ = ["bench_compile"]

_BUILD = """
import json, resource, time
start = time.perf_counter()
from ursim_core.segmentation.maoris.compiled import build_ahead
build_ahead({folder!r})
own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({{"process_s": time.perf_counter() - start,
    "cpu_s": own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime}}))
"""
_JIT = """
import json, resource, time
start = time.perf_counter()
from ursim_core.segmentation.maoris import compile_kernels
compile_kernels(jit=True, processes={processes})
own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({{"process_s": time.perf_counter() - start,
    "cpu_s": own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime}}))
"""
_MATCHING = """
import json, resource, time
start = time.perf_counter()
from ursim_core.matching.kernels import MODULE
MODULE.build({folder!r})
own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({{"process_s": time.perf_counter() - start,
    "cpu_s": own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime}}))
"""
# A later process: load the kernels and run one small segmentation (what a command pays).
_LOAD = """
import json, time
start = time.perf_counter()
import numpy as np
from ursim_core.segmentation.maoris import maoris_labels
from ursim_core.segmentation.maoris.compiled import kernels
free = np.zeros((40, 40), bool); free[2:38, 2:38] = True
maoris_labels(free)
print(json.dumps({"load_s": time.perf_counter() - start, "source": kernels().source}))
"""


def _child(code: str, env: dict[str, str]) -> dict:
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(result.stdout.strip().splitlines()[-1])


def bench_compile(*, processes: int = 1, repeats: int = 1) -> list[dict]:
    """Prepare the kernels on empty caches in subprocesses, both ways; print and return the figures.

    Parameters
    ----------
    processes : int
        Processes of the JIT compile (``compile_kernels(processes=...)``).
    repeats : int
        Runs of each way, each on new empty caches.

    Returns
    -------
    list of dict
        Per run: ``way`` ("ahead", "jit" or "matching": the matcher's C module), ``process_s`` (the preparing process less the
        interpreter's start), ``cpu_s`` (user + system, with its helper processes) and, for the
        MAORIS kernels, ``load_s`` (a later process: import, load the kernels, segment a 40 x 40 map).
    """
    from ursim_core.segmentation.maoris import compile_kernels

    # The later processes load the install's own build: made first if the sources changed.
    compile_kernels()
    rows = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="ursim-kernels-bench-") as scratch:
            folder, numba_cache, xdg = (os.path.join(scratch, name) for name in ("ahead", "numba", "xdg"))
            base = {**os.environ, "NUMBA_CACHE_DIR": numba_cache, "XDG_CACHE_HOME": xdg}
            row = {"way": "ahead", **_child(_BUILD.format(folder=folder), base)}
            # A later process loads the install's own build (the same machine code as this one).
            row["load_s"] = _child(_LOAD, {**os.environ, "URSIM_KERNELS": "ahead"})["load_s"]
            rows.append(row)
            jit = {"way": "jit", **_child(_JIT.format(processes=int(processes)), {**base, "URSIM_KERNELS": "jit"})}
            jit["load_s"] = _child(_LOAD, {**base, "URSIM_KERNELS": "jit"})["load_s"]
            rows.append(jit)
            matching = os.path.join(scratch, "matching")
            rows.append({"way": "matching", **_child(_MATCHING.format(folder=matching), base)})
    for row in rows:
        if row["way"] == "matching":
            print(f"matching kernels (C) on an empty folder: {row['process_s']:.1f} s (CPU {row['cpu_s']:.1f} s)")
            continue
        load = f"{row['load_s']:.2f} s"
        print(
            f"kernels {row['way']:>5} on empty caches: {row['process_s']:.1f} s (CPU {row['cpu_s']:.1f} s); "
            f"a later process loads them and segments a small map in {load}"
        )
    return rows
