"""Whether this install's MAORIS kernels are compiled on disk, without importing numba.

By default the kernels come from the module compiled from their C sources
(:mod:`ursim_core.segmentation.maoris.compiled`): :func:`kernels_cached` is true when it is
built for these sources. With ``URSIM_KERNELS=jit`` it asks numba's cache instead:
numba compiles a ``cache=True`` function on its first call and writes it to a cache
directory (``NUMBA_CACHE_DIR`` if set, else ``__pycache__`` beside the module, else the
user's cache directory) as an index file ``<module>.<function>-<line>.pyXY.nbi`` plus data
files. :func:`kernels_cached` looks for the index of every kernel that Python code calls,
newer than its source: the CLI and the GUI call it to say "Compiling the segmentation
kernels..." before a first segmentation that will take seconds.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

from ursim_core.segmentation.maoris.compiled import ENTRY_KERNELS, ahead_module_path

__all__ = [
    "kernels_cached",
    "compile_notice",
    "ENTRY_KERNELS",
    "COMPILE_SECONDS",
    "COMPILE_CPU_SECONDS",
    "JIT_COMPILE_SECONDS",
]

_KERNELS_DIR = Path(__file__).resolve().parent / "kernels"

#: Seconds that compiling the C kernels on empty caches takes on the 2-CPU machine of the
#: project (one compiler per source file, two at once): 1.6 s with -O3 in round 13's
#: ``ursim bench compile`` (16.6 s for numba's pycc build it replaced); the wait
#: :func:`compile_notice` gives, rounded up for a busy machine.
COMPILE_SECONDS = 2
#: Seconds of CPU of that build (every compiler process): 1.7-2.3 s.
COMPILE_CPU_SECONDS = 3
#: Seconds of numba's JIT compiling every kernel on an empty cache (``URSIM_KERNELS=jit``, or
#: no C compiler; one process): 22.4-23.2 s in round 13's ``ursim bench compile``.
JIT_COMPILE_SECONDS = 23


def compile_notice() -> str | None:
    """The line to show before a segmentation that will first compile the kernels, else None.

    Examples
    --------
    >>> compile_notice() is None or compile_notice().startswith("Compiling")
    True
    """
    if kernels_cached():
        return None
    jit = os.environ.get("URSIM_KERNELS", "auto").strip().lower() == "jit"
    seconds = JIT_COMPILE_SECONDS if jit else COMPILE_SECONDS
    return f"Compiling the segmentation kernels (first run only, about {seconds} s)..."


def _cache_dirs(source: Path) -> list[Path]:
    """Where numba's locators would put the cache of ``source``, in their order."""
    folder = str(source.parent)
    subpath = f"{source.parent.name}_{hashlib.sha1(folder.encode()).hexdigest()}"
    user_dir = os.environ.get("NUMBA_CACHE_DIR")
    if user_dir:
        return [Path(user_dir) / subpath]
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return [source.parent / "__pycache__", Path(xdg) / "numba" / subpath]


def kernels_cached() -> bool:
    """True when the MAORIS kernels of this install are compiled: built ahead of time
    (:mod:`ursim_core.segmentation.maoris.compiled`) or, with ``URSIM_KERNELS=jit``, every
    one in numba's cache.

    Cheap (a few directory listings and reading the kernel sources; imports neither numba
    nor the kernels). A cache older than its source, as numba would reject, counts as missing.

    Examples
    --------
    >>> isinstance(kernels_cached(), bool)
    True
    """
    if os.environ.get("URSIM_KERNELS", "auto").strip().lower() != "jit":
        return ahead_module_path() is not None
    return jit_kernels_cached()


def jit_kernels_cached() -> bool:
    """True when every MAORIS kernel is compiled in numba's cache (``URSIM_KERNELS=jit``)."""
    tag = f".py{sys.version_info[0]}{sys.version_info[1]}{getattr(sys, 'abiflags', '')}.nbi"
    for module, names in ENTRY_KERNELS.items():
        source = _KERNELS_DIR / f"{module}.py"
        try:
            source_mtime = source.stat().st_mtime
        except OSError:
            return False
        for folder in _cache_dirs(source):
            try:
                indexes = {entry.name: entry for entry in os.scandir(folder) if entry.name.endswith(tag)}
            except OSError:
                continue
            fresh = {name.split("-", 1)[0] for name, entry in indexes.items() if entry.stat().st_mtime >= source_mtime}
            if all(f"{module}.{name}" in fresh for name in names):
                break
        else:
            return False
    return True
