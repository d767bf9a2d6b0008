"""Whether this install's MAORIS kernels are compiled on disk, without importing numba.

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

__all__ = ["kernels_cached", "compile_notice", "ENTRY_KERNELS", "COMPILE_CPU_SECONDS"]

_KERNELS_DIR = Path(__file__).resolve().parent / "kernels"

#: The kernels called from Python, by module of :mod:`ursim_core.segmentation.maoris.kernels`
#: (the helpers they call are compiled into them). A test checks this against the modules.
ENTRY_KERNELS: dict[str, tuple[str, ...]] = {
    "discs": ("centre_rectangles", "paint_discs"),
    "flat_zones": ("label_flat_zones", "zone_values_and_sizes", "first_pixels", "resolve_parents", "relabel"),
    "adjacency": ("build_adjacency", "adjacency_entries", "_link_entries", "remove_small_zones"),
    "contacts": ("_compact_labels", "count_contacts", "join_counts", "contact_table"),
    "fusion": ("merge_ripples", "remove_doors"),
}


#: Seconds of CPU that compiling every kernel on an empty cache took on the 2-CPU machine
#: of the project (``ursim bench compile``: 27-34 s); the wait :func:`compile_notice` gives.
COMPILE_CPU_SECONDS = 30


def compile_notice() -> str | None:
    """The line to show before a segmentation that will first compile the kernels, else None.

    Examples
    --------
    >>> compile_notice() is None or compile_notice().startswith("Compiling")
    True
    """
    if kernels_cached():
        return None
    return f"Compiling the segmentation kernels (first run only, about {COMPILE_CPU_SECONDS} s)..."


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
    """True when every MAORIS kernel of this install is compiled in numba's cache.

    Cheap (a few directory listings; imports neither numba nor the kernels). A cache
    older than its source, as numba would reject, counts as missing.

    Examples
    --------
    >>> isinstance(kernels_cached(), bool)
    True
    """
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
