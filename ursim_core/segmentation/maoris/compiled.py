"""The MAORIS kernels as the steps call them: the C module when it is built, else numba's JIT.

:func:`kernels` gives one namespace with every kernel called from Python (the names of
:data:`ENTRY_KERNELS`). It is the extension module ``_maoris_kernels`` that :func:`build_ahead`
compiled from the C sources of :file:`csrc` (``make`` builds it; :mod:`.c_build`), when it was
built from the sources of this install: it loads in milliseconds and needs no numba. When
there is none, the first call builds it (seconds, once); when that fails (no C compiler),
numba's JIT dispatchers of :mod:`.kernels`, which import numba and load (or compile) their
cache. The C kernels are a port of the numba ones, which stay the reference: the tests check
that both give the same label images.

``URSIM_KERNELS`` chooses: ``auto`` (default), ``jit`` (always the JIT) or ``ahead`` (the
built module, or a :class:`~ursim_core.errors.SegmentationError` saying how to build it).
This module imports neither numba nor the kernels.

Why C: numba's JIT costs every new process about a second before the first segmentation
(importing numba, loading each kernel's cached machine code), and building the same kernels
ahead of time with numba's ``pycc`` (deprecated by numba) took 16.6 s of a fresh install on
two CPUs, most of it numba typing and lowering in Python. The C compiler builds the port in a
few seconds (``ursim bench compile``). Every kernel releases the GIL: the contacts of large
maps are counted in bands on threads, and the C kernels of the image-wide passes (the distance
transform, disc centres and painting, flat zones, relabelling, the value lookup, first pixels)
split large images into bands of rows (or parts), one thread each, with the results of one pass.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys
import time
import warnings
from pathlib import Path
from types import SimpleNamespace

from ursim_core.errors import SegmentationError

__all__ = [
    "ENTRY_KERNELS",
    "MODULE_NAME",
    "DIGEST_NAME",
    "kernels",
    "ahead_module_path",
    "build_directories",
    "sources_digest",
    "build_ahead",
    "build_or_warn",
    "forget",
]

#: The kernels called from Python, by module of :mod:`.kernels` (the helpers they call are
#: compiled into them). A test checks this against :data:`.kernels.signatures.SIGNATURES`.
ENTRY_KERNELS: dict[str, tuple[str, ...]] = {
    "distance": ("distance_transform",),
    "discs": ("centre_rectangles", "paint_discs", "lookup_bytes"),
    "flat_zones": (
        "label_flat_zones",
        "label_radii_zones_counted",
        "zone_values_and_sizes",
        "first_pixels",
        "resolve_parents",
        "relabel",
    ),
    "adjacency": (
        "build_adjacency",
        "adjacency_entries",
        "_link_entries",
        "remove_small_zones",
        "compact_graph",
        "expand_graph",
    ),
    "contacts": ("_compact_labels", "count_contacts", "join_counts", "group_candidates", "contact_table"),
    "fusion": ("merge_ripples", "remove_doors"),
    "flooding": ("flood_levels", "clearance_levels"),
}

MODULE_NAME = "_maoris_kernels"
"""Name of the extension module built from :file:`csrc` (:func:`ahead_module_path` gives its path)."""
DIGEST_NAME = "_maoris_kernels.digest"
"""The file beside it that names the sources it was built from (:func:`sources_digest`)."""

_KERNELS_DIR = Path(__file__).resolve().parent / "kernels"
_loaded: SimpleNamespace | None = None


def _native():
    """The module as a :class:`~ursim_core.native.NativeModule`: its sources, how they are built
    (:mod:`.c_build`, in the digest), where the build lives."""
    from ursim_core.native import NativeModule
    from ursim_core.segmentation.maoris.c_build import SOURCE_DIR

    return NativeModule(MODULE_NAME, SOURCE_DIR, digest_extra=(_KERNELS_DIR.parent / "c_build.py",), numpy=True)


def sources_digest() -> str:
    """SHA-256 of the C sources (:file:`csrc`), of how they are built (:mod:`.c_build`,
    :mod:`ursim_core.native`) and of the Python ABI.

    The built module is used only while this matches the digest it was built with: an edited
    source is built again on the next :func:`kernels`.
    """
    return _native().digest()


def build_directories() -> list[Path]:
    """Where the built module may live, in the order looked at: beside the sources (a checkout
    or a writable install), then the user's cache (``$XDG_CACHE_HOME/ursim``)."""
    return _native().directories()


def ahead_module_path() -> Path | None:
    """The built module (:data:`MODULE_NAME`) of these kernel sources, or None when it is
    missing or stale."""
    return _native().built_path(build_directories(), sources_digest)


def _load_ahead(path: Path) -> SimpleNamespace:
    """Every kernel, from the module at ``path`` (:func:`ahead_module_path`)."""
    spec = importlib.util.spec_from_file_location(MODULE_NAME, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    # A kernel missing (a module of other sources) is an AttributeError: the module is broken.
    found = {kernel: getattr(module, kernel) for names in ENTRY_KERNELS.values() for kernel in names}
    return SimpleNamespace(source="ahead", path=path, **found)


def _load_jit() -> SimpleNamespace:
    import importlib

    from ursim_core.segmentation.maoris.kernels import signatures

    found = {}
    for module_name, names in ENTRY_KERNELS.items():
        module = importlib.import_module(f"ursim_core.segmentation.maoris.kernels.{module_name}")
        for name in names:
            key = (module_name, name)
            # Kernels that take an array of any layout are held to their declared signature
            # (signatures.takes_any_layout): the others' arrays are C-contiguous, as declared.
            found[name] = signatures.declared_only(key) if signatures.takes_any_layout(key) else getattr(module, name)
    return SimpleNamespace(source="jit", path=None, **found)


def kernels() -> SimpleNamespace:
    """Every kernel called from Python, and ``source`` ("ahead" or "jit"); loaded once.

    Examples
    --------
    >>> kernels().source in ("ahead", "jit")
    True
    """
    global _loaded
    if _loaded is None:
        choice = os.environ.get("URSIM_KERNELS", "auto").strip().lower() or "auto"
        if choice not in ("auto", "jit", "ahead"):
            raise SegmentationError(f"URSIM_KERNELS must be auto, jit or ahead, not {choice!r}")
        path = None if choice == "jit" else ahead_module_path()
        if choice == "auto" and path is None:
            path = build_or_warn()  # once per install: as long as the JIT's first compile
        if choice == "ahead" and path is None:
            raise SegmentationError(
                "URSIM_KERNELS=ahead but the kernels are not built for these sources: run "
                f"`{Path(sys.executable).name} -m ursim_core.segmentation.maoris.compiled`"
            )
        _loaded = _load_ahead_or_warn(path, choice) if path is not None else None
        if _loaded is None:
            _loaded = _load_jit()
    return _loaded


def _load_ahead_or_warn(path: Path, choice: str) -> SimpleNamespace | None:
    """The built module at ``path``; a broken one (truncated, foreign, missing a kernel) is
    reported, and then built again (``auto``), refused (``ahead``) or left for the JIT."""
    try:
        return _load_ahead(path)
    except (ImportError, OSError, AttributeError) as error:
        problem = f"the segmentation kernels built at {path} cannot be loaded ({type(error).__name__}: {error})"
    if choice == "ahead":
        raise SegmentationError(problem)
    warnings.warn(f"{problem}; building them again", RuntimeWarning, stacklevel=3)
    rebuilt = build_or_warn()
    if rebuilt is None:
        return None
    try:
        return _load_ahead(rebuilt)
    except (ImportError, OSError, AttributeError):
        return None


def build_or_warn() -> Path | None:
    """Build the kernels ahead of time; on failure warn, and return None (the JIT is used)."""
    try:
        return build_ahead()
    except Exception as error:
        warnings.warn(
            f"could not build the segmentation kernels ahead of time ({type(error).__name__}: {error}); "
            "using numba's JIT, which starts about a second slower",
            RuntimeWarning,
            stacklevel=2,
        )
        return None


def forget() -> None:
    """Load again on the next :func:`kernels` (after a build, or to switch ``URSIM_KERNELS``)."""
    global _loaded
    _loaded = None


def build_ahead(directory: str | Path | None = None) -> Path:
    """Compile the kernels in C into the module loaded here; return its path.

    The module and its digest file are written to ``directory`` (default: the first writable
    of :func:`build_directories`) by :meth:`ursim_core.native.NativeModule.build`: the old digest
    is removed first, then the module and the new digest are put in place by a rename, so a
    reader never sees a digest without its module. ``ursim bench compile`` measures how long it
    takes.

    Raises
    ------
    RuntimeError
        When there is no C compiler or it fails (with the end of its messages).
    """
    target = Path(directory) if directory is not None else build_directories()[0]
    path = _native().build(target, digest=sources_digest())
    forget()
    return path


def _main() -> None:  # ``python -m ursim_core.segmentation.maoris.compiled``
    started = time.perf_counter()
    path = build_ahead()
    print(f"{path} ({time.perf_counter() - started:.1f} s)")


if __name__ == "__main__":
    _main()
